//! Output sets (`src/output_set.rs`): after a kill at any point of `frond lod`'s writing, the
//! output folder holds the complete old set or the complete new set (plus the user's own files,
//! untouched); the next run finishes or clears what a killed one left; a failed write (disk
//! full) leaves the old set; a rerun with fewer LODs removes the old set's extra files; frond
//! never replaces a file it did not write; bad output folders are refused before any work.
//!
//! Kills are deterministic: `FROND_FAULT=abort-after:K` aborts the process after its K-th file
//! operation, as `kill -9` would (no destructor runs).
//!
//! (The file is named `frond_…` so that this test process counts as a live frond run for the
//! concurrent-run check, which looks at `/proc/<pid>/comm`.)

use crate::common;

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use common::*;

const SAMPLE: &str = "samples/sapling.glb";

/// Small settings for every `frond lod` here: few samples and planes, no error measurement and
/// no preview page (the set's mechanism is the same for every file, and the kill test runs
/// `frond lod` a hundred times).
const QUICK: [&str; 6] = [
    "--samples",
    "8",
    "--planes",
    "30",
    "--no-measure",
    "--no-preview",
];

/// `frond lod` of the sample into `out` with small settings, `FROND_FAULT` as given.
fn lod(out: &Path, lods: &str, seed: &str, fault: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_frond"));
    c.args(["lod", SAMPLE, "-o"])
        .arg(out)
        .args(QUICK)
        .args([
            "--lods", lods, "--seed", seed,
            // Billboards: their LODs have the most files (mappings beside the GLBs).
            "--method", "static",
        ])
        .current_dir(root())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env_remove("FROND_FAULT");
    if let Some(f) = fault {
        c.env("FROND_FAULT", f);
    }
    c.output().expect("frond runs")
}

/// Every visible file below `dir` (relative name → bytes); a report without its timings.
fn visible_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("list") {
            let p = e.expect("entry").path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(&p).expect("read");
            if rel.ends_with("_report.json") {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).expect("json");
                strip_timings(&mut v);
                bytes = serde_json::to_vec(&v).unwrap();
            }
            out.insert(rel, bytes);
        }
    }
    out
}

/// Removes the timing fields of a report, recursively: the written forms of two reports
/// compared whole (the method sections included, whose `t_*` fields no struct names), not a
/// read of either.
fn strip_timings(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| k != "timings_s" && !k.starts_with("t_"));
            m.values_mut().for_each(strip_timings);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_timings),
        _ => {}
    }
}

/// Hidden entries frond left in `dir` (staging folders, temporary files).
fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// A folder holding `set` plus the user's `notes.txt`.
fn reset(dir: &Path, set: &BTreeMap<String, Vec<u8>>, raw: &Path) {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    // Copy the raw files (reports with their timings) so the folder is what a run left.
    for rel in set.keys() {
        let to = dir.join(rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(raw.join(rel), to).unwrap();
    }
    std::fs::write(dir.join("notes.txt"), b"the user's own file").unwrap();
}

/// Asserts two file sets are equal, naming the files that differ (not their bytes).
#[track_caller]
fn assert_same(a: &BTreeMap<String, Vec<u8>>, b: &BTreeMap<String, Vec<u8>>, what: &str) {
    let names = |m: &BTreeMap<String, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(a), names(b), "{what}: the same files");
    let differ: Vec<&String> = a.keys().filter(|k| a[*k] != b[*k]).collect();
    assert!(differ.is_empty(), "{what}: {differ:?} differ");
}

