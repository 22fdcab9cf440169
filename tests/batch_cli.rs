//! `frond batch` end to end: shards as separate processes match a single run, a SIGKILLed
//! batch never shows a partial tree and its rerun does only the missing trees, broken inputs
//! are isolated, manifests, presets, --eval and staleness.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{fixture, frond, frond_ok, parse_json, read_json, root, validate};
use frond_app::batch::summary::{BatchSummary, LodMetric, Status, TreeEntry};

/// Small, quick settings for every batch here.
const FAST: &[&str] = &["--lods", "100,30", "--samples", "16", "--planes", "60"];

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A generated small tree at `path`.
fn sample_tree(path: &Path, seed: u64) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    frond_ok(&[
        "sample",
        "--preset",
        "small",
        "--seed",
        &seed.to_string(),
        "-o",
        s(path),
    ]);
}

fn batch_cmd(input: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_frond"));
    c.args(["batch", s(input), "-o", s(out)])
        .args(FAST)
        .args(extra)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID");
    c
}

fn summary(path: &Path) -> BatchSummary {
    read_json(path)
}

/// `trees` without their timing fields (stage times, wall time, memory).
fn untimed_trees(trees: &[TreeEntry]) -> Vec<TreeEntry> {
    trees.iter().map(TreeEntry::without_timing).collect()
}

/// Removes timing fields, recursively: the written forms of two reports or stamps compared
/// whole (the method sections included, whose `t_*` fields no struct names), not a read of
/// either.
fn untimed(mut v: serde_json::Value) -> serde_json::Value {
    match &mut v {
        serde_json::Value::Object(m) => {
            // Timing fields: stage times, wall time, memory, and the skeleton's `t_simplify`.
            m.retain(|k, _| {
                !["timings_s", "times_s", "wall_s", "peak_rss_bytes"].contains(&k.as_str())
                    && !k.starts_with("t_")
            });
            for x in m.values_mut() {
                *x = untimed(x.take());
            }
        }
        serde_json::Value::Array(a) => {
            for x in a.iter_mut() {
                *x = untimed(x.take());
            }
        }
        _ => {}
    }
    v
}

