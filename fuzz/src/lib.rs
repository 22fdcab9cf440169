//! Shared code of frond's cargo-fuzz targets: the harnesses that import and sample one input
//! (`import_and_sample`) or run `frond lod` on it (`build_lods`), GLB splitting, and the
//! structure-aware mutator (`mutator`) used by `import_structured` and `lod_chain`.

pub mod mutator;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use frond_scene::gltf_writer::{encode_png, glb_container};
use frond_scene::{ImportOptions, SampleOptions, SceneError, import_bytes, sample};

/// Trees with more vertices than this are imported but not sampled (sampling is
/// samples × vertices; the importer's own bounds are what is under test).
const MAX_SAMPLED_VERTICES: usize = 1 << 20;
/// Upper bound on samples × (vertices + bones) per sampled clip.
const SAMPLE_WORK: usize = 1 << 22;

struct Env {
    /// The path every input is imported as: a file in a folder of small external resources
    /// (`buffer.bin`, `image.png`, `sub/inner.bin`, `escape.bin` → a file outside), so that
    /// relative URIs resolve to something, deterministically, and never to the fuzzer's cwd.
    path: PathBuf,
}

fn env() -> &'static Env {
    static ENV: OnceLock<Env> = OnceLock::new();
    ENV.get_or_init(|| {
        // One rayon worker: the importer and sampler use rayon, and the fuzzer must stay on
        // one core (and a fork-mode child must not multiply threads).
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global();
        let dir = std::env::temp_dir().join("frond-fuzz-ext");
        let _ = std::fs::create_dir_all(dir.join("sub"));
        let write = |name: &str, bytes: &[u8]| {
            let p = dir.join(name);
            if std::fs::metadata(&p).map(|m| m.len() as usize).ok() != Some(bytes.len()) {
                let tmp = dir.join(format!(".{name}.{}", std::process::id()).replace('/', "_"));
                if std::fs::write(&tmp, bytes).is_ok() {
                    let _ = std::fs::rename(&tmp, &p);
                }
            }
        };
        let pattern: Vec<u8> = (0..4096u32)
            .flat_map(|i| ((i % 97) as f32 * 0.25).to_le_bytes())
            .take(4096)
            .collect();
        write("buffer.bin", &pattern);
        write("sub/inner.bin", &pattern[..256]);
        write("image.png", &tiny_png(4, 4, 7));
        #[cfg(unix)]
        {
            let link = dir.join("escape.bin");
            if std::fs::symlink_metadata(&link).is_err() {
                let _ = std::os::unix::fs::symlink("/etc/hostname", &link);
            }
        }
        Env {
            path: dir.join("fuzz.glb"),
        }
    })
}

/// A small RGBA PNG with a deterministic pattern (alpha varies, so it looks like a leaf card).
pub fn tiny_png(w: u32, h: u32, seed: u32) -> Vec<u8> {
    let rgba: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let v = i.wrapping_mul(2654435761).wrapping_add(seed);
            [
                (v >> 8) as u8,
                0x80 | (v >> 16) as u8,
                (v >> 24) as u8,
                if i % 3 == 0 { 0 } else { 255 },
            ]
        })
        .collect();
    encode_png(w, h, &rgba).unwrap_or_default()
}

fn check_error(e: &SceneError, path: &Path) {
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}: ", path.display())),
        "error does not name the file: {msg}"
    );
}

/// Imports `bytes` as the harness's input file; an error must name the file (else a crash).
fn import_checked(bytes: &[u8], options: &ImportOptions) -> Option<frond_scene::Tree> {
    let path = env().path.as_path();
    match import_bytes(path, bytes, options) {
        Ok(tree) => Some(tree),
        Err(e) => {
            check_error(&e, path);
            None
        }
    }
}

/// Imports `bytes`; on success samples up to two clips with a bounded number of samples.
/// Panics (a fuzzer crash) only when the library panics or breaks a documented contract.
pub fn import_and_sample(bytes: &[u8]) {
    let path = env().path.as_path();
    let options = ImportOptions {
        allow_empty: true,
        ..ImportOptions::default()
    };
    let Some(tree) = import_checked(bytes, &options) else {
        return;
    };
    if tree.triangles.is_empty() {
        // The refusing path too (empty trees are an error by default).
        if let Err(e) = import_bytes(path, bytes, &ImportOptions::default()) {
            check_error(&e, path);
        }
    }
    let nv = tree.vertices.len();
    if nv > MAX_SAMPLED_VERTICES {
        return;
    }
    let samples = (SAMPLE_WORK / (nv + tree.bones.len() + 1)).clamp(1, 3);
    let mut clips: Vec<Option<String>> = vec![None];
    clips.extend(
        tree.rig.clips
            .iter()
            .skip(1)
            .take(1)
            .map(|c| Some(c.name.clone())),
    );
    for clip in clips {
        match sample(
            &tree,
            &SampleOptions {
                clip: clip.clone(),
                samples,
            },
        ) {
            Ok(s) => {
                assert_eq!(s.positions.len(), s.times.len() * nv, "positions layout");
                assert_eq!(
                    s.centres.len(),
                    s.foliage.len() * s.times.len(),
                    "centres layout"
                );
                assert_eq!(s.average.len(), nv, "average layout");
            }
            Err(e) => {
                check_error(&e, path);
            }
        }
    }
}

