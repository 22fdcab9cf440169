//! Where frond's tests and benches find their trees (dev-only, never published).
//!
//! Two kinds of data:
//!
//! - **Fixtures** that travel with the repository: `samples/sapling.glb` ([`sample`]) and the
//!   small real-exporter trees under `tests/fixtures/` ([`fixture`]). Always there.
//! - **Shared trees**: the large third-party trees (and their `MANIFEST.json`, `_meta/`) kept
//!   outside the repository. One setting finds them: the environment variable
//!   [`FROND_TEST_TREES`](ENV), by default `<workspace root>/../shared/data/trees`
//!   ([`trees_dir`]). A fresh clone has no such folder, so every test that needs one of them
//!   starts with [`require_tree!`] (or [`require_trees!`]): when the file is absent, it prints
//!   one line to stderr, `skipped: <test>: shared tree <name> not found in <dir> (set
//!   FROND_TEST_TREES)`, and returns from the test (which then counts as passed).
//!
//! The skip line is written to the process's stderr directly, not through `eprintln!`, so that
//! libtest's output capture does not swallow it: it shows in a plain `cargo test` run, and
//! `grep -c '^skipped: '` counts the skipped tests.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The environment variable naming the folder of the shared trees.
pub const ENV: &str = "FROND_TEST_TREES";

/// The workspace root (the folder holding the workspace `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("testdata/ sits in the workspace root")
        .to_path_buf()
}

/// The folder of the shared trees: `$FROND_TEST_TREES` when set (and not empty), else
/// `<workspace root>/../shared/data/trees`. A relative `$FROND_TEST_TREES` is taken from the
/// workspace root (cargo runs each crate's tests in that crate's own folder, so the current
/// directory would differ between crates). The folder need not exist.
pub fn trees_dir() -> PathBuf {
    match std::env::var_os(ENV) {
        Some(dir) if !dir.is_empty() => workspace_root().join(dir),
        _ => workspace_root().join("../shared/data/trees"),
    }
}

/// Every shared tree (`MANIFEST.json`'s files), by file name.
pub const SHARED_TREES: [&str; 7] = [
    "bush_1.glb",
    "oak_dense.glb",
    "oak_large.glb",
    "oak_medium.glb",
    "oak_medium_blendedleaves.glb",
    "pine_medium.glb",
    "pine_medium_blender.glb",
];

/// Calls `f` with the name and path of every shared tree present ([`SHARED_TREES`]), and
/// reports each absent one as skipped by the test `what` (one line each).
pub fn each_shared_tree(what: &str, mut f: impl FnMut(&str, PathBuf)) {
    for name in SHARED_TREES {
        match tree(name) {
            Some(path) => f(name, path),
            None => report_skip(what, &[name.to_string()]),
        }
    }
}

/// The shared tree (or other shared file, e.g. `MANIFEST.json`, `_meta/x.structure.json`)
/// `name` in [`trees_dir`], or `None` when the folder or the file is absent.
pub fn tree(name: &str) -> Option<PathBuf> {
    let path = trees_dir().join(name);
    path.is_file().then_some(path)
}

/// Every one of `names` in [`trees_dir`], in order; or, when any is absent, the names of those
/// that are.
pub fn trees<I, S>(names: I) -> Result<Vec<PathBuf>, Vec<String>>
where
    I: IntoIterator<Item = S>,
    S: AsRef<str>,
{
    let (mut found, mut missing) = (Vec::new(), Vec::new());
    for name in names {
        match tree(name.as_ref()) {
            Some(path) => found.push(path),
            None => missing.push(name.as_ref().to_string()),
        }
    }
    if missing.is_empty() {
        Ok(found)
    } else {
        Err(missing)
    }
}

/// `tests/fixtures/<name>`: a small tree committed with the repository (see
/// `tests/fixtures/README.md`).
pub fn fixture(name: &str) -> PathBuf {
    workspace_root().join("tests/fixtures").join(name)
}

/// `samples/sapling.glb`, the bundled generated tree.
pub fn sample() -> PathBuf {
    workspace_root().join("samples/sapling.glb")
}

/// The environment variable that lets the heavy cases run: the benchmark tree, long fuzz runs,
/// timings. A plain `cargo test` (a debug build) leaves them out; `.ci/run` sets it for its
/// optimised run of just those cases (tests named `heavy_*`).
pub const HEAVY: &str = "FROND_HEAVY_TESTS";