/// Every file under `dir` outside hidden folders and the summaries, by relative path.
fn tree_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || (d == root && name.starts_with("summary")) {
                continue;
            }
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Asserts two batch outputs hold the same files with the same bytes (reports and stamps
/// compared without their timing fields).
fn assert_same_outputs(a: &Path, b: &Path) {
    let (fa, fb) = (tree_files(a), tree_files(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "same files"
    );
    for (name, bytes) in &fa {
        if name.ends_with("report.json") || name.ends_with("batch.json") {
            let j = |b: &[u8]| untimed(serde_json::from_slice(b).unwrap());
            assert_eq!(j(bytes), j(&fb[name]), "{name}");
        } else {
            assert!(bytes == &fb[name], "{name} differs");
        }
    }
}

/// Output folders under `out` whose stamp exists, checking each is complete: every file its
/// stamp lists is there with its size (a visible folder without a stamp is partial).
fn complete_outputs(out: &Path, outputs: &[&str]) -> Vec<String> {
    let mut done = Vec::new();
    for o in outputs {
        let dir = out.join(o);
        if !dir.exists() {
            continue;
        }
        let stamp: TreeEntry = serde_json::from_slice(
            &std::fs::read(dir.join("batch.json"))
                .unwrap_or_else(|_| panic!("{o}: visible without its stamp (partial)")),
        )
        .unwrap_or_else(|_| panic!("{o}: stamp unreadable"));
        for f in &stamp.files {
            let m = std::fs::metadata(dir.join(&f.name))
                .unwrap_or_else(|_| panic!("{o}: {:?} missing (partial)", f.name));
            assert_eq!(m.len(), f.bytes, "{o}: size");
        }
        done.push(o.to_string());
    }
    done
}

/// `<dir>/in/` holding the bundled sapling.
fn library_with_sapling(dir: &Path) -> PathBuf {
    let input = dir.join("in");
    std::fs::create_dir_all(&input).unwrap();
    std::fs::copy(
        root().join("samples/sapling.glb"),
        input.join("sapling.glb"),
    )
    .unwrap();
    input
}

#[test]
fn shards_in_separate_processes_equal_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let input = library_with_sapling(dir.path());
    std::fs::copy(fixture("bush_1.glb"), input.join("bush_1.glb")).unwrap();
    sample_tree(&input.join("gen/a.glb"), 2);
    sample_tree(&input.join("gen/b.glb"), 3);
    sample_tree(&input.join("gen/deep/c.glb"), 4);

    let single = dir.path().join("single");
    let out = batch_cmd(&input, &single, &["--jobs", "2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let one = summary(&single.join("summary.json"));
    assert_eq!(one.counts.built, 5);

    // Three shards at once into one shared folder; shard 1 finds itself from the Kubernetes
    // variables, as an Indexed Job's pod would.
    let shared = dir.path().join("shared");
    let children: Vec<_> = (0..3)
        .map(|i| {
            let mut c = if i == 1 {
                let mut c = batch_cmd(&input, &shared, &["--jobs", "1", "--shard", "auto"]);
                c.env("JOB_COMPLETION_INDEX", "1")
                    .env("JOB_COMPLETIONS", "3");
                c
            } else {
                batch_cmd(
                    &input,
                    &shared,
                    &["--jobs", "1", "--shard", &format!("{i}/3")],
                )
            };
            c.stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let out = c.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Every tree in exactly one shard.
    let mut seen: Vec<String> = Vec::new();
    for i in 0..3 {
        let part = summary(&shared.join(format!("summary.shard-{i:04}-of-0003.json")));
        assert_eq!(part.shard.expect("a shard's summary").index, i);
        for t in &part.trees {
            seen.push(t.tree.clone());
        }
    }
    seen.sort();
    let all: Vec<String> = one.trees.iter().map(|t| t.tree.clone()).collect();
    assert_eq!(seen, all, "each tree in exactly one shard");

    let merged = frond_ok(&["batch-merge", s(&shared), "--json"]);
    let merged: BatchSummary = parse_json(&merged.stdout);
    assert_eq!(merged.merged_from.len(), 3);
    assert_eq!(untimed_trees(&merged.trees), untimed_trees(&one.trees));
    assert_eq!(merged.counts, one.counts);
    assert_eq!(summary(&shared.join("summary.json")).trees, merged.trees);
    assert_same_outputs(&single, &shared);
}

#[cfg(unix)]
#[test]
fn a_killed_batch_shows_no_partial_tree_and_its_rerun_does_only_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    let outputs = ["t1", "t2", "t3", "t4", "t5"];
    for (i, o) in outputs.iter().enumerate() {
        sample_tree(&input.join(format!("{o}.glb")), 10 + i as u64);
    }
    let out = dir.path().join("out");

    // Watches the output folder until the batch ends (or is killed at the first tree done).
    let watch = |mut child: std::process::Child, kill_at_first: bool| -> Vec<String> {
        let start = Instant::now();
        loop {
            let done = complete_outputs(&out, &outputs);
            if kill_at_first && !done.is_empty() {
                child.kill().unwrap(); // SIGKILL
                child.wait().unwrap();
                return complete_outputs(&out, &outputs);
            }
            if let Some(status) = child.try_wait().unwrap() {
                assert!(status.success() || kill_at_first, "batch failed");
                return done;
            }
            assert!(start.elapsed() < Duration::from_secs(600), "batch hangs");
            std::thread::sleep(Duration::from_millis(5));
        }
    };
    let child = batch_cmd(&input, &out, &["--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let before = watch(child, true);
    assert!(
        !before.is_empty() && before.len() < outputs.len(),
        "{before:?}"
    );
    assert!(!out.join("summary.json").exists());
    // The killed batch's `frond lod` died with it: nothing changes any more.
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(complete_outputs(&out, &outputs), before);
    let mtimes: Vec<_> = before
        .iter()
        .map(|o| {
            std::fs::metadata(out.join(o).join("batch.json"))
                .unwrap()
                .modified()
                .unwrap()
        })
        .collect();

    let child = batch_cmd(&input, &out, &["--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let after = watch(child, false);
    assert_eq!(after.len(), outputs.len());
    let sum = summary(&out.join("summary.json"));
    for t in &sum.trees {
        let o = t.output.as_str();
        let expected = if before.iter().any(|b| b == o) {
            Status::UpToDate
        } else {
            Status::Built
        };
        assert_eq!(t.status, expected, "{o}");
    }
    for (o, m) in before.iter().zip(mtimes) {
        let now = std::fs::metadata(out.join(o).join("batch.json"))
            .unwrap()
            .modified()
            .unwrap();
        assert_eq!(now, m, "{o} was redone");
    }
    // No temporary folders left behind.
    let tmp = out.join(".frond-tmp");
    assert!(!tmp.exists() || std::fs::read_dir(&tmp).unwrap().next().is_none());
}

#[test]
fn broken_files_are_isolated_with_one_error_line_each() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir_all(input.join("real")).unwrap();
    for t in ["bush_1.glb", "sapling_blender.glb"] {
        std::fs::copy(fixture(t), input.join("real").join(t)).unwrap();
    }
    let bush = std::fs::read(fixture("bush_1.glb")).unwrap();
    std::fs::write(input.join("truncated.glb"), &bush[..bush.len() / 3]).unwrap();
    std::fs::write(
        input.join("notes.glb"),
        b"these are not the trees you are looking for",
    )
    .unwrap();
    std::fs::write(
        input.join("empty.gltf"),
        br#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"name":"x"}]}"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = batch_cmd(&input, &out, &["--jobs", "2"]).output().unwrap();
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    for bad in ["truncated.glb", "notes.glb", "empty.gltf"] {
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with(&format!("error: {bad}: ")))
            .collect();
        assert_eq!(lines.len(), 1, "{bad}: {stderr}");
        assert!(!out.join(bad.split('.').next().unwrap()).exists());
    }
    assert!(
        stderr.contains("error: notes.glb: not a glTF file"),
        "{stderr}"
    );
    assert!(
        stderr.contains("error: truncated.glb: truncated"),
        "{stderr}"
    );
    assert!(
        stderr.contains("error: empty.gltf: the file has no mesh"),
        "{stderr}"
    );
    let last = stderr.lines().last().unwrap();
    assert!(
        last.contains("5 trees: 2 built, 0 up to date, 3 failed"),
        "{last}"
    );
    assert_eq!(
        complete_outputs(&out, &["real/bush_1", "real/sapling_blender"]).len(),
        2
    );
    let sum = summary(&out.join("summary.json"));
    let failed: Vec<&str> = sum
        .trees
        .iter()
        .filter(|t| t.status == Status::Failed)
        .map(|t| t.tree.as_str())
        .collect();
    assert_eq!(failed, ["empty.gltf", "notes.glb", "truncated.glb"]);
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_eq!(csv.lines().count(), 6);
}

/// `--eval`'s numbers of a tree of one LOD: every summary number for LOD1, evaluated at its
/// size, the coverage errors fractions of the tree's area, the covered area about the tree's;
/// none for LOD0, the input.
fn check_eval_numbers(t: &TreeEntry) {
    let lod1 = &t.lods[1];
    assert_eq!(
        lod1.metrics.keys().copied().collect::<Vec<_>>(),
        LodMetric::ALL,
        "{}",
        t.tree
    );
    for m in [
        LodMetric::CoverageStatic,
        LodMetric::CoverageAnimated,
        LodMetric::CoverageFoliage,
    ] {
        let cov = lod1.metric(m).unwrap_or(f64::NAN);
        assert!((0.0..1.0).contains(&cov), "{}: {m:?} {cov}", t.tree);
    }
    let ratio = lod1.metric(LodMetric::CoverageRatio).unwrap_or(f64::NAN);
    assert!(
        (0.5..1.5).contains(&ratio),
        "{}: coverage ratio {ratio}",
        t.tree
    );
    assert!(lod1.metric(LodMetric::DominatingAxis).is_some());
    assert!(t.lods[0].metrics.is_empty(), "LOD0 is the input");
}

/// `summary.csv` at `path` has a column per summary number, last, and its first tree's line
/// is `first`'s: LOD0's cell empty before LOD1's value.
fn check_csv_numbers(path: &Path, first: &TreeEntry) {
    let csv = std::fs::read_to_string(path).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keys: Vec<&str> = LodMetric::ALL.iter().map(|m| m.key()).collect();
    assert_eq!(header[header.len() - keys.len()..], keys[..]);
    let ratio = first.lods[1].metric(LodMetric::CoverageRatio).unwrap();
    // (The metric cells are last and hold no comma; the settings' JSON before them does.)
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let from_end = header.len() - header.iter().position(|h| *h == "coverage_ratio").unwrap();
    assert_eq!(row[row.len() - from_end], format!(";{ratio:.5}"));
}

#[test]
fn manifest_overrides_preset_eval_and_staleness() {
    let dir = tempfile::tempdir().unwrap();
    let lib = dir.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    std::fs::copy(root().join("samples/sapling.glb"), lib.join("sapling.glb")).unwrap();
    sample_tree(&lib.join("more/a.glb"), 5);
    let manifest = dir.path().join("trees.toml");
    let write_manifest = |seed: u64| {
        std::fs::write(
            &manifest,
            format!(
                "[defaults]\nsamples = 16\n\n[[tree]]\npath = \"lib/sapling.glb\"\nmethod = \
                 \"static\"\nlods = [60]\n\n[[tree]]\npath = \"lib/more/a.glb\"\noutput = \
                 \"custom/a\"\nmethod = \"skeleton\"\nlods = [100]\nseed = {seed}\n"
            ),
        )
        .unwrap()
    };
    write_manifest(1);
    let out = dir.path().join("out");
    let run = || {
        let r = frond(&[
            "batch",
            s(&manifest),
            "-o",
            s(&out),
            "--preset",
            "unreal",
            "--eval",
            "--planes",
            "60",
            "--json",
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        parse_json::<BatchSummary>(&r.stdout)
    };
    let first = run();
    let trees = &first.trees;
    assert_eq!(trees[0].tree, "lib/more/a.glb");
    assert_eq!(trees[0].output, "custom/a");
    assert_eq!(trees[1].output, "lib/sapling");
    // Each tree's settings: the manifest's, the batch's options and the preset's conventions.
    let settings = |k: usize| trees[k].settings.clone().unwrap();
    let (a, b) = (settings(0), settings(1));
    assert_eq!(
        (a.method.text(), a.lods.as_slice()),
        ("skeleton", &[100.0][..])
    );
    assert_eq!((a.max_atlas, a.external_textures), (8192, true));
    assert_eq!(a.preset, Some(frond_app::lod_settings::Engine::Unreal));
    assert_eq!(a.build.planes, 60);
    assert_eq!(
        (b.method.text(), b.lods.as_slice()),
        ("static", &[60.0][..])
    );
    // The joint budget keeps every LOD within 256 joints (a static LOD of the sapling once had a
    // joint per moving billboard): nothing to warn about.
    assert!(trees[1].warnings.is_empty());
    assert!(trees[0].warnings.is_empty());
    for t in trees {
        assert_eq!(t.status, Status::Built);
        assert_eq!(t.preset.as_deref(), Some("unreal"));
        // Every GLB is read back: each LOD whose skin has more than Unreal's 256 joints (the
        // static sapling LOD: a joint per moving billboard) is warned about, with the combined
        // file holding it, and nothing else.
        let over: Vec<String> = t
            .lods
            .iter()
            .filter(|l| l.bones > 256)
            .map(|l| l.file.clone())
            .collect();
        let mut expected = over.clone();
        if !over.is_empty() {
            expected.push(format!(
                "{}_lods.glb",
                over[0].split("_LOD").next().unwrap()
            ));
        }
        let warned: Vec<String> = t
            .warnings
            .iter()
            .map(|w| {
                assert!(w.contains("joints in one skin, over unreal's 256"), "{w}");
                w.split(':').next().unwrap().to_string()
            })
            .collect();
        assert_eq!(warned, expected);
        let lods = &t.lods;
        assert_eq!(lods.len(), 2);
        check_eval_numbers(t);
        let files: Vec<&str> = t.files.iter().map(|f| f.name.as_str()).collect();
        assert!(
            files.iter().any(|f| f.ends_with(".png")),
            "external textures: {files:?}"
        );
        let folder = out.join(&t.output);
        for l in lods {
            let Some(report) = validate(&folder.join(&l.file)) else {
                continue;
            };
            assert_eq!(report["errors"], 0, "{report}");
            assert_eq!(report["warnings"], 0, "{report}");
            // The preset's influence limit, as the validator counts it.
            assert!(
                report["info"]["maxInfluences"].as_u64().unwrap() <= 4,
                "{report}"
            );
        }
    }
    check_csv_numbers(&out.join("summary.csv"), &trees[0]);

    // Nothing changed: nothing rebuilt.
    let again = run();
    assert_eq!(again.counts.up_to_date, 2);
    assert_eq!(again.trees[0].lods, trees[0].lods);
    // A changed setting rebuilds that tree, a changed input file that one.
    write_manifest(2);
    std::fs::copy(fixture("bush_1.glb"), lib.join("sapling.glb")).unwrap();
    let third = run();
    assert_eq!(third.counts.built, 2);
    assert_ne!(third.trees[0].params_hash, trees[0].params_hash);
    assert_ne!(third.trees[1].input_hash, trees[1].input_hash);
    assert_eq!(third.trees[1].params_hash, trees[1].params_hash);

    // A bad manifest is refused before any work, naming the file.
    std::fs::write(
        &manifest,
        "[[tree]]\npath = \"lib/sapling.glb\"\nlods = [0]\n",
    )
    .unwrap();
    let bad = frond(&["batch", s(&manifest), "-o", s(&dir.path().join("o2"))]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("trees.toml tree 1") && err.contains("lods: 0"),
        "{err}"
    );
}

#[test]
fn never_overwrites_what_it_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let input = library_with_sapling(dir.path());
    sample_tree(&input.join("b.glb"), 7);
    // An output folder inside which the input lies would feed outputs back as inputs.
    for out in [input.clone(), dir.path().to_path_buf()] {
        let r = frond(&["batch", s(&input), "-o", s(&out)]);
        assert!(!r.status.success());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains("holds the input"), "{err}");
    }
    // A folder of the user's where a tree's output would go is left alone, the tree failed;
    // a budget smaller than any tree still runs every tree (one at a time).
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("sapling")).unwrap();
    std::fs::write(out.join("sapling/mine.txt"), b"keep").unwrap();
    let r = batch_cmd(&input, &out, &["--jobs", "2", "--max-memory", "1K"])
        .output()
        .unwrap();
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("error: sapling.glb: ") && err.contains("is not a frond batch output"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(out.join("sapling/mine.txt")).unwrap(),
        b"keep"
    );
    assert_eq!(complete_outputs(&out, &["b"]), ["b"]);
}
