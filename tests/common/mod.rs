//! Helpers shared by the end-to-end tests: paths to the shared trees, running the CLI, and the
//! real glTF clients (Khronos validator, gltfpack, three.js) that `.ci/run` installs into
//! `tools/node_modules`.
//!
//! The large shared trees are found through `frond_testdata` (`FROND_TEST_TREES`); a test that
//! needs one starts with `frond_testdata::require_tree!`, which skips it with one line when the
//! tree is absent. Fixtures that travel with the repository: [`fixture`], `samples/`.
//!
//! Tools outside Rust (the Node clients, Godot, Chromium, glslang) are not needed either: a test
//! that needs a missing one prints one `skipped: <test>: <tool> not installed (…)` line
//! ([`report_not_installed`]) and skips what needs it; `.ci/run` installs them all.

pub mod gltf_cases;
pub mod hostile;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use frond_lod::methods::cards::CardReport;
use frond_lod::methods::spectral::SpectralReport;
use frond_lod::{LodEntry, LodReport};
use frond_metrics::EvalReport;
use frond_skeleton::sbcs::SkeletonReport;
use serde::de::DeserializeOwned;

/// The workspace root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `<name>` in the shared trees' folder (`$FROND_TEST_TREES`, default `../shared/data/trees`),
/// whether or not it is there: tests check with `frond_testdata::require_tree!` first.
pub fn shared_tree(name: &str) -> PathBuf {
    frond_testdata::trees_dir().join(name)
}

/// The shared MANIFEST.json (tests check with `require_tree!("MANIFEST.json")` first).
pub fn manifest() -> serde_json::Value {
    let text = std::fs::read_to_string(shared_tree("MANIFEST.json"))
        .expect("shared MANIFEST.json is readable");
    serde_json::from_str(&text).expect("MANIFEST.json is JSON")
}

/// `tests/fixtures/<name>`: a small tree committed with the repository.
pub fn fixture(name: &str) -> PathBuf {
    frond_testdata::fixture(name)
}

/// Runs the `frond` binary.
pub fn frond(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_frond"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("frond runs")
}

/// Runs the `frond` binary and asserts it succeeded (showing its stderr otherwise).
pub fn frond_ok(args: &[&str]) -> Output {
    let out = frond(args);
    assert!(
        out.status.success(),
        "frond {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `frond lod INPUT -o OUT` with small test settings (16 samples, 60 candidate planes, no
/// error measurement: `tests/lod_error.rs` tests that; no preview page: `tests/preview_page.rs`
/// does) plus `extra`, asserts it succeeded and
/// returns its report (`<input stem>_report.json`).
pub fn frond_lod(input: &Path, out: &Path, extra: &[&str]) -> LodReport {
    let mut args = vec!["--planes", "60", "--no-measure", "--no-preview"];
    args.extend_from_slice(extra);
    frond_lod_measured(input, out, &args)
}

/// The far LOD of `report`, checked to be `auto`'s far end: an impostor-class LOD built by
/// `spectral-axis-phase` (one motion per FFT cluster), the reason saying so.
pub fn far_end_of_auto(report: &LodReport) -> &LodEntry {
    let far = report.lods.last().expect("the far LOD");
    assert_eq!(
        far.method.name(),
        "spectral-axis-phase",
        "{}",
        far.method_reason
    );
    assert!(
        far.method_reason.contains("impostor"),
        "{}",
        far.method_reason
    );
    far
}

/// The 600 px LOD of `tree` at ε = 0 with the per-bone method (every billboard one card), its
/// error measured; returns the report. The cost budgets are off: at ε = 0 a LOD keeps a
/// billboard per card, more than half the input's triangles, and the budgets would widen ε
/// (they come first); the LOD's texel density (4 texels per pixel for alpha-tested maps) still
/// applies.
pub fn per_bone_at_zero(tree: &Path, out: &Path) -> LodReport {
    frond_lod_measured(
        tree,
        out,
        &[
            "--method",
            "per-bone",
            "--epsilon",
            "0",
            "--lods",
            "600",
            "--no-cost-budgets",
        ],
    )
}

/// Runs `frond lod INPUT -o OUT --samples 16` plus `extra`, each LOD's error measured (unless
/// `extra` says `--no-measure`), asserts it succeeded and returns its report.
pub fn frond_lod_measured(input: &Path, out: &Path, extra: &[&str]) -> LodReport {
    let mut args = vec![
        "lod",
        input.to_str().expect("utf-8 path"),
        "-o",
        out.to_str().expect("utf-8 path"),
        "--samples",
        "16",
    ];
    args.extend_from_slice(extra);
    frond_ok(&args);
    let stem = input
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("utf-8 stem");
    lod_report(out, stem)
}

/// `<name>_report.json` in `dir`: the report `frond lod` wrote for a tree named `name`.
pub fn lod_report(dir: &Path, name: &str) -> LodReport {
    read_json(&dir.join(format!("{name}_report.json")))
}

/// The JSON file at `path` read as a `T` (a report or sidecar frond wrote), naming the file
/// when it is missing or does not read as one.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> T {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_slice(&bytes).unwrap_or_else(|e| {
        panic!(
            "{} does not read as {}: {e}",
            path.display(),
            std::any::type_name::<T>()
        )
    })
}

