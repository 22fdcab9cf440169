//! Structure-aware fuzzing of the importer on the stable toolchain (cargo fuzz needs nightly):
//! real exporters' trees (the `tests/fixtures/` ez-tree bush and Blender round trip) are
//! mutated in their JSON (numbers swapped for edge values, bytes flipped) and binary chunks,
//! re-wrapped as valid GLB containers, or truncated. Every result must be
//! `Ok` or a clean `Err`: never a panic. A short run is part of the tests; a long one is a heavy
//! case in `.ci/run`'s optimised run (`FROND_HEAVY_TESTS=1 FROND_FUZZ_RUNS=20000 cargo test
//! --release --test frond_tests -- fuzz_import::heavy_` for a longer one by hand).

use crate::common;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use frond_scene::gltf_writer::glb_container;
use frond_scene::{ImportOptions, SampleOptions, import_bytes, sample};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Splits a GLB into (json text, bin chunk).
fn split_glb(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let jl = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
    let json = bytes[20..20 + jl].to_vec();
    let rest = &bytes[20 + jl..];
    let bin = if rest.len() >= 8 {
        rest[8..].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

const EDGE_NUMBERS: &[&str] = &[
    "0",
    "1",
    "-1",
    "2",
    "3",
    "4",
    "5",
    "255",
    "256",
    "65535",
    "65536",
    "4294967295",
    "1e30",
    "-0.5",
    "1e999",
    "5120",
    "5121",
    "5123",
    "5125",
    "5126",
    "9999999",
];

/// One mutation of a seed file.
fn mutate(rng: &mut ChaCha8Rng, json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_vec();
    let mut b = bin.to_vec();
    match rng.random_range(0..6u32) {
        0..=2 => {
            // Replace a few numeric tokens of the JSON with edge values.
            let spans: Vec<(usize, usize)> = {
                let mut v = Vec::new();
                let mut i = 0;
                while i < j.len() {
                    if j[i].is_ascii_digit()
                        && (i == 0 || !(j[i - 1].is_ascii_alphanumeric() || j[i - 1] == b'_'))
                    {
                        let s = i;
                        while i < j.len()
                            && (j[i].is_ascii_digit()
                                || j[i] == b'.'
                                || j[i] == b'e'
                                || j[i] == b'-')
                        {
                            i += 1;
                        }
                        v.push((s, i));
                    }
                    i += 1;
                }
                v
            };
            for _ in 0..rng.random_range(1..4) {
                if spans.is_empty() {
                    break;
                }
                let (s, e) = spans[rng.random_range(0..spans.len())];
                if e > j.len() {
                    continue;
                }
                let with = EDGE_NUMBERS[rng.random_range(0..EDGE_NUMBERS.len())].as_bytes();
                j.splice(s..e, with.iter().copied());
                // Spans after this one moved; stop to keep them valid.
                break;
            }
        }
        3 => {
            for _ in 0..rng.random_range(1..4) {
                let k = rng.random_range(0..j.len());
                j[k] = rng.random::<u8>();
            }
        }
        4 => {
            if !b.is_empty() {
                let start = rng.random_range(0..b.len());
                for k in start..(start + rng.random_range(1..64)).min(b.len()) {
                    b[k] = rng.random::<u8>();
                }
            }
        }
        _ => {
            let whole = glb_container(&j, &b);
            let cut = rng.random_range(0..whole.len());
            return whole[..cut].to_vec();
        }
    }
    glb_container(&j, &b)
}

fn fuzz(runs: usize, seed: u64) {
    let seeds: Vec<Vec<u8>> = ["bush_1.glb", "sapling_blender.glb"]
        .iter()
        .map(|n| std::fs::read(common::fixture(n)).expect("fixture tree"))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut ok, mut err) = (0, 0);
    for run in 0..runs {
        let src = &seeds[run % seeds.len()];
        let (json, bin) = split_glb(src);
        let input = mutate(&mut rng, &json, &bin);
        let result = catch_unwind(AssertUnwindSafe(|| {
            let tree = import_bytes(Path::new("fuzz.glb"), &input, &ImportOptions::default())?;
            sample(
                &tree,
                &SampleOptions {
                    clip: None,
                    samples: 4,
                },
            )
            .map(|_| ())
        }));
        match result {
            Ok(Ok(())) => ok += 1,
            Ok(Err(e)) => {
                assert!(
                    e.to_string().starts_with("fuzz.glb: "),
                    "error names the file: {e}"
                );
                err += 1
            }
            Err(_) => {
                let path = std::env::temp_dir().join(format!("frond-fuzz-crash-{seed}-{run}.glb"));
                let _ = std::fs::write(&path, &input);
                panic!(
                    "importer panicked on run {run}; input saved to {}",
                    path.display()
                );
            }
        }
    }
    eprintln!("fuzz: {runs} runs, {ok} imported, {err} rejected cleanly, 0 panics");
}

#[test]
fn importer_survives_mutated_real_trees() {
    fuzz(120, 1);
}

/// A long fuzz run (`FROND_FUZZ_RUNS` sets the count): a heavy case, in `.ci/run`'s
/// optimised run.
#[test]
fn heavy_importer_survives_a_long_fuzz_run() {
    if !common::heavy() {
        return;
    }
    let runs = std::env::var("FROND_FUZZ_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5000);
    fuzz(runs, 2);
}
