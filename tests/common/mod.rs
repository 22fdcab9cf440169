//! Helpers shared by the end-to-end tests: paths to the shared trees, running the CLI, and the
//! real glTF clients (Khronos validator, gltfpack) installed into `tools/node_modules`.
//!
//! The large shared trees are found through `frond_testdata` (`FROND_TEST_TREES`); a test that
//! needs one starts with `frond_testdata::require_tree!`, which skips it with one line when the
//! tree is absent. Fixtures that travel with the repository: [`fixture`], `samples/`.

pub mod gltf_cases;
pub mod hostile;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

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
pub fn frond_lod(input: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["--planes", "60", "--no-measure", "--no-preview"];
    args.extend_from_slice(extra);
    frond_lod_measured(input, out, &args)
}

/// The 600 px LOD of `tree` at ε = 0 with the per-bone method (every billboard one card), its
/// error measured; returns the report. The cost budgets are off: at ε = 0 a LOD keeps a
/// billboard per card, more than half the input's triangles, and the budgets would widen ε
/// (they come first); the LOD's texel density (4 texels per pixel for alpha-tested maps) still
/// applies.
pub fn per_bone_at_zero(tree: &Path, out: &Path) -> serde_json::Value {
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
pub fn frond_lod_measured(input: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
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
    let report = out.join(format!("{stem}_report.json"));
    serde_json::from_slice(&std::fs::read(&report).expect("the lod report"))
        .expect("report is JSON")
}

/// Runs `frond eval ORIGINAL CANDIDATE --json` plus `extra`, asserts it succeeded and returns
/// its JSON report.
pub fn frond_eval(original: &Path, candidate: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "eval",
        original.to_str().expect("utf-8"),
        candidate.to_str().expect("utf-8"),
        "--json",
    ];
    args.extend_from_slice(extra);
    let out = frond_ok(&args);
    serde_json::from_slice(&out.stdout).expect("JSON report")
}

/// Installs the Node tools once (npm install into tools/node_modules) and returns the folder:
/// the validator, gltfpack, three.js and puppeteer-core (drives Debian's Chromium). Installs whenever one of them is missing (a
/// tools/node_modules made before a package joined package.json lacks it).
pub fn node_tools() -> PathBuf {
    static READY: OnceLock<PathBuf> = OnceLock::new();
    READY
        .get_or_init(|| {
            let tools = root().join("tools");
            let packages = ["gltf-validator", "gltfpack", "three", "puppeteer-core"];
            let missing = |tools: &Path| {
                packages.iter().any(|p| {
                    !tools
                        .join("node_modules")
                        .join(p)
                        .join("package.json")
                        .exists()
                })
            };
            if missing(&tools) {
                let status = Command::new("npm")
                    .args(["install", "--no-audit", "--no-fund", "--prefix"])
                    .arg(&tools)
                    .status()
                    .expect("npm is installed (needed for the glTF validator, gltfpack, three.js)");
                assert!(status.success(), "npm install in tools/ failed");
                assert!(
                    !missing(&tools),
                    "{packages:?} not all in tools/node_modules after npm install"
                );
            }
            tools
        })
        .clone()
}

/// Runs the Khronos glTF validator on `file`; returns its JSON summary.
pub fn validate(file: &Path) -> serde_json::Value {
    let tools = node_tools();
    let out = Command::new("node")
        .arg(tools.join("validate.mjs"))
        .arg(file)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "validator output is not JSON ({e}): {text} {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
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
        per_bone_at_zero,
        frond_eval,
        node_tools,
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