/// JSON text (a command's `--json` output) read as a `T`.
pub fn parse_json<T: DeserializeOwned>(bytes: &[u8]) -> T {
    serde_json::from_slice(bytes).unwrap_or_else(|e| {
        panic!(
            "{} does not read as {}: {e}",
            String::from_utf8_lossy(bytes),
            std::any::type_name::<T>()
        )
    })
}

/// The number a JSON reader gets from `x` as frond writes it (the shortest decimal that reads
/// back as `x`), for comparing a report's `f32` exactly with a number from another file.
pub fn written_f64(x: f32) -> f64 {
    x.to_string().parse().expect("a float's text reads back")
}

/// The `spectral` section of a LOD entry (a spectral method's), if it has one.
pub fn spectral_section(entry: &LodEntry) -> Option<SpectralReport> {
    section(entry, "spectral")
}

/// The `skeleton` section of a LOD entry (a skeleton method's), if it has one.
pub fn skeleton_section(entry: &LodEntry) -> Option<SkeletonReport> {
    section(entry, "skeleton")
}

/// The `cards` section of a LOD entry (the cards method's), if it has one.
pub fn cards_section(entry: &LodEntry) -> Option<CardReport> {
    section(entry, "cards")
}

/// The section `key` of a LOD entry read as a `T`, if the entry has one.
pub fn section<T: DeserializeOwned>(entry: &LodEntry, key: &str) -> Option<T> {
    entry
        .sections
        .typed::<T>(key)
        .map(|r| r.unwrap_or_else(|e| panic!("the {key} section: {e}")))
}

/// Runs `frond eval ORIGINAL CANDIDATE --json` plus `extra`, asserts it succeeded and returns
/// its JSON report.
pub fn frond_eval(original: &Path, candidate: &Path, extra: &[&str]) -> EvalReport {
    let mut args = vec![
        "eval",
        original.to_str().expect("utf-8"),
        candidate.to_str().expect("utf-8"),
        "--json",
    ];
    args.extend_from_slice(extra);
    let out = frond_ok(&args);
    parse_json(&out.stdout)
}

/// The running test's name as the shared trees' skip lines give it, `<test binary>::<test>`
/// (libtest runs each test on a thread named after its path in the binary).
pub fn test_name() -> String {
    let thread = std::thread::current();
    format!(
        "{}::{}",
        env!("CARGO_CRATE_NAME"),
        thread.name().unwrap_or("main")
    )
}

