// Plays a glTF/GLB file with three.js (headless, in Node) and prints the world-space position of
// every mesh vertex at the requested times, as one JSON document on stdout.
//
// Usage: node three_sample.mjs FILE.glb|FILE.gltf --times t1,t2,... [--clip NAME]...
//
//   --times   comma-separated clip times in seconds, in the file's own time base (three.js plays a
//             clip from t = 0, not from its first key: a clip whose keys start at 2 s holds its first
//             pose until 2 s). Times past the clip's duration wrap (the action loops, LoopRepeat).
//   --clip    a clip (glTF animation) by name; repeat the option or separate names with commas.
//             Default: every clip. A file without animations is sampled once per time in its rest
//             pose, as one entry whose name is null.
//
// Output: { file, nodes, skins, meshes, animations: [names], clips: [{ name, duration, times,
//   meshes: [{ name, node, mesh, primitive, skinned, vertex_count, positions: [[x,y,z,...] per time] }] }] }
// `node`, `mesh`, `primitive` are the glTF indices the three.js object was made from (three's
// GLTFParser.associations), so a caller can line vertices up with the file's POSITION accessors.
// A one-line summary goes to stderr. Exit 1 (message on stderr) when the file does not load,
// 2 on a bad command line or an unknown clip name.
//
// How positions are computed, per time:
//   mixer.setTime(t); scene.updateMatrixWorld(true);
//   for each Mesh / SkinnedMesh: mesh.getVertexPosition(i, v).applyMatrix4(mesh.matrixWorld)
// SkinnedMesh.getVertexPosition (three r151+) applies morph targets and then applyBoneTransform:
//   v' = bindMatrixInverse · Σ_k w_k · (bone_k.matrixWorld · boneInverse_k) · bindMatrix · v
// which is the skinned position in the mesh's *local* space, exactly what the skinning vertex
// shader produces before the model matrix. The renderer then multiplies by mesh.matrixWorld, so we
// do too. GLTFLoader binds every skinned mesh with bindMatrix = identity (GLTFParser.loadNode:
// mesh.bind(skeleton, _identityMatrix)), so world = mesh.matrixWorld · Σ w_k · joint_world_k · IBM_k · v.
// The glTF spec says a skinned mesh node's own world transform is ignored; three.js applies it.
// The two agree whenever that transform is the identity (frond's sample trees and the shared trees:
// untransformed root nodes, or children of an untransformed root; the Khronos validator warns about
// other cases). Bone matrices are read straight from bone.matrixWorld (no skeleton.update() needed).
//
// Textures: a GLTFLoader plugin answers every loadTexture with an empty Texture, so images are
// never decoded (no DOM, canvas or createImageBitmap needed in Node); geometry, skins and
// animation are unaffected. External and data: buffers are read with node:fs / Buffer, not
// three's FileLoader (whose fetch path needs DOM ProgressEvent). EXT_meshopt_compression is
// decoded with three's bundled decoder.

import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { AnimationMixer, SkinnedMesh, Texture, Vector3 } from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';

function usage(message) {
  process.stderr.write(
    `three_sample: ${message}\nusage: node three_sample.mjs FILE.glb --times t1,t2,... [--clip NAME]...\n`,
  );
  process.exit(2);
}

function parseArgs(argv) {
  let file = null;
  let times = null;
  const clips = [];
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--times') {
      times = value()
        .split(',')
        .filter((s) => s.trim() !== '')
        .map((s) => {
          const t = Number(s);
          if (!Number.isFinite(t)) usage(`bad time '${s}'`);
          return t;
        });
    } else if (a.startsWith('--times=')) {
      return parseArgs([...argv.slice(0, i), '--times', a.slice(8), ...argv.slice(i + 1)]);
    } else if (a === '--clip') {
      clips.push(...value().split(',').filter((s) => s !== ''));
    } else if (a.startsWith('--clip=')) {
      clips.push(...a.slice(7).split(',').filter((s) => s !== ''));
    } else if (a === '-h' || a === '--help') {
      usage('help');
    } else if (a.startsWith('--')) {
      usage(`unknown option ${a}`);
    } else if (file === null) {
      file = a;
    } else {
      usage(`unexpected argument ${a}`);
    }
  }
  if (file === null) usage('no input file');
  if (times === null || times.length === 0) usage('--times is required');
  return { file, times, clips };
}

function fail(file, error) {
  const message = error && error.message ? error.message : String(error);
  process.stderr.write(`three_sample: ${file}: ${message}\n`);
  process.exit(1);
}

