//! `frond batch` throughput and memory on a 50-tree library: the seven shared trees
//! (oak_dense among them) plus 28 small and 15 medium generated trees, default `frond lod`
//! settings, `--jobs` from `FROND_JOBS` (default 2). Prints trees per minute, the peak memory
//! of all processes together (sampled every 50 ms) and of the largest single tree, then the
//! time of a rerun that finds everything up to date.
//!
//! Run with `cargo bench --bench batch_throughput` (the library is made once under
//! `target/bench-batch/`; `FROND_BENCH_DIR` moves it). The shared trees come from
//! `FROND_TEST_TREES`; those absent are left out of the library with one `skipped:` line.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use frond_scene::generator::{Preset, generate};

/// Resident memory (bytes) of `pid` and all its descendants, from /proc.
fn tree_rss(pid: u32) -> u64 {
    let mut parent_of = Vec::new();
    if let Ok(dir) = std::fs::read_dir("/proc") {
        for e in dir.flatten() {
            let Ok(p) = e.file_name().to_string_lossy().parse::<u32>() else {
                continue;
            };
            let Ok(stat) = std::fs::read_to_string(format!("/proc/{p}/stat")) else {
                continue;
            };
            // Fields after the ")" of the command name: state ppid ...
            let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
                continue;
            };
            let ppid: u32 = rest
                .split_whitespace()
                .nth(1)
                .and_then(|v| v.parse().ok())
                .unwrap_or(0);
            parent_of.push((p, ppid));
        }
    }
    let mut family = vec![pid];
    let mut i = 0;
    while i < family.len() {
        let f = family[i];
        family.extend(parent_of.iter().filter(|(_, pp)| *pp == f).map(|(p, _)| *p));
        i += 1;
    }
    family
        .iter()
        .filter_map(|p| {
            let s = std::fs::read_to_string(format!("/proc/{p}/status")).ok()?;
            let l = s.lines().find(|l| l.starts_with("VmRSS:"))?;
            Some(l.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
        })
        .sum()
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let base = std::env::var("FROND_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| root.join("target/bench-batch"));
    let jobs = std::env::var("FROND_JOBS").unwrap_or_else(|_| "2".into());
    let lib = base.join("lib");
    let names = [
        "bush_1",
        "oak_dense",
        "oak_large",
        "oak_medium",
        "oak_medium_blendedleaves",
        "pine_medium",
        "pine_medium_blender",
    ];
    std::fs::create_dir_all(lib.join("shared")).expect("library folder");
    let mut missing = Vec::new();
    for n in names {
        let to = lib.join("shared").join(format!("{n}.glb"));
        if !to.exists() {
            match frond_testdata::tree(&format!("{n}.glb")) {
                Some(from) => {
                    std::fs::copy(from, &to).expect("shared tree");
                }
                None => missing.push(format!("{n}.glb")),
            }
        }
    }
    if !missing.is_empty() {
        frond_testdata::report_skip("batch_throughput (those trees only)", &missing);
    }
    for (preset, name, count) in [
        (Preset::Small, "small", 28u64),
        (Preset::Medium, "medium", 15),
    ] {
        for seed in 1..=count {
            let to = lib.join(name).join(format!("{name}_{seed:02}.glb"));
            if !to.exists() {
                std::fs::create_dir_all(to.parent().expect("parent")).expect("folder");
                let t = generate(preset, seed).expect("generates");
                std::fs::write(&to, &t.glb).expect("writes");
            }
        }
    }
    let out = base.join("out");
    let _ = std::fs::remove_dir_all(&out);

    let run = |label: &str| {
        let start = Instant::now();
        let mut child = Command::new(env!("CARGO_BIN_EXE_frond"))
            .args(["batch"])
            .arg(&lib)
            .arg("-o")
            .arg(&out)
            .args(["--jobs", &jobs])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .expect("frond runs");
        let pid = child.id();
        let stop = AtomicBool::new(false);
        let peak = std::thread::scope(|s| {
            let sampler = s.spawn(|| {
                let mut peak = 0u64;
                while !stop.load(Ordering::SeqCst) {
                    peak = peak.max(tree_rss(pid));
                    std::thread::sleep(Duration::from_millis(50));
                }
                peak
            });
            let status = child.wait().expect("waits");
            stop.store(true, Ordering::SeqCst);
            assert!(status.success(), "batch failed");
            sampler.join().expect("sampler")
        });
        let wall = start.elapsed().as_secs_f64();
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary"))
                .expect("json");
        let trees = summary["trees"].as_array().expect("trees");
        let (largest, name) = trees
            .iter()
            .filter_map(|t| Some((t["peak_rss_bytes"].as_u64()?, t["tree"].as_str()?)))
            .max()
            .unwrap_or((0, "-"));
        println!(
            "{label}: {} trees ({}) in {wall:.1} s = {:.1} trees/min with --jobs {jobs}; peak \
             memory all processes {:.0} MB, largest tree {:.0} MB ({name}); output {:.0} MB",
            trees.len(),
            summary["counts"],
            trees.len() as f64 / wall * 60.0,
            peak as f64 / 1_048_576.0,
            largest as f64 / 1_048_576.0,
            trees
                .iter()
                .filter_map(|t| t["output_bytes"].as_u64())
                .sum::<u64>() as f64
                / 1_048_576.0,
        );
        for t in trees {
            println!(
                "  {:40} {:7.1} s {:6.0} MB",
                t["tree"].as_str().unwrap_or("?"),
                t["times_s"]["total"].as_f64().unwrap_or(0.0),
                t["peak_rss_bytes"].as_u64().unwrap_or(0) as f64 / 1_048_576.0
            );
        }
    };
    run("first run");
    run("rerun (all up to date)");
}
