// The live view of a frond preview page: plays the run's combined file with three.js
// (window.FROND_THREE, vendored in viewer/), one LOD at a time. State for scripts and tests is
// on window.frondView: ready, error, lods[k].loaded/meshes/triangles, lod (shown), playing,
// time (the clip's), frames (drawn), select(k), setPlaying(on).
(() => {
  'use strict';
  const cfg = JSON.parse(document.getElementById('frond-config').textContent);
  const statusEl = document.getElementById('live-status');
  const slider = document.getElementById('lod-slider');
  const label = document.getElementById('lod-label');
  const auto = document.getElementById('lod-auto');
  const play = document.getElementById('play');
  const canvas = document.getElementById('live-canvas');
  const state = {
    ready: false,
    error: null,
    lods: cfg.lods.map((l) => ({ file: l.file, loaded: false, meshes: 0, triangles: 0 })),
    lod: 0,
    visible: [],
    playing: true,
    time: 0,
    frames: 0,
    treePixels: 0,
  };
  window.frondView = state;
  const say = (text) => { statusEl.textContent = text; };
  const fail = (text) => { state.error = text; say(text); };

  const T = window.FROND_THREE;
  if (!T) {
    fail(`three.js did not load: ${cfg.viewer}/frond-three.js should be beside this page`);
    return;
  }
  let renderer;
  try {
    renderer = new T.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail(`WebGL is not available in this browser: ${e.message}`);
    return;
  }
  renderer.outputColorSpace = T.SRGBColorSpace;
  const scene = new T.Scene();
  scene.background = new T.Color(0xdfe9f1);
  scene.add(new T.HemisphereLight(0xf4f8ff, 0x4a4f3a, 1.4));
  const sun = new T.DirectionalLight(0xffffff, 2.2);
  sun.position.set(4, 10, 6);
  scene.add(sun);
  const camera = new T.PerspectiveCamera(40, 1, 0.01, 1000);
  const controls = new T.OrbitControls(camera, canvas);
  controls.enableDamping = true;
  const timer = new T.Timer();
  let mixer = null;
  let groups = [];
  let height = 1;

  function resize() {
    const w = canvas.clientWidth;
    const h = canvas.clientHeight;
    if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(h, 1);
      camera.updateProjectionMatrix();
    }
  }

  function select(k) {
    k = Math.max(0, Math.min(groups.length - 1, k | 0));
    state.lod = k;
    groups.forEach((g, i) => g.forEach((o) => { o.visible = i === k; }));
    state.visible = groups.map((g) => g.some((o) => o.visible));
    slider.value = String(k);
    const l = cfg.lods[k];
    const built = l.screen_height ? `built for ${l.screen_height} px` : 'the input';
    const still = l.vertex_animated ? ' · vertex-animated, shown still' : '';
    label.textContent = `LOD${k} · ${state.lods[k].triangles.toLocaleString()} triangles · ${built}${still}`;
  }

  // The tree's height on the canvas in device pixels, for switching by screen size.
  function treePixels() {
    const d = camera.position.distanceTo(controls.target);
    const fov = (camera.fov * Math.PI) / 180;
    return (height / (2 * d * Math.tan(fov / 2))) * canvas.height;
  }

  function autoLod(px) {
    let k = 0;
    while (k + 1 < cfg.lods.length && px < cfg.lods[k].shown_down_to_px) k += 1;
    return k;
  }

  function loaded(gltf) {
    const root = gltf.scene;
    scene.add(root);
    groups = cfg.lods.map((l) => l.nodes
      .map((n) => root.getObjectByName(T.PropertyBinding.sanitizeNodeName(n)))
      .filter(Boolean));
    groups.forEach((g, i) => {
      let meshes = 0;
      let triangles = 0;
      g.forEach((o) => o.traverse((m) => {
        if (!m.isMesh) return;
        meshes += 1;
        const geo = m.geometry;
        triangles += (geo.index ? geo.index.count : geo.attributes.position.count) / 3;
        // Skinned meshes move beyond their bind-pose bounds.
        m.frustumCulled = false;
      }));
      state.lods[i].meshes = meshes;
      state.lods[i].triangles = Math.round(triangles);
      state.lods[i].loaded = meshes > 0;
    });
    const box = new T.Box3();
    groups[0].forEach((o) => box.expandByObject(o));
    const size = box.getSize(new T.Vector3());
    const centre = box.getCenter(new T.Vector3());
    height = Math.max(size.y, 1e-6);
    const dist = (0.62 * Math.max(size.y, size.x, size.z)) / Math.tan((camera.fov * Math.PI) / 360);
    controls.target.copy(centre);
    camera.position.set(centre.x, centre.y + 0.1 * size.y, centre.z + dist);
    camera.near = dist / 100;
    camera.far = dist * 100;
    camera.updateProjectionMatrix();
    const clip = gltf.animations.find((a) => a.name === cfg.clip) || gltf.animations[0];
    if (clip) {
      mixer = new T.AnimationMixer(root);
      mixer.clipAction(clip).play();
    }
    select(0);
    const missing = state.lods.filter((l) => !l.loaded).map((l) => l.file);
    if (missing.length) {
      fail(`not found in ${cfg.combined}: ${missing.join(', ')}`);
      return;
    }
    state.ready = true;
    say(`${cfg.combined}: ${groups.length} LODs${clip ? `, clip ${clip.name} (${clip.duration.toFixed(2)} s)` : ', no clip'}`);
  }

  const loader = new T.GLTFLoader();
  loader.setMeshoptDecoder(T.MeshoptDecoder);
  if (cfg.ktx2) {
    const ktx2 = new T.KTX2Loader().setTranscoderPath(`${cfg.viewer}/`).detectSupport(renderer);
    loader.setKTX2Loader(ktx2);
  }
  const failed = (e) => fail(`could not load ${cfg.combined}: ${e && e.message ? e.message : e}`);
  if (location.protocol === 'file:') {
    document.getElementById('file-fallback').hidden = false;
    say('opened from disk: pick the combined file, or run frond view');
    document.getElementById('file-pick').addEventListener('change', async (ev) => {
      const file = ev.target.files[0];
      if (!file) return;
      say(`reading ${file.name}…`);
      loader.parse(await file.arrayBuffer(), '', loaded, failed);
    });
  } else {
    loader.load(cfg.combined, loaded, (p) => {
      if (p.total) say(`loading ${cfg.combined}: ${Math.round((100 * p.loaded) / p.total)} %`);
    }, failed);
  }

  slider.addEventListener('input', () => {
    auto.checked = false;
    select(Number(slider.value));
  });
  state.select = select;
  state.setPlaying = (on) => {
    state.playing = on;
    play.textContent = on ? 'Pause' : 'Play';
  };
  play.addEventListener('click', () => state.setPlaying(!state.playing));

  renderer.setAnimationLoop(() => {
    resize();
    timer.update();
    const dt = timer.getDelta();
    if (mixer && state.playing) {
      mixer.update(dt);
      state.time = mixer.time;
    }
    controls.update();
    if (state.ready) {
      state.treePixels = treePixels();
      if (auto.checked) {
        const k = autoLod(state.treePixels);
        if (k !== state.lod) select(k);
      }
    }
    renderer.render(scene, camera);
    state.frames += 1;
  });
})();