/// Says on stderr that the running test skips for want of `what` (a tool, or files a tool
/// needs), in the shared trees' form: `skipped: <test>: <what> not installed (<how>)`, or
/// `skipped: <test> (<step> only): …` when the test skips one step and checks everything else.
/// One line per test, however often it is called: a test whose every file would go through the
/// missing tool says so once. Written to the process's stderr directly, past libtest's output
/// capture (like `frond_testdata::report_skip`), so a plain `cargo test` shows it.
pub fn report_not_installed(step: Option<&str>, what: &str, how: &str) {
    use std::io::Write;
    thread_local! {
        static REPORTED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    if REPORTED.replace(true) {
        return;
    }
    let step = step.map(|s| format!(" ({s} only)")).unwrap_or_default();
    let line = format!(
        "skipped: {}{step}: {what} not installed ({how})\n",
        test_name()
    );
    // Nothing sensible to do when stderr is gone; the test still skips.
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

/// Whether the heavy cases run ([`frond_testdata::heavy`]); else one skip line for the
/// running test.
pub fn heavy() -> bool {
    frond_testdata::heavy(env!("CARGO_CRATE_NAME"))
}

/// The Node packages the tests drive from `tools/` (tools/package.json): the Khronos glTF
/// validator, gltfpack, three.js and puppeteer-core (which drives Debian's Chromium).
const NODE_PACKAGES: [&str; 4] = ["gltf-validator", "gltfpack", "three", "puppeteer-core"];

/// `tools/`, when `node` is on `PATH` and every one of [`NODE_PACKAGES`] is installed in
/// `tools/node_modules`; else what is missing and how to install it, for the skip line. The tests never install them
/// (a fresh clone's `cargo test` needs no network beyond the crate registry): `.ci/run` runs
/// `npm ci` in `tools/` before the tests.
fn find_node_tools() -> Result<PathBuf, (String, &'static str)> {
    let tools = root().join("tools");
    if !on_path("node") {
        return Err((
            "node (Node.js, which runs the glTF clients in tools/)".to_string(),
            "apt-get install nodejs npm, then npm ci in tools/; bash .ci/run does both",
        ));
    }
    let missing: Vec<&str> = NODE_PACKAGES
        .into_iter()
        .filter(|p| {
            !tools
                .join("node_modules")
                .join(p)
                .join("package.json")
                .is_file()
        })
        .collect();
    if missing.is_empty() {
        Ok(tools)
    } else {
        Err((
            format!("{} in tools/node_modules", missing.join(", ")),
            "npm ci in tools/, as bash .ci/run does",
        ))
    }
}

/// The `tools/` folder with the Node clients installed, or `None` after one `skipped:` line
/// ([`report_not_installed`]) for the running test, which then returns: for a test that is
/// all about a client (a missing client skips all of it).
pub fn node_tools() -> Option<PathBuf> {
    node_tools_for(None)
}

/// [`node_tools`] for one step of a test (`step`, e.g. "the Khronos glTF validator checks"):
/// when the clients are missing the skip line names the step, and the test goes on checking
/// frond's own behaviour without it.
pub fn node_tools_for(step: Option<&str>) -> Option<PathBuf> {
    static FOUND: OnceLock<Result<PathBuf, (String, &'static str)>> = OnceLock::new();
    match FOUND.get_or_init(find_node_tools) {
        Ok(tools) => Some(tools.clone()),
        Err((missing, how)) => {
            report_not_installed(step, missing, how);
            None
        }
    }
}

/// Runs the Khronos glTF validator on `file`; returns its JSON summary, or `None` (one
/// `skipped:` line for the test, naming the validator step) when the Node clients are not
/// installed: the caller skips its validator assertions and checks the rest.
pub fn validate(file: &Path) -> Option<serde_json::Value> {
    let tools = node_tools_for(Some("the Khronos glTF validator checks"))?;
    let out = Command::new("node")
        .arg(tools.join("validate.mjs"))
        .arg(file)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    Some(serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "validator output is not JSON ({e}): {text} {}",
            String::from_utf8_lossy(&out.stderr)
        )
    }))
}

/// The JSON of a glTF file (`.gltf`, or a GLB's JSON chunk).
pub fn gltf_json(path: &Path) -> serde_json::Value {
    let bytes = std::fs::read(path).expect("read glTF");
    let json = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
        assert_eq!(&bytes[16..20], b"JSON", "first GLB chunk is JSON");
        &bytes[20..20 + len]
    } else {
        &bytes[..]
    };
    serde_json::from_slice(json).expect("glTF JSON")
}