fn with_notes(set: &BTreeMap<String, Vec<u8>>) -> BTreeMap<String, Vec<u8>> {
    let mut s = set.clone();
    s.insert("notes.txt".into(), b"the user's own file".to_vec());
    s
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The two sets the kill test moves between, as `frond lod` writes them in an empty folder.
struct Sets {
    /// The old set's folder as its run left it (reports with their timings), to copy from.
    raw_old: PathBuf,
    /// The old set's files (reports without their timings).
    old: BTreeMap<String, Vec<u8>>,
    /// The old set plus the user's `notes.txt`.
    old_n: BTreeMap<String, Vec<u8>>,
    /// The new set plus the user's `notes.txt`.
    new_n: BTreeMap<String, Vec<u8>>,
}

/// What a run of the new settings killed after its `k`-th file operation left.
#[derive(Clone, Copy)]
enum Kill {
    /// `k` is past the last file operation: the run finished and left exactly the new set.
    Finished,
    /// Killed: whether a commit journal was left, and whether the report was gone (a committed
    /// install under way).
    Killed { journal: bool, no_report: bool },
}

/// In `work` holding the old set and the user's file, kills the new settings' run after its
/// `k`-th file operation and checks what it left (the whole old or the whole new set, going by
/// the report; no report only with a journal); then checks that the old settings' next run
/// starts from a whole set and leaves exactly its own, nothing hidden.
fn kill_at(k: usize, work: &Path, sets: &Sets) -> Kill {
    reset(work, &sets.old, &sets.raw_old);
    let run = lod(work, "150,40", "2", Some(&format!("abort-after:{k}")));
    if run.status.success() {
        // k is past the last file operation: the run finished.
        assert_same(
            &visible_files(work),
            &sets.new_n,
            &format!("k = {k}: complete run"),
        );
        assert!(hidden(work).is_empty(), "{:?}", hidden(work));
        return Kill::Finished;
    }
    assert_eq!(run.status.code(), None, "k = {k}: killed by a signal");
    let now = visible_files(work);
    let journal = hidden(work)
        .iter()
        .any(|h| work.join(h).join("frond-commit.json").exists());
    // The report is the set's mark for readers: the old report means exactly the old
    // set, the new one exactly the new set; none only while a committed install is
    // under way (its journal then says how to finish it).
    let no_report = match now.get("sapling_report.json") {
        None => {
            assert!(journal, "k = {k}: no report and no journal");
            true
        }
        Some(r) if Some(r) == sets.old.get("sapling_report.json") => {
            assert_same(&now, &sets.old_n, &format!("k = {k}: the old report"));
            false
        }
        Some(_) => {
            assert_same(&now, &sets.new_n, &format!("k = {k}: the new report"));
            false
        }
    };
    // Whatever was left, the next run (here: the old settings again) starts from a whole
    // set and leaves exactly its own set, nothing hidden.
    ok(&lod(work, "150,60,30", "1", None));
    assert_same(
        &visible_files(work),
        &sets.old_n,
        &format!("k = {k}: rerun after the kill"),
    );
    assert!(hidden(work).is_empty(), "k = {k}: {:?}", hidden(work));
    Kill::Killed { journal, no_report }
}

/// Kills the new settings' run after each of its file operations in turn (`kill_at` for k = 0,
/// 1, … up to the first k whose run finishes). The k are independent (each in a folder of its
/// own, made afresh), so they are spread over a few threads: each `frond lod` of the sample
/// leaves most of a core idle, and this test would otherwise run alone for minutes at the end of
/// the suite.
#[test]
fn a_kill_at_any_point_leaves_the_old_or_the_new_set() {
    let tmp = tempfile::tempdir().unwrap();
    let (ref_old, ref_new) = (tmp.path().join("old"), tmp.path().join("new"));
    // The old set has three LODs; the new one two, another seed: fewer files, other bytes.
    ok(&lod(&ref_old, "150,60,30", "1", None));
    ok(&lod(&ref_new, "150,40", "2", None));
    let (old, new) = (visible_files(&ref_old), visible_files(&ref_new));
    assert!(old.contains_key("sapling_LOD3.glb") && !new.contains_key("sapling_LOD3.glb"));
    assert!(old.contains_key("sapling_report.json"));
    assert_ne!(old["sapling_LOD1.glb"], new["sapling_LOD1.glb"]);
    let sets = Sets {
        raw_old: ref_old,
        old_n: with_notes(&old),
        new_n: with_notes(&new),
        old,
    };

    // At most 100 file operations; `end` is the first k whose run finished.
    const LIMIT: usize = 100;
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
    let next = AtomicUsize::new(0);
    let end = AtomicUsize::new(LIMIT);
    let failed = AtomicBool::new(false);
    let outcomes = Mutex::new(BTreeMap::new());
    std::thread::scope(|scope| {
        for w in 0..workers {
            let work = tmp.path().join(format!("work{w}"));
            let (sets, next, end, failed, outcomes) = (&sets, &next, &end, &failed, &outcomes);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    if k >= end.load(Ordering::SeqCst) || failed.load(Ordering::SeqCst) {
                        break;
                    }
                    // A failed check stops the other threads too (its panic fails the test
                    // when the scope ends).
                    let outcome = catch_unwind(AssertUnwindSafe(|| kill_at(k, &work, sets)))
                        .unwrap_or_else(|panic| {
                            failed.store(true, Ordering::SeqCst);
                            resume_unwind(panic)
                        });
                    if matches!(outcome, Kill::Finished) {
                        end.fetch_min(k, Ordering::SeqCst);
                    }
                    outcomes.lock().unwrap().insert(k, outcome);
                }
            });
        }
    });
    let k = end.into_inner();
    assert!(k < LIMIT, "the run never finished");
    let outcomes = outcomes.into_inner().unwrap();
    let (mut committed_kills, mut kills_before_commit) = (0, 0);
    for kk in 0..k {
        match outcomes[&kk] {
            Kill::Finished => unreachable!("k = {kk} finished before the first finished run"),
            Kill::Killed { journal, no_report } => {
                kills_before_commit += usize::from(!journal);
                committed_kills += usize::from(no_report);
            }
        }
    }
    eprintln!(
        "{k} file operations: {kills_before_commit} kills before the commit, {committed_kills} during the install"
    );
    assert!(k > 10, "{k} file operations");
    assert!(
        committed_kills > 3,
        "{committed_kills} kills during the install"
    );
    assert!(
        kills_before_commit > 3,
        "{kills_before_commit} kills before the commit"
    );
}

