//! Structure-aware fuzzing of the importer: inputs are GLB (or .gltf) files, mutated by
//! `frond_fuzz::mutator` (JSON edits chosen with `arbitrary`, binary-chunk and container edits,
//! JSON-aware crossover), then imported and sampled like `import_glb`.
#![no_main]

use libfuzzer_sys::{fuzz_crossover, fuzz_mutator, fuzz_target};

fuzz_target!(|data: &[u8]| {
    frond_fuzz::import_and_sample(data);
});

fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    frond_fuzz::mutator::mutate(data, size, max_size, seed)
});

fuzz_crossover!(|data1: &[u8], data2: &[u8], out: &mut [u8], seed: u32| {
    frond_fuzz::mutator::crossover(data1, data2, out, seed)
});
