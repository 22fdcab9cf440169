//! Raw bytes → `frond_scene::import_bytes` (as `fuzz.glb`), then bounded sampling of the
//! imported tree. libFuzzer's own byte mutations; use `fuzz/gltf.dict` as its dictionary.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    frond_fuzz::import_and_sample(data);
});