/// The Chromium to drive: `FROND_CHROMIUM`, else the first of Debian's and Google's names on
/// `PATH`.
pub fn chromium() -> Option<String> {
    if let Ok(c) = std::env::var("FROND_CHROMIUM") {
        return Some(c);
    }
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| on_path(c))
        .map(|c| {
            std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
                .map(|d| d.join(c))
                .find(|p| p.is_file())
                .map_or_else(|| c.to_string(), |p| p.display().to_string())
        })
}

/// [`chromium`] and the Node clients that drive it ([`node_tools`]), or `None` after one
/// `skipped:` line for the running test when either is missing.
pub fn chromium_and_node_tools() -> Option<(String, PathBuf)> {
    let Some(chromium) = chromium() else {
        report_not_installed(
            None,
            "chromium",
            "apt-get install chromium, as bash .ci/run does, or set FROND_CHROMIUM",
        );
        return None;
    };
    Some((chromium, node_tools()?))
}

/// `name` is an executable file in a `PATH` folder.
pub fn on_path(name: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|path| {
        std::env::split_paths(&path).any(|dir| {
            let file = dir.join(name);
            std::fs::metadata(&file).is_ok_and(|m| {
                use std::os::unix::fs::PermissionsExt;
                m.is_file() && m.permissions().mode() & 0o111 != 0
            })
        })
    })
}

/// `frond view FOLDER --port 0 --no-open` while it lives (stopped on drop).
pub struct ViewServer {
    child: std::process::Child,
    url: String,
}

impl ViewServer {
    /// The page's URL, the first line `frond view` prints.
    pub fn url(&self) -> &str {
        &self.url
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `frond view` on `folder` (any free port) and reads the URL it prints.
pub fn frond_view(folder: &Path) -> ViewServer {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_frond"))
        .args([
            "view",
            folder.to_str().expect("utf-8"),
            "--port",
            "0",
            "--no-open",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("frond view starts");
    let mut stdout = child.stdout.take().expect("stdout");
    let mut line = Vec::new();
    let mut byte = [0u8; 1];
    while stdout.read(&mut byte).expect("reads") == 1 && byte[0] != b'\n' {
        line.push(byte[0]);
    }
    ViewServer {
        child,
        url: String::from_utf8(line).expect("utf-8 URL"),
    }
}

/// Where a test leaves files for people to look at (screenshots, renders):
/// `target/test-artefacts/<name>/`, made empty.
pub fn artefact_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target/tmp has a parent")
        .join("test-artefacts")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("artefact folder");
    dir
}

// Each test binary compiles this module on its own (`mod common;`) and uses only some of the
// helpers, and the dead_code lint runs per binary. Instead of a lint exception (a bare `allow`
// is against house rules, and `#![expect(dead_code)]` fails in any binary that happens to use
// every helper), this unnamed constant names each helper once: rustc's dead-code pass treats
// `const _` items as always used, so whatever they name is used too. A new helper (here or in
// a submodule) goes in this list.
const _: () = {
    let _ = (
        root,
        shared_tree,
        manifest,
        fixture,
        frond,
        frond_ok,
        frond_lod,
        frond_lod_measured,
        far_end_of_auto,
        per_bone_at_zero,
        frond_eval,
        lod_report,
        read_json::<serde_json::Value>,
        parse_json::<serde_json::Value>,
        written_f64,
        spectral_section,
        skeleton_section,
        cards_section,
        section::<serde_json::Value>,
        test_name,
        report_not_installed,
        heavy,
        node_tools,
        node_tools_for,
        validate,
        gltf_json,
        on_path,
        artefact_dir,
        frond_view,
        ViewServer::url,
        gltf_cases::triangle_gltf,
        gltf_cases::triangle_bin,
        gltf_cases::GOOD,
        gltf_cases::write_case,
        hostile::Glb::read,
        hostile::Glb::sample,
        hostile::Glb::write,
        hostile::Glb::add_image,
        hostile::Glb::add_ktx2,
        hostile::Glb::set_map,
        hostile::Glb::attribute,
        hostile::Glb::accessor_offset,
        hostile::png_header_only,
        hostile::png_solid,
        hostile::ktx2_solid,
        hostile::ktx2_header_only,
        hostile::frond_measured,
        hostile::Measured::stderr,
        hostile::Measured::summary,
    );
};