/// Vertex limit of the trees `build_lods` runs the chain on: small trees, so that one run
/// takes milliseconds (the importer's bounds are `import_and_sample`'s to test).
const LOD_MAX_VERTICES: u64 = 20_000;

/// The methods `build_lods` picks from, by the input's hash.
const LOD_METHODS: [&str; 6] = ["auto", "cards", "per-bone", "static", "spectral", "skeleton"];

/// What `build_lods` keeps between runs: the renderer (made once: starting a GPU adapter takes
/// far longer than a run) and the output folder.
struct LodEnv {
    renderer: frond_render::Renderer,
    out: PathBuf,
}

fn lod_env() -> &'static LodEnv {
    static LOD: OnceLock<LodEnv> = OnceLock::new();
    LOD.get_or_init(|| {
        env();
        let out = std::env::temp_dir().join(format!("frond-fuzz-lod-{}", std::process::id()));
        LodEnv {
            renderer: frond_render::Renderer::new().expect("a renderer (GPU or llvmpipe)"),
            out,
        }
    })
}

/// Runs `frond lod` on `bytes` as a small tree would be: imported with the default limits (and
/// at most [`LOD_MAX_VERTICES`] vertices), one of [`LOD_METHODS`] chosen by the input's hash,
/// two LODs, 8 samples, 30 candidate planes, written as an output set into a temporary folder
/// (measuring and the preview off: they render, which the chain's tests cover). Panics (a
/// fuzzer crash) only when frond panics, or when an import error does not name the input.
pub fn build_lods(bytes: &[u8]) {
    let lod = lod_env();
    let options = ImportOptions {
        limits: frond_scene::InputLimits {
            max_vertices: LOD_MAX_VERTICES,
            ..Default::default()
        },
        ..ImportOptions::default()
    };
    let Some(tree) = import_checked(bytes, &options) else {
        return;
    };
    let hash = bytes
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    let method = LOD_METHODS[(hash % LOD_METHODS.len() as u64) as usize];
    let out = lod.out.to_str().unwrap_or("/tmp/frond-fuzz-lod");
    let args = [
        "lod", "fuzz.glb", "-o", out, "--method", method, "--lods", "200,60", "--samples", "8",
        "--planes", "30", "--no-measure", "--no-preview",
    ];
    let request = frond::cli::lod::LodArgs::parse_from(args)
        .expect("the harness's own arguments parse")
        .settings()
        .request(&tree);
    // A refusal (a budget, a tree no method can build) is an answer; only a panic or an
    // out-of-memory is a finding.
    let _ = request.and_then(|req| {
        frond_app::lod_cmd::run_lod(&lod.renderer, &tree, &req, &lod.out, &|_| {})
    });
}

/// Splits a GLB into its JSON chunk and (if present) its BIN chunk; None if the container
/// header or the JSON chunk header is malformed.
pub fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Option<Vec<u8>>)> {
    let u32_at = |i: usize| -> Option<usize> {
        Some(u32::from_le_bytes(bytes.get(i..i + 4)?.try_into().ok()?) as usize)
    };
    if !bytes.starts_with(b"glTF") || bytes.get(16..20)? != b"JSON" {
        return None;
    }
    let jl = u32_at(12)?;
    let json = bytes.get(20..20usize.checked_add(jl)?)?.to_vec();
    let rest = &bytes[20 + jl..];
    let bin = if rest.len() >= 8 && &rest[4..8] == b"BIN\0" {
        let bl = u32::from_le_bytes(rest[0..4].try_into().ok()?) as usize;
        Some(rest[8..8 + bl.min(rest.len() - 8)].to_vec())
    } else {
        None
    };
    Some((json, bin))
}

/// A GLB of `json` and `bin` (no BIN chunk when `bin` is None or empty).
pub fn join_glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    glb_container(json, bin.unwrap_or(&[]))
}