// Headless loading: never touch image data, and read external buffers (.gltf + .bin, data: URIs)
// ourselves instead of through three's FileLoader (fetch + DOM progress events).
function headless(parser) {
  parser.fileLoader = {
    load(url, onLoad, _onProgress, onError) {
      let pending;
      if (url.startsWith('data:')) {
        const comma = url.indexOf(',');
        const meta = url.slice(5, comma);
        const body = url.slice(comma + 1);
        pending = Promise.resolve(
          meta.endsWith(';base64') ? Buffer.from(body, 'base64') : Buffer.from(decodeURIComponent(body)),
        );
      } else {
        pending = readFile(url.startsWith('file:') ? new URL(url) : url);
      }
      pending
        .then((b) => onLoad(b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength)))
        .catch((e) => onError(new Error(`cannot read buffer ${url}: ${e.message}`)));
    },
  };
  return {
    name: 'FROND_headless',
    loadTexture(textureIndex) {
      const texture = new Texture();
      texture.userData.gltfTexture = textureIndex;
      texture.userData.stub = true;
      parser.associations.set(texture, { textures: textureIndex });
      return Promise.resolve(texture);
    },
  };
}

async function load(file) {
  let bytes;
  try {
    bytes = await readFile(file);
  } catch (e) {
    fail(file, e);
  }
  // The exact ArrayBuffer slice (Node may pool small buffers).
  const data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  loader.register(headless);
  // Buffer URIs resolve against the file's folder, as file: URLs.
  const resourcePath = pathToFileURL(path.dirname(path.resolve(file)) + path.sep).href;
  try {
    return await new Promise((resolve, reject) => loader.parse(data, resourcePath, resolve, reject));
  } catch (e) {
    fail(file, e);
  }
}

function meshesOf(gltf) {
  const out = [];
  gltf.scene.traverse((object) => {
    if (!object.isMesh) return;
    const assoc = gltf.parser.associations.get(object) ?? {};
    let node = assoc.nodes;
    // A multi-primitive mesh is a Group (the node) of one Mesh per primitive; a mesh on a joint
    // node is a child of the Bone.
    for (let p = object.parent; node === undefined && p; p = p.parent) {
      const a = gltf.parser.associations.get(p);
      if (a && a.nodes !== undefined) node = a.nodes;
    }
    out.push({
      object,
      node: node ?? null,
      mesh: assoc.meshes ?? null,
      primitive: assoc.primitives ?? null,
    });
  });
  return out;
}

function samplePositions(meshes) {
  const v = new Vector3();
  return meshes.map(({ object }) => {
    const count = object.geometry.getAttribute('position').count;
    const flat = new Array(count * 3);
    for (let i = 0; i < count; i++) {
      object.getVertexPosition(i, v);
      v.applyMatrix4(object.matrixWorld);
      flat[3 * i] = v.x;
      flat[3 * i + 1] = v.y;
      flat[3 * i + 2] = v.z;
    }
    return flat;
  });
}

async function main() {
  const { file, times, clips: wanted } = parseArgs(process.argv.slice(2));
  if (typeof SkinnedMesh.prototype.getVertexPosition !== 'function') {
    fail(file, new Error('this three.js has no SkinnedMesh.getVertexPosition (needs r151+)'));
  }
  const gltf = await load(file);
  const json = gltf.parser.json;
  const scene = gltf.scene;
  const animations = gltf.animations.map((c) => c.name);

  let chosen;
  if (wanted.length > 0) {
    chosen = wanted.map((name) => {
      const clip = gltf.animations.find((c) => c.name === name);
      if (!clip) usage(`no clip named '${name}' (clips: ${JSON.stringify(animations)})`);
      return clip;
    });
  } else {
    chosen = gltf.animations.length > 0 ? gltf.animations : [null];
  }

  const meshes = meshesOf(gltf);
  const result = {
    file,
    nodes: (json.nodes ?? []).length,
    skins: (json.skins ?? []).length,
    meshes: (json.meshes ?? []).length,
    animations,
    clips: [],
  };

  for (const clip of chosen) {
    const mixer = new AnimationMixer(scene);
    let action = null;
    if (clip) {
      action = mixer.clipAction(clip);
      action.play();
    }
    const perMesh = meshes.map(() => []);
    for (const t of times) {
      mixer.setTime(t);
      scene.updateMatrixWorld(true);
      samplePositions(meshes).forEach((flat, m) => perMesh[m].push(flat));
    }
    if (action) {
      action.stop();
      mixer.uncacheClip(clip);
    }
    // Back to the rest pose so the next clip starts from the file's transforms.
    mixer.stopAllAction();
    result.clips.push({
      name: clip ? clip.name : null,
      duration: clip ? clip.duration : 0,
      times,
      meshes: meshes.map((m, k) => ({
        name: m.object.name,
        node: m.node,
        mesh: m.mesh,
        primitive: m.primitive,
        skinned: m.object.isSkinnedMesh === true,
        vertex_count: m.object.geometry.getAttribute('position').count,
        positions: perMesh[k],
      })),
    });
  }

  process.stderr.write(
    `three_sample: ${file}: ${result.nodes} nodes, ${result.skins} skins, ${meshes.length} mesh primitives, ` +
      `animations ${JSON.stringify(animations)}\n`,
  );
  process.stdout.write(JSON.stringify(result));
  process.stdout.write('\n');
}

main().catch((e) => {
  process.stderr.write(`three_sample: ${e && e.stack ? e.stack : e}\n`);
  process.exit(1);
});