#[test]
fn a_failed_write_leaves_the_old_set_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    ok(&lod(&work, "150,60,30", "1", None));
    std::fs::write(work.join("notes.txt"), b"the user's own file").unwrap();
    let before = visible_files(&work);
    for k in [0, 2, 4] {
        let run = lod(&work, "150,40", "2", Some(&format!("fail-after:{k}")));
        assert_eq!(run.status.code(), Some(1));
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains("no space left"), "{err}");
        assert_same(&visible_files(&work), &before, &format!("fail-after:{k}"));
        assert!(hidden(&work).is_empty(), "{:?}", hidden(&work));
    }
    // A run into a new folder that fails leaves no folder at all.
    let fresh = tmp.path().join("a/b/fresh");
    let run = lod(&fresh, "150", "1", Some("fail-after:1"));
    assert_eq!(run.status.code(), Some(1));
    assert!(!tmp.path().join("a").exists(), "no empty folders left");
}

#[test]
fn stale_temporary_files_and_stagings_of_dead_runs_are_cleared() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir_all(work.join(".frond-staging-sapling%999999999/shaders")).unwrap();
    std::fs::write(
        work.join(".frond-staging-sapling%999999999/sapling_LOD1.glb"),
        b"x",
    )
    .unwrap();
    // What frond 0.1's per-file writes left when killed.
    std::fs::write(work.join(".sapling_LOD2.glb.tmp-999999999"), b"half").unwrap();
    // Another tree's staging is not ours to clear.
    std::fs::create_dir_all(work.join(".frond-staging-oak%999999999")).unwrap();
    ok(&lod(&work, "150", "1", None));
    assert_eq!(hidden(&work), [".frond-staging-oak%999999999"]);
}

#[test]
fn a_live_run_of_the_same_tree_is_not_disturbed() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    // This test process is a live "frond" (see the module doc) staging the sample.
    let staging = work.join(format!(".frond-staging-sapling%{}", std::process::id()));
    std::fs::create_dir_all(&staging).unwrap();
    let run = lod(&work, "150", "1", None);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("another frond run"), "{err}");
    assert!(staging.exists());
}

#[test]
fn user_files_are_never_replaced() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir_all(&work).unwrap();
    // A file of the user's where frond would write: refused before any work, untouched.
    std::fs::write(work.join("sapling_LOD1.glb"), b"mine").unwrap();
    let run = lod(&work, "150", "1", None);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("sapling_LOD1.glb") && err.contains("never replaces"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(work.join("sapling_LOD1.glb")).unwrap(),
        b"mine"
    );
    assert_eq!(visible_files(&work).len(), 1);
    assert!(hidden(&work).is_empty());
}

