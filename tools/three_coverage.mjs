// Renders a glTF/GLB file with three.js in headless Chromium (Debian's, through puppeteer-core;
// WebGL in software through SwiftShader) from one orthographic camera and writes each pixel's
// covered fraction: the alpha the framebuffer holds after drawing the file as GLTFLoader loads it
// (MASK materials alpha-tested and written opaque, BLEND materials transparent with depth writes
// off, composited as alpha + dst·(1 − alpha) by three's NormalBlending), cleared to alpha 0.
//
//   node tools/three_coverage.mjs FILE.glb CAMERA.json OUT.raw [CHROMIUM]
//
// CAMERA.json: an array of views, each { eye, target, up: [x, y, z], half_width, half_height,
//   near, far, width, height, time: seconds on the first clip (ignored without clips) }
// OUT.raw: per view in order, width × height bytes: the alpha of each pixel (0..255), rows from
// the top.
// Stdout: one JSON object { ok, error, views, console }.
//
// The page is served from 127.0.0.1 by this script (three's modules from tools/node_modules, the
// file as written); nothing else is reachable from it.
import { createServer } from 'node:http';
import { readFile, writeFile } from 'node:fs/promises';
import { dirname, join, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

const [file, cameraPath, outPath, chromium = '/usr/bin/chromium'] = process.argv.slice(2);
if (!file || !cameraPath || !outPath) {
  console.error('usage: node tools/three_coverage.mjs FILE.glb CAMERA.json OUT.raw [CHROMIUM]');
  process.exit(2);
}
const cameras = JSON.parse(await readFile(cameraPath, 'utf8'));
const threeRoot = join(dirname(fileURLToPath(import.meta.url)), 'node_modules', 'three');

const page = `<!doctype html><html><body>
<script type="importmap">{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
window.frondCoverage = async (c) => {
  const renderer = new THREE.WebGLRenderer({ antialias: false, alpha: true, premultipliedAlpha: false });
  const gltf = await new GLTFLoader().loadAsync('/model.glb');
  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  if (gltf.animations.length > 0) {
    const mixer = new THREE.AnimationMixer(gltf.scene);
    mixer.clipAction(gltf.animations[0]).play();
    mixer.setTime(c.time);
  }
  // A skinned mesh's bounds are its bind pose's: never cull what the wind moved.
  gltf.scene.traverse((o) => { o.frustumCulled = false; });
  scene.updateMatrixWorld(true);
  const cam = new THREE.OrthographicCamera(-c.half_width, c.half_width, c.half_height, -c.half_height, c.near, c.far);
  cam.position.set(...c.eye);
  cam.up.set(...c.up);
  cam.lookAt(new THREE.Vector3(...c.target));
  cam.updateMatrixWorld(true);
  const target = new THREE.WebGLRenderTarget(c.width, c.height, {
    type: THREE.UnsignedByteType, format: THREE.RGBAFormat, depthBuffer: true,
    minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, generateMipmaps: false,
  });
  renderer.setRenderTarget(target);
  renderer.setClearColor(0x000000, 0);
  renderer.clear(true, true, true);
  renderer.render(scene, cam);
  const rgba = new Uint8Array(c.width * c.height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, c.width, c.height, rgba);
  target.dispose();
  renderer.dispose();
  renderer.forceContextLoss();
  // WebGL reads rows from the bottom; the caller wants them from the top.
  const alpha = [];
  for (let y = c.height - 1; y >= 0; y -= 1) {
    for (let x = 0; x < c.width; x += 1) alpha.push(rgba[(y * c.width + x) * 4 + 3]);
  }
  return alpha;
};
window.frondReady = true;
</script></body></html>`;

const types = { '.js': 'text/javascript', '.glb': 'model/gltf-binary' };
const server = createServer(async (req, res) => {
  try {
    const path = decodeURIComponent(new URL(req.url, 'http://127.0.0.1').pathname);
    if (path === '/') {
      res.writeHead(200, { 'content-type': 'text/html' });
      res.end(page);
    } else if (path === '/model.glb') {
      res.writeHead(200, { 'content-type': types['.glb'] });
      res.end(await readFile(file));
    } else if (path.startsWith('/three/')) {
      const rel = normalize(path.slice('/three/'.length));
      if (rel.startsWith('..')) throw new Error('outside three');
      res.writeHead(200, { 'content-type': types['.js'] });
      res.end(await readFile(join(threeRoot, rel)));
    } else {
      res.writeHead(404);
      res.end();
    }
  } catch {
    res.writeHead(404);
    res.end();
  }
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const url = `http://127.0.0.1:${server.address().port}/`;

const result = { ok: false, error: null, views: cameras.length, console: [] };
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
    '--disable-background-networking', '--disable-component-update', '--no-first-run'],
});
try {
  const tab = await browser.newPage();
  tab.on('console', (m) => result.console.push(`${m.type()}: ${m.text()}`));
  tab.on('pageerror', (e) => result.console.push(`pageerror: ${e.message}`));
  await tab.goto(url, { waitUntil: 'load', timeout: 120000 });
  await tab.waitForFunction(() => window.frondReady === true, { timeout: 120000 });
  const alphas = [];
  for (const camera of cameras) alphas.push(...(await tab.evaluate((c) => window.frondCoverage(c), camera)));
  await writeFile(outPath, Uint8Array.from(alphas));
  result.ok = true;
} catch (e) {
  result.error = `${e.message}`;
} finally {
  await browser.close();
  server.close();
}
console.log(JSON.stringify(result));
