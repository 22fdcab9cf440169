//! `frond batch`: `frond lod` over a whole tree library — in parallel within a memory budget,
//! resumable (up-to-date trees are skipped), failure-isolated (each tree is its own process),
//! and sharded deterministically for job arrays (Kubernetes Indexed Jobs, Slurm).

pub mod inputs;
pub mod shard;
pub mod summary;
pub mod tree_job;

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Condvar, Mutex};
use std::time::Instant;

use anyhow::{Context, Result};

use inputs::{TreeInput, discover};
use shard::Shard;
use summary::{BatchSummary, Counts, Status, TreeEntry};
use tree_job::{TreeContext, process};

/// Memory a `frond lod` child is assumed to need before any has been measured: a fixed part
/// (renderer, buffers), in bytes, plus [`MEMORY_PER_INPUT_BYTE`] for each byte of the input
/// file. Both are set just above the peaks `cargo bench --bench batch_throughput` measures
/// (docs/experiments.md, "How fast does frond batch process a library").
pub const BASE_MEMORY: u64 = 256 << 20;
/// Bytes a `frond lod` child is assumed to need per byte of its input file, on top
/// of [`BASE_MEMORY`], until this run has measured more.
pub const MEMORY_PER_INPUT_BYTE: u64 = 160;

/// What `frond batch` was asked for.
#[derive(Clone, Debug)]
pub struct BatchRequest {
    /// A folder or a TOML manifest.
    pub input: PathBuf,
    /// OUTDIR: each tree's output folder, the summaries and `index.html` go under it.
    pub out_dir: PathBuf,
    /// Trees at once (at most).
    pub jobs: usize,
    /// The shard of the trees this process takes (None: every tree).
    pub shard: Option<Shard>,
    /// Memory the running trees may hold together (bytes); a tree larger than it runs alone.
    pub max_memory: u64,
    /// What every tree's child processes share.
    pub context: TreeContext,
}

/// What a caller is told while a batch runs.
pub trait BatchProgress: Sync {
    /// The trees this run will look at (after sharding).
    fn total(&self, trees: usize);
    /// A tree (its path relative to INPUT) was taken by a worker.
    fn started(&self, tree: &str);
    /// A tree is done: built, up to date or failed, with its summary line.
    fn finished(&self, entry: &TreeEntry);
}

/// The default memory budget: three quarters of the memory available now (Linux
/// `MemAvailable`), else 4 GiB.
pub fn default_max_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            let line = t.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024 / 4 * 3)
        })
        .unwrap_or(4 << 30)
}

/// Parses a memory size: bytes, or a number with K, M, G or T (binary units, optional `B`/`iB`).
pub fn parse_memory(text: &str) -> Result<u64> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let trimmed = upper.trim_end_matches("IB").trim_end_matches('B');
    let (number, unit) = match trimmed.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&trimmed[..i], Some(c)),
        _ => (trimmed, None),
    };
    let shift = match unit {
        None => 0,
        Some('K') => 10,
        Some('M') => 20,
        Some('G') => 30,
        Some('T') => 40,
        Some(u) => anyhow::bail!("memory size '{text}': unknown unit '{u}' (K, M, G or T)"),
    };
    let value: f64 = number
        .trim()
        .parse()
        .with_context(|| format!("memory size '{text}': expected a size like 8G or 512M"))?;
    if !(value.is_finite() && value > 0.0) {
        anyhow::bail!("memory size '{text}': must be positive");
    }
    Ok((value * (1u64 << shift) as f64) as u64)
}

/// Memory a tree of `input_bytes` is expected to peak at, given the largest peak above
/// [`BASE_MEMORY`] per input byte measured so far in this run (`measured_per_byte`).
fn memory_estimate(input_bytes: u64, measured_per_byte: Option<f64>) -> u64 {
    let per_byte = measured_per_byte
        .unwrap_or(0.0)
        .max(MEMORY_PER_INPUT_BYTE as f64);
    BASE_MEMORY.saturating_add((input_bytes as f64 * per_byte) as u64)
}

/// Shared state of the workers.
struct Pool {
    /// Trees not started, with their input's size.
    queue: VecDeque<(TreeInput, u64)>,
    reserved: u64,
    running: usize,
    /// Largest peak RSS per input byte seen.
    per_byte: Option<f64>,
}