#[test]
fn two_trees_share_a_folder_and_a_rerun_keeps_the_other_tree() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    let other = tmp.path().join("twin.glb");
    std::fs::copy(root().join(SAMPLE), &other).unwrap();
    let run = |input: &Path, lods: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_frond"))
            .arg("lod")
            .arg(input)
            .arg("-o")
            .arg(&work)
            .args(QUICK)
            .args(["--lods", lods])
            .args(["--animation", "vat"])
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .expect("runs");
        ok(&o);
    };
    run(&root().join(SAMPLE), "150,40");
    run(&other, "150,40");
    let both = visible_files(&work);
    assert!(both.contains_key("sapling_report.json") && both.contains_key("twin_report.json"));
    assert!(both.keys().any(|k| k.starts_with("shaders/")));
    // The sapling again with one LOD: its own extra files go, the twin's and the shared
    // shaders (which the twin's report lists) stay.
    run(&root().join(SAMPLE), "150");
    let after = visible_files(&work);
    assert!(!after.contains_key("sapling_LOD2.glb"));
    for (name, bytes) in &both {
        if name.starts_with("twin") || name.starts_with("shaders/") {
            assert_eq!(after.get(name), Some(bytes), "{name} kept");
        }
    }
}

#[test]
fn bad_output_folders_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("tree.glb");
    std::fs::copy(root().join(SAMPLE), &input).unwrap();
    let refuse = |out: &Path, why: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_frond"))
            .arg("lod")
            .arg(&input)
            .arg("-o")
            .arg(out)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(1), "{}", out.display());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(why), "{}: {err}", out.display());
        // Refused at once: no build progress, nothing sampled.
        assert!(!err.contains("LOD1"), "{err}");
    };
    refuse(Path::new("/"), "system folder");
    refuse(Path::new("/usr"), "system folder");
    refuse(&input, "input file");
    // A folder below a file cannot be made.
    refuse(&input.join("sub"), "cannot create the output folder");
    assert_eq!(
        std::fs::read(&input).unwrap(),
        std::fs::read(root().join(SAMPLE)).unwrap()
    );
}

#[test]
fn cloud_names_its_files_after_the_input_and_never_replaces_one() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("trees");
    std::fs::create_dir_all(&dir).unwrap();
    // The input is called cloud.glb and sits in the output folder.
    let input = dir.join("cloud.glb");
    std::fs::copy(root().join(SAMPLE), &input).unwrap();
    let cloud = |out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_frond"))
            .arg("cloud")
            .arg(&input)
            .args([
                "--epsilon",
                "5%",
                "--planes",
                "30",
                "--coverage-views",
                "0",
                "-o",
            ])
            .arg(out)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .expect("runs")
    };
    ok(&cloud(&dir));
    assert_eq!(
        std::fs::read(&input).unwrap(),
        std::fs::read(root().join(SAMPLE)).unwrap(),
        "the input is untouched"
    );
    let names: Vec<String> = visible_files(&dir).into_keys().collect();
    assert_eq!(
        names,
        [
            "cloud.glb",
            "cloud_atlas_color.png",
            "cloud_atlas_normal.png",
            "cloud_cloud.glb",
            "cloud_cloud_stats.json"
        ]
    );
    // Rerunning replaces its own set.
    ok(&cloud(&dir));
    // A user's file where the atlas would go: refused, untouched.
    let other = tmp.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("cloud_atlas_color.png"), b"mine").unwrap();
    let run = cloud(&other);
    assert_eq!(run.status.code(), Some(1));
    assert_eq!(
        std::fs::read(other.join("cloud_atlas_color.png")).unwrap(),
        b"mine"
    );
    assert_eq!(visible_files(&other).len(), 1);
}

#[test]
fn render_never_writes_over_its_input() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("tree.glb");
    std::fs::copy(root().join(SAMPLE), &input).unwrap();
    let p = input.to_str().unwrap();
    let out = frond(&["render", p, "-o", p]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("-o names the input file"), "{err}");
    assert_eq!(
        std::fs::read(&input).unwrap(),
        std::fs::read(root().join(SAMPLE)).unwrap()
    );
}

#[test]
fn a_set_written_by_frond_0_1_is_adopted_and_replaced() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    ok(&lod(&work, "150,60,30", "1", None));
    // What frond 0.1 left: `report.json` listing the files as `<-o>/<file>`.
    let mut report: frond_lod::LodReport = read_json(&work.join("sapling_report.json"));
    report.files = report
        .files
        .iter()
        .map(|f| {
            let f = f.replace("sapling_report.json", "report.json");
            work.join(f).display().to_string()
        })
        .collect();
    std::fs::write(
        work.join("report.json"),
        serde_json::to_string(&report).unwrap(),
    )
    .unwrap();
    std::fs::remove_file(work.join("sapling_report.json")).unwrap();
    ok(&lod(&work, "150", "1", None));
    // The shared shaders (the LOD cross-fade every chain ships) and the preview page with its
    // pictures and viewer (tests/preview_page.rs) aside.
    let names: Vec<String> = visible_files(&work)
        .into_keys()
        .filter(|n| {
            !n.starts_with("shaders/") && !n.starts_with("viewer/") && !n.contains("_preview")
        })
        .collect();
    assert_eq!(
        names,
        [
            "sapling_LOD0.glb",
            "sapling_LOD1.glb",
            "sapling_LOD1.mapping.json",
            "sapling_lods.glb",
            "sapling_report.json"
        ]
    );
}

