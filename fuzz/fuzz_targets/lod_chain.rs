//! Structure-aware fuzzing of `frond lod` itself: inputs are GLB (or .gltf) files, mutated as
//! for `import_structured`; a tree that imports goes through sampling, a method's build (picked
//! by the input's hash), the budgets, export and the output set (`frond_fuzz::build_lods`).
#![no_main]

use libfuzzer_sys::{fuzz_crossover, fuzz_mutator, fuzz_target};

fuzz_target!(|data: &[u8]| {
    frond_fuzz::build_lods(data);
});

fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    frond_fuzz::mutator::mutate(data, size, max_size, seed)
});

fuzz_crossover!(|data1: &[u8], data2: &[u8], out: &mut [u8], seed: u32| {
    frond_fuzz::mutator::crossover(data1, data2, out, seed)
});