/// Runs the batch and writes its summary (`summary.json`/`.csv`, or the shard's
/// `summary.shard-i-of-n.*`) into OUTDIR. Err only for problems of the whole batch (no input,
/// OUTDIR not writable, a folder without trees); a tree's failure is in its entry.
pub fn run_batch(req: &BatchRequest, progress: &dyn BatchProgress) -> Result<BatchSummary> {
    let start = Instant::now();
    crate::out_folder::OutFolder::new(&req.out_dir)
        .create()
        .context("cannot create the output folder")?;
    let out_abs = std::fs::canonicalize(&req.out_dir)
        .with_context(|| format!("{}: cannot resolve", req.out_dir.display()))?;
    if let Ok(input_abs) = std::fs::canonicalize(&req.input)
        && input_abs.starts_with(&out_abs)
    {
        anyhow::bail!(
            "{}: the output folder {} holds the input; choose an output folder outside it",
            req.input.display(),
            req.out_dir.display()
        );
    }
    if req.context.preview {
        // The trees' preview pages share one copy of the viewer scripts (`--preview-viewer`).
        for (rel, bytes) in frond_preview::viewer_files(true) {
            crate::out_folder::OutFolder::new(&out_abs).write_atomic(&rel, bytes)?;
        }
    }
    let mut trees = discover(&req.input, Some(&out_abs))?;
    if let Some(s) = req.shard {
        trees.retain(|t| s.takes(&t.relative));
    }
    progress.total(trees.len());
    let mut context = req.context.clone();
    context.out_dir = out_abs.clone();
    let jobs = req.jobs.max(1).min(trees.len().max(1));
    let pool = Mutex::new(Pool {
        // Each input's size, read once: it sizes the tree's memory estimate.
        queue: trees
            .into_iter()
            .map(|t| {
                let bytes = std::fs::metadata(&t.path).map_or(0, |m| m.len());
                (t, bytes)
            })
            .collect(),
        reserved: 0,
        running: 0,
        per_byte: None,
    });
    let freed = Condvar::new();
    let results = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                loop {
                    // Take the next tree once its memory fits (or nothing else runs).
                    let (tree, bytes, estimate) = {
                        let Ok(mut p) = pool.lock() else { return };
                        loop {
                            let Some(&(_, bytes)) = p.queue.front() else {
                                return;
                            };
                            let estimate = memory_estimate(bytes, p.per_byte);
                            if p.running == 0
                                || p.reserved.saturating_add(estimate) <= req.max_memory
                            {
                                let Some((tree, _)) = p.queue.pop_front() else {
                                    return;
                                };
                                p.reserved = p.reserved.saturating_add(estimate);
                                p.running += 1;
                                break (tree, bytes, estimate);
                            }
                            p = match freed.wait(p) {
                                Ok(p) => p,
                                Err(_) => return,
                            };
                        }
                    };
                    progress.started(&tree.relative);
                    // A panic is that tree's failure, never a stuck pool.
                    let entry = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        process(&context, &tree)
                    }))
                    .unwrap_or_else(|_| TreeEntry::failed(&tree, "internal error (a panic)"));
                    if let Ok(mut p) = pool.lock() {
                        p.reserved = p.reserved.saturating_sub(estimate);
                        p.running -= 1;
                        // Small inputs' peaks are mostly the base: learn from 1 MiB up.
                        if let Some(rss) = entry.peak_rss_bytes
                            && bytes >= 1 << 20
                            && entry.status == Status::Built
                        {
                            let r = rss.saturating_sub(BASE_MEMORY) as f64 / bytes as f64;
                            p.per_byte = Some(p.per_byte.map_or(r, |q| q.max(r)));
                        }
                    }
                    freed.notify_all();
                    progress.finished(&entry);
                    if let Ok(mut r) = results.lock() {
                        r.push(entry);
                    }
                }
            });
        }
    });
    let mut trees = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a batch worker panicked"))?;
    trees.sort_by(|a, b| a.tree.cmp(&b.tree));
    let summary = BatchSummary {
        frond: env!("CARGO_PKG_VERSION").to_string(),
        input: req.input.display().to_string(),
        preset: req.context.preset.map(|p| p.name.to_string()),
        shard: req.shard,
        merged_from: Vec::new(),
        counts: Counts::of(&trees),
        trees,
        wall_s: start.elapsed().as_secs_f64(),
        jobs,
    };
    summary.write(&out_abs, &BatchSummary::stem(req.shard))?;
    // Only succeeds when empty (other shards may still be writing theirs).
    let _ = crate::out_folder::OutFolder::new(&out_abs).remove_dir(tree_job::TMP_DIR);
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_sizes_and_estimates() {
        assert_eq!(parse_memory("512M").unwrap(), 512 << 20);
        assert_eq!(parse_memory("8G").unwrap(), 8 << 30);
        assert_eq!(parse_memory("1.5GiB").unwrap(), 3 << 29);
        assert_eq!(parse_memory("1000").unwrap(), 1000);
        assert!(parse_memory("8X").is_err());
        assert!(parse_memory("-1G").is_err());
        assert!(parse_memory("lots").is_err());
        assert_eq!(memory_estimate(0, None), BASE_MEMORY);
        // A measured ratio only ever raises the model.
        assert_eq!(
            memory_estimate(1 << 20, Some(1.0)),
            BASE_MEMORY + (MEMORY_PER_INPUT_BYTE << 20)
        );
        assert_eq!(
            memory_estimate(1 << 20, Some(1000.0)),
            BASE_MEMORY + (1000 << 20)
        );
    }
}