/// A folder beside the output folder holding the files a planted journal or report aims at,
/// with their bytes, to check nothing outside `-o` was touched.
fn victims(dir: &Path) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let v = dir.join("victims");
    std::fs::create_dir_all(&v).unwrap();
    ["abs.txt", "rel.txt", "target.txt", "linked.glb"]
        .iter()
        .map(|n| {
            let p = v.join(n);
            std::fs::write(&p, format!("victim {n}")).unwrap();
            (p, format!("victim {n}").into_bytes())
        })
        .collect()
}

#[track_caller]
fn untouched(files: &[(std::path::PathBuf, Vec<u8>)]) {
    for (p, bytes) in files {
        assert_eq!(
            std::fs::read(p).ok().as_ref(),
            Some(bytes),
            "{} was changed",
            p.display()
        );
    }
}

#[test]
fn a_planted_journal_is_refused_whole_and_nothing_outside_is_touched() {
    let dir = tempfile::tempdir().unwrap();
    let files = victims(dir.path());
    let out = dir.path().join("out");
    // A killed run's staging folder, as a shared folder or an unpacked archive could hold it:
    // its journal removes an absolute path and a `../` one and installs over `../target.txt`.
    let staging = out.join(".frond-staging-sapling%999999");
    std::fs::create_dir_all(&staging).unwrap();
    std::fs::write(staging.join("target.txt"), b"planted").unwrap();
    let journal = serde_json::json!({
        "install": ["../victims/target.txt"],
        "remove": [files[0].0.to_str().unwrap(), "../victims/rel.txt"],
    });
    std::fs::write(
        staging.join("frond-commit.json"),
        serde_json::to_vec(&journal).unwrap(),
    )
    .unwrap();
    std::fs::write(out.join("mine.txt"), b"mine").unwrap();
    let o = lod(&out, "60", "1", None);
    assert_eq!(o.status.code(), Some(1), "refused");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("frond-commit.json") && err.contains("outside the output folder"),
        "{err}"
    );
    untouched(&files);
    assert_eq!(std::fs::read(out.join("mine.txt")).unwrap(), b"mine");
    assert!(
        staging.join("frond-commit.json").is_file(),
        "nothing changed"
    );
    // One bad entry among good ones refuses the whole journal.
    let journal = serde_json::json!({ "install": ["a.glb"], "remove": ["ok.glb", "/x/../y"] });
    std::fs::write(
        staging.join("frond-commit.json"),
        serde_json::to_vec(&journal).unwrap(),
    )
    .unwrap();
    std::fs::write(staging.join("a.glb"), b"staged").unwrap();
    assert_eq!(lod(&out, "60", "1", None).status.code(), Some(1));
    assert!(!out.join("a.glb").exists(), "nothing installed");
    // Removed by the user, the next run goes on.
    std::fs::remove_dir_all(&staging).unwrap();
    ok(&lod(&out, "60", "1", None));
    untouched(&files);
}

#[test]
fn links_out_of_the_output_folder_are_never_followed() {
    let dir = tempfile::tempdir().unwrap();
    let files = victims(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    // A staging folder that is a link to elsewhere: refused, not entered.
    let staging = out.join(".frond-staging-sapling%999999");
    std::os::unix::fs::symlink(dir.path().join("victims"), &staging).unwrap();
    let o = lod(&out, "60", "1", None);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("not a staging folder"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    untouched(&files);
    std::fs::remove_file(&staging).unwrap();
    // A report of this tree listing a file through a link out of the folder: the old set's
    // files are removed on the next run, that one is not.
    ok(&lod(&out, "60", "1", None));
    let report = out.join("sapling_report.json");
    let mut v: frond_lod::LodReport = read_json(&report);
    v.files.push("away/linked.glb".to_string());
    std::fs::write(&report, serde_json::to_vec(&v).unwrap()).unwrap();
    std::os::unix::fs::symlink(dir.path().join("victims"), out.join("away")).unwrap();
    ok(&lod(&out, "200", "1", None));
    untouched(&files);
}
