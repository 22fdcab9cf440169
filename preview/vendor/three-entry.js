export * from 'three';
export { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
export { KTX2Loader } from 'three/examples/jsm/loaders/KTX2Loader.js';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
export { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