/// True when [`HEAVY`] is set (to anything but empty or `0`); else prints one
/// `skipped: <crate>::<test>: heavy case (…)` line for the running test (named after libtest's
/// thread for it, in the test binary `crate_name`; straight to stderr, past libtest's capture,
/// like the other skip lines), which then returns.
pub fn heavy(crate_name: &str) -> bool {
    use std::io::Write;
    if std::env::var_os(HEAVY).is_some_and(|v| !v.is_empty() && v != "0") {
        return true;
    }
    let line = format!(
        "skipped: {crate_name}::{}: heavy case, left to the optimised run (set {HEAVY}=1; \
         bash .ci/run runs it)\n",
        std::thread::current().name().unwrap_or("main")
    );
    // Nothing sensible to do when stderr is gone; the test still skips.
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
    false
}

/// The line printed when `what` (a test or bench name) is skipped because the shared files
/// `missing` are absent: `skipped: <what>: shared tree <names> not found in <dir> (set
/// FROND_TEST_TREES)`.
pub fn skip_line(what: &str, missing: &[String]) -> String {
    let noun = if missing.len() == 1 { "tree" } else { "trees" };
    format!(
        "skipped: {what}: shared {noun} {} not found in {} (set {ENV})",
        missing.join(", "),
        trees_dir().display()
    )
}

/// Prints [`skip_line`] to stderr, bypassing libtest's output capture (one write of one line).
pub fn report_skip(what: &str, missing: &[String]) {
    let line = format!("{}\n", skip_line(what, missing));
    // Nothing sensible to do when stderr is gone; the test still skips.
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

/// The name of the function that `here` (a function item declared inside it) belongs to,
/// `<crate>::<path>::<fn>`, without closure segments. Used by [`require_trees!`].
#[doc(hidden)]
pub fn enclosing_fn<F>(here: F) -> String {
    let name = std::any::type_name_of_val(&here);
    let name = name.strip_suffix("::__frond_here").unwrap_or(name);
    name.split("::")
        .filter(|segment| *segment != "{{closure}}")
        .collect::<Vec<_>>()
        .join("::")
}

/// The path of every shared file named, as `Vec<PathBuf>`; when any is absent, prints one
/// `skipped:` line naming all absent ones (see [`report_skip`]) and returns from the enclosing
/// test function. Takes one iterable of names (`require_trees!(["a.glb", "b.glb"])`).
#[macro_export]
macro_rules! require_trees {
    ($names:expr) => {
        match $crate::trees($names) {
            Ok(paths) => paths,
            Err(missing) => {
                fn __frond_here() {}
                $crate::report_skip(&$crate::enclosing_fn(__frond_here), &missing);
                return;
            }
        }
    };
}

/// The path of the shared file `name` (e.g. `require_tree!("oak_medium.glb")`); when it is
/// absent, prints one `skipped:` line and returns from the enclosing test function.
#[macro_export]
macro_rules! require_tree {
    ($name:expr) => {
        $crate::require_trees!([$name])
            .pop()
            .expect("one path per name")
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixtures_and_the_sample_travel_with_the_repository() {
        for name in ["bush_1.glb", "sapling_blender.glb", "README.md"] {
            assert!(fixture(name).is_file(), "{name}");
        }
        assert!(sample().is_file());
        assert!(workspace_root().join("Cargo.toml").is_file());
    }

    #[test]
    fn absent_trees_are_none_and_named() {
        assert_eq!(tree("no such tree.glb"), None);
        assert_eq!(
            trees(["no such tree.glb", "nor this.glb"]),
            Err(vec![
                "no such tree.glb".to_string(),
                "nor this.glb".to_string()
            ])
        );
        assert_eq!(trees(Vec::<String>::new()), Ok(Vec::new()));
    }

    #[test]
    fn the_skip_line_names_the_test_the_trees_the_folder_and_the_setting() {
        let one = skip_line("t", &["a.glb".into()]);
        assert!(
            one.starts_with("skipped: t: shared tree a.glb not found in "),
            "{one}"
        );
        assert!(one.ends_with(" (set FROND_TEST_TREES)"), "{one}");
        assert!(one.contains(&trees_dir().display().to_string()), "{one}");
        let two = skip_line("t", &["a.glb".into(), "b.glb".into()]);
        assert!(two.contains("shared trees a.glb, b.glb not found"), "{two}");
        assert_eq!(two.lines().count(), 1);
    }

    /// Returns early through `require_tree!` before setting `reached`.
    fn skips(reached: &mut bool) {
        let _path = crate::require_tree!("no such tree.glb");
        *reached = true;
    }

    #[test]
    fn require_tree_returns_from_the_enclosing_function() {
        let mut reached = false;
        skips(&mut reached);
        assert!(!reached);
        fn __frond_here() {}
        assert_eq!(
            enclosing_fn(__frond_here),
            "frond_testdata::tests::require_tree_returns_from_the_enclosing_function"
        );
        let from_closure = || {
            fn __frond_here() {}
            enclosing_fn(__frond_here)
        };
        assert_eq!(
            from_closure(),
            "frond_testdata::tests::require_tree_returns_from_the_enclosing_function"
        );
    }
}
