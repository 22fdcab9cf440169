//! Godot 3 reads frond's LOD chains: every LOD file goes through Godot's own glTF importer (the
//! editor's, with its default import settings; Debian's `godot3`, 3.2.x, headless under
//! `xvfb-run`), is loaded as a game loads it, and Godot's view of it is checked: one Skeleton
//! with bones, an AnimationPlayer holding the clip at the input clip's length (looping exactly
//! when the clip's name carries Godot 3's `-loop` / `_loop` import hint), every material as the
//! glTF says (foliage alpha-scissored at its cutoff, or transparent where the far end is blended,
//! double-sided foliage not culled, base colour and normal textures present, at the file's image
//! sizes), and nothing printed as an error. Then Godot renders the posed tree (the clip paused at
//! time 0 and at 0.325 of the period) with `frond render`'s camera, and its silhouettes are
//! compared with frond's renders of the same file at the same times (a blended pixel counts once
//! its alpha shows against the background: `BLENDED_SHOWS`). Lit by Godot's light, every LOD's
//! mean colour stays within 0.02 of LOD0's (`check_lit_colour`; a blended LOD's pixels unmixed
//! from the background with frond's alpha).
//!
//! The Godot side is `tests/godot/run.sh` (the project, editor plugin and scripts are in
//! `tests/godot/project/`); it prints one JSON line per file. Skips (one `skipped:` line) when
//! `godot3` or `xvfb-run` is not installed; CI installs both (`.ci/run`).
//!
//! What Godot 3.2 does with these files that the assertions tolerate, each measured:
//! - Import prints `ERROR: free_static: Condition "p_ptr == __null" is true.` about four times
//!   per animation track, for any animated glTF (Blender's exports alike; a triangle without
//!   animation prints it twice): Godot's own noise, filtered out (`GODOT_NOISE`).
//! - Godot 3.2 ignores glTF samplers: every texture repeats and is mipmapped with a plain box
//!   filter. frond render samples level 0 with the file's CLAMP_TO_EDGE for foliage. So Godot
//!   also renders the frame with the textures sampled as frond samples them (mipmaps off, foliage
//!   not repeated), and that frame must match frond's closely; the frame as imported only
//!   loosely (see `Silhouette` and the tolerances where they are used).
//! - Godot 3.2 bakes glTF animation at its import FPS (default 15) and interpolates linearly
//!   between those keys; frond's clips have more keys (pine: 24/s, sapling: 30/s), so between
//!   keys Godot's pose drifts from the file's. Measured on the pine at 1.3 s: silhouette IoU
//!   0.873-0.944 with the default import, 0.997-1.000 imported at 60 FPS (the import's key
//!   optimizer changes nothing measurable); at time 0 (a key) it is exact.
//! - Godot 3.2's glTF importer keeps two UV sets (TEXCOORD_0, _1) and drops TEXCOORD_2/3, where a
//!   VAT LOD carries the rest pivots: the shipped Godot 3 VAT material reads them from the
//!   sidecar's pivot texture instead, and `godot_plays_a_vat_lod_where_frond_plays_it_skinned`
//!   plays a VAT LOD with it (the textures imported beside the model, the uniforms from the
//!   sidecar; tests/godot/project/inspect.gd `_set_vat`).
//! - The combined file imports as one Skeleton per LOD, every LOD visible at once (Godot 3 has
//!   no MSFT_lod), and Godot merges skins and extracted materials with equal contents or names
//!   across the LODs; it is imported and described but only checked for loading.

use crate::common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

use common::*;
use frond_app::inspect::InspectReport;
use frond_lod::LodReport;
use frond_scene::Part;
use serde_json::Value;

/// Godot's own error lines that every animated glTF import prints (see the module docs).
const GODOT_NOISE: &[&str] = &["ERROR: free_static: Condition \"p_ptr == __null\" is true."];

/// One Godot run (an X server and an editor) at a time: `xvfb-run -a` picks its display number
/// racily.
static GODOT: Mutex<()> = Mutex::new(());

/// When Godot cannot run here: prints one `skipped:` line for the running test
/// (`common::report_not_installed`) and returns true.
fn skip_without_godot() -> bool {
    let missing: Vec<&str> = ["godot3", "xvfb-run", "bash"]
        .into_iter()
        .filter(|tool| !on_path(tool))
        .collect();
    if missing.is_empty() {
        return false;
    }
    report_not_installed(
        None,
        &missing.join(", "),
        "apt-get install godot3 xvfb xauth, as bash .ci/run does",
    );
    true
}

/// Runs `tests/godot/run.sh OUT FILES…` with `FROND` set (so it frames Godot's camera on
/// `frond inspect`'s bounds and writes frond's own render beside Godot's) at clip `times`;
/// returns each file's JSON line by the file's absolute path.
fn godot_run(out: &Path, files: &[PathBuf], times: &[String]) -> HashMap<String, Value> {
    let plain: Vec<(PathBuf, Option<PathBuf>)> = files.iter().map(|f| (f.clone(), None)).collect();
    godot_run_with(out, &plain, times)
}

/// [`godot_run`], each file with the file frond frames and renders in its place (None: itself).
fn godot_run_with(
    out: &Path,
    files: &[(PathBuf, Option<PathBuf>)],
    times: &[String],
) -> HashMap<String, Value> {
    let _one_at_a_time = GODOT.lock().unwrap_or_else(|e| e.into_inner());
    let args: Vec<String> = files
        .iter()
        .map(|(f, reference)| match reference {
            Some(r) => format!("{}={}", f.display(), r.display()),
            None => f.display().to_string(),
        })
        .collect();
    let run = Command::new("bash")
        .arg(root().join("tests/godot/run.sh"))
        .arg(out)
        .args(&args)
        .env("FROND", env!("CARGO_BIN_EXE_frond"))
        .env("FROND_GODOT_TIMES", times.join(" "))
        .output()
        .expect("bash runs tests/godot/run.sh");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "tests/godot/run.sh failed ({}):\n{stdout}\n{}",
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    let mut results = HashMap::new();
    for line in stdout.lines().filter(|l| l.starts_with("{\"")) {
        let value: Value = serde_json::from_str(line).expect("Godot's line is JSON");
        let file = value["file"].as_str().expect("file").to_string();
        results.insert(file, value);
    }
    for (file, _) in files {
        assert!(
            results.contains_key(file.to_str().expect("utf-8")),
            "no Godot line for {}",
            file.display()
        );
    }
    results
}

/// The JSON chunk and binary chunk of a `.glb`.
fn glb(path: &Path) -> (Value, Vec<u8>) {
    let bytes = std::fs::read(path).expect("glb readable");
    assert_eq!(&bytes[0..4], b"glTF", "{}", path.display());
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let json_len = u32_at(12) as usize;
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).expect("glb JSON");
    let bin_at = 20 + json_len;
    let bin = if bin_at + 8 <= bytes.len() {
        let len = u32_at(bin_at) as usize;
        bytes[bin_at + 8..bin_at + 8 + len].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// What Godot must make of one glTF material.
#[derive(Debug)]
struct GltfMaterial {
    name: String,
    mask: bool,
    blend: bool,
    cutoff: f64,
    double_sided: bool,
    /// Width and height of the base colour texture's image.
    base_color: Option<(u32, u32)>,
    normal: bool,
}

fn gltf_materials(json: &Value, bin: &[u8]) -> Vec<GltfMaterial> {
    let image_size = |texture: &Value| -> (u32, u32) {
        let t = texture["index"].as_u64().expect("texture index") as usize;
        let source = json["textures"][t]["source"].as_u64().expect("source") as usize;
        let view = &json["bufferViews"][json["images"][source]["bufferView"]
            .as_u64()
            .expect("embedded image") as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let end = start + view["byteLength"].as_u64().expect("length") as usize;
        image::ImageReader::new(std::io::Cursor::new(&bin[start..end]))
            .with_guessed_format()
            .expect("image format")
            .into_dimensions()
            .expect("image header")
    };
    json["materials"]
        .as_array()
        .map(|materials| {
            materials
                .iter()
                .map(|m| {
                    let mode = m["alphaMode"].as_str().unwrap_or("OPAQUE");
                    let base = &m["pbrMetallicRoughness"]["baseColorTexture"];
                    GltfMaterial {
                        name: m["name"].as_str().unwrap_or("").to_string(),
                        mask: mode == "MASK",
                        blend: mode == "BLEND",
                        cutoff: m["alphaCutoff"].as_f64().unwrap_or(0.5),
                        double_sided: m["doubleSided"].as_bool().unwrap_or(false),
                        base_color: base.is_object().then(|| image_size(base)),
                        normal: m["normalTexture"].is_object(),
                    }
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Godot 3.2's import hint for looping clips (`ResourceImporterScene`, `_teststr`): the name,
/// less trailing digits, dots and spaces, contains `$loop` / `$cycle` or ends in `-loop`,
/// `_loop`, `-cycle`, `_cycle` (case-insensitive).
fn godot_loops(name: &str) -> bool {
    let trimmed = name
        .trim_end_matches(|c: char| c.is_ascii_digit() || c == '.' || c <= ' ')
        .to_lowercase();
    ["loop", "cycle"].iter().any(|hint| {
        trimmed.contains(&format!("${hint}"))
            || trimmed.ends_with(&format!("-{hint}"))
            || trimmed.ends_with(&format!("_{hint}"))
    })
}

/// The error and warning entries Godot printed while importing and while loading/rendering,
/// less its known noise.
fn godot_errors(result: &Value) -> Vec<String> {
    ["import_log", "log"]
        .iter()
        .flat_map(|key| result[*key].as_array().cloned().unwrap_or_default())
        .filter_map(|entry| {
            let text = entry["text"].as_str().unwrap_or("").to_string();
            (!GODOT_NOISE.iter().any(|noise| text.starts_with(noise)))
                .then(|| format!("{}× {text}", entry["count"]))
        })
        .collect()
}

/// Whether a pixel of Godot's frame shows the tree: it is not the magenta background (1, 0, 1).
/// Alpha scissor, no MSAA: a pixel is background or tree, the margin only absorbs rounding.
fn godot_covers(rgb: [u8; 3]) -> bool {
    let [r, g, b] = rgb.map(i32::from);
    (255 - r) + g + (255 - b) > 48
}

/// The alpha (0..255) from which a blended pixel of frond's frame counts as the tree's: a leaf
/// colour at this alpha over magenta moves [`godot_covers`]'s sum past its margin.
const BLENDED_SHOWS: u8 = 26;

/// A silhouette: which pixels of a frame show the tree.
struct Silhouette {
    width: u32,
    height: u32,
    covered: Vec<bool>,
}

impl Silhouette {
    /// Godot's frame: the pixels that show the tree ([`godot_covers`]).
    fn godot(png: &Path) -> Silhouette {
        let image = image::open(png).expect("Godot's PNG").to_rgb8();
        let covered = image.pixels().map(|p| godot_covers(p.0)).collect();
        Silhouette {
            width: image.width(),
            height: image.height(),
            covered,
        }
    }

    /// frond's frame: transparent background, the pixels whose alpha reaches `min_alpha`
    /// (0..255).
    fn frond(png: &Path, min_alpha: u8) -> Silhouette {
        let image = image::open(png).expect("frond's PNG").to_rgba8();
        let covered = image.pixels().map(|p| p.0[3] >= min_alpha).collect();
        Silhouette {
            width: image.width(),
            height: image.height(),
            covered,
        }
    }

    fn area(&self) -> usize {
        self.covered.iter().filter(|c| **c).count()
    }

    /// The covered pixels' extent, less the outermost 0.5% of them on each side: x0, y0, x1, y1
    /// (inclusive). A bounding box that one-pixel slivers (billboards seen edge-on, rasterized
    /// a pixel apart by the two renderers) do not move.
    fn extent(&self) -> [i64; 4] {
        let (mut xs, mut ys): (Vec<i64>, Vec<i64>) = self
            .covered
            .iter()
            .enumerate()
            .filter(|(_, c)| **c)
            .map(|(i, _)| {
                (
                    (i as u32 % self.width) as i64,
                    (i as u32 / self.width) as i64,
                )
            })
            .unzip();
        xs.sort_unstable();
        ys.sort_unstable();
        let n = xs.len();
        assert!(n > 0, "an empty frame");
        let k = n / 200;
        [xs[k], ys[k], xs[n - 1 - k], ys[n - 1 - k]]
    }

    /// Intersection over union with `other`, the ratio of the areas (self / other) and the
    /// largest distance in pixels between the two extents' edges (see `extent`).
    fn compare(&self, other: &Silhouette) -> (f64, f64, i64) {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "frame sizes"
        );
        let both = self
            .covered
            .iter()
            .zip(&other.covered)
            .filter(|(a, b)| **a && **b)
            .count();
        let (a, b) = (self.area(), other.area());
        let iou = both as f64 / (a + b - both).max(1) as f64;
        let ratio = a as f64 / b.max(1) as f64;
        let (p, q) = (self.extent(), other.extent());
        let edge = (0..4).map(|k| (p[k] - q[k]).abs()).max().expect("4 edges");
        (iou, ratio, edge)
    }
}

/// One frame's comparison with frond's render: silhouette IoU, area ratio (Godot / frond) and
/// distance between the extents (px), sampled as frond samples and as imported.
struct Measured {
    time: f64,
    sampled: (f64, f64, i64),
    imported: (f64, f64, i64),
}

/// Checks Godot's view of one LOD file (`result`, its JSON line) against the file itself, the
/// chain's report (the input clip) and frond's render.
#[expect(
    clippy::too_many_lines,
    reason = "one LOD file checked against Godot's view in turn: meshes, skins, clips, frames"
)]
fn check_lod(file: &Path, result: &Value, report: &LodReport) -> Vec<Measured> {
    let what = file.display().to_string();
    assert_eq!(result["imported"], true, "{what}: not imported: {result}");
    assert_eq!(result["loaded"], true, "{what}: not loaded: {result}");
    let errors = godot_errors(result);
    assert!(errors.is_empty(), "{what}: Godot printed {errors:#?}");

    let (json, bin) = glb(file);
    let inspect: InspectReport =
        parse_json(&frond_ok(&["inspect", file.to_str().expect("utf-8"), "--json"]).stdout);

    // One skeleton, with at least the skin's joints: Godot 3.2 also makes a bone of every
    // animated node below the skeleton's root that is no joint (measured: sapling_LOD3's 30
    // joints and 53 animated nodes make 54 bones).
    let skeletons = result["skeletons"].as_array().expect("skeletons");
    assert_eq!(skeletons.len(), 1, "{what}: skeletons {skeletons:?}");
    let bones = skeletons[0]["bones"].as_u64().expect("bones");
    let joints = json["skins"][0]["joints"].as_array().expect("a skin").len() as u64;
    assert!(
        bones > 0 && bones >= joints,
        "{what}: {bones} bones, {joints} joints"
    );

    // The clip, at the input clip's length (the report's period) and the file's own.
    let players = result["animation_players"].as_array().expect("players");
    assert_eq!(players.len(), 1, "{what}: players {players:?}");
    let clip = report.clip.as_deref().expect("report clip");
    let period = written_f64(report.period);
    let anim = players[0]["animations"]
        .as_array()
        .expect("animations")
        .iter()
        .find(|a| a["name"] == clip)
        .unwrap_or_else(|| panic!("{what}: no animation {clip}: {}", players[0]));
    let length = anim["length"].as_f64().expect("length");
    assert!(
        (length - period).abs() < 1e-3,
        "{what}: length {length}, period {period}"
    );
    let file_clip = inspect
        .clips
        .iter()
        .find(|c| c.name == clip)
        .expect("the clip in the file");
    let duration = written_f64(file_clip.duration_s);
    assert!(
        (length - duration).abs() < 1e-3,
        "{what}: length {length}, file {duration}"
    );
    let channels = file_clip.channels as u64;
    let tracks = anim["tracks"].as_u64().expect("tracks");
    assert!(
        tracks > 0 && tracks <= channels,
        "{what}: {tracks} tracks, {channels} channels"
    );
    assert_eq!(
        anim["loop"].as_bool(),
        Some(godot_loops(clip)),
        "{what}: Godot 3 loops a clip exactly when its name carries the import hint"
    );

    // Materials, by name (the LOD files' names are unique), as the glTF says.
    let godot_materials: Vec<&Value> = result["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .flat_map(|m| m["materials"].as_array().expect("materials"))
        .collect();
    let foliage: Vec<&str> = inspect
        .classification
        .iter()
        .filter(|c| c.part == Part::Foliage)
        .map(|c| c.material.as_str())
        .collect();
    assert!(!foliage.is_empty(), "{what}: no foliage");
    for material in gltf_materials(&json, &bin) {
        let name = &material.name;
        let godot = godot_materials
            .iter()
            .find(|m| m["name"] == name.as_str())
            .unwrap_or_else(|| panic!("{what}: Godot has no material {name}"));
        assert_eq!(godot["class"], "SpatialMaterial", "{what}: {name}");
        if foliage.contains(&name.as_str()) {
            assert!(
                material.mask || material.blend,
                "{what}: foliage material {name} is neither MASK nor BLEND"
            );
        }
        assert_eq!(
            godot["alpha_scissor"], material.mask,
            "{what}: {name}: {godot}"
        );
        if material.mask {
            let threshold = godot["alpha_scissor_threshold"]
                .as_f64()
                .expect("threshold");
            assert!(
                (threshold - material.cutoff).abs() < 1e-6,
                "{what}: {name}: {godot}"
            );
        }
        assert_eq!(
            godot["transparent"], material.blend,
            "{what}: {name}: {godot}"
        );
        let cull = if material.double_sided {
            "disabled"
        } else {
            "back"
        };
        assert_eq!(godot["cull_mode"], cull, "{what}: {name}: {godot}");
        assert_eq!(
            godot["albedo_texture"],
            material.base_color.is_some(),
            "{what}: {name}: {godot}"
        );
        if let Some((w, h)) = material.base_color {
            assert_eq!(
                godot["albedo_texture_size"],
                serde_json::json!([w, h]),
                "{what}: {name}"
            );
        }
        assert_eq!(
            godot["normal_texture"], material.normal,
            "{what}: {name}: {godot}"
        );
    }

    // A blended pixel shows the tree in Godot's frame once its alpha reaches what
    // `godot_covers` tells from the magenta (about a tenth for a leaf's colour); an alpha-tested
    // one is whole or nothing, and frond's frame is cut at a half.
    let blended = gltf_materials(&json, &bin).iter().any(|m| m.blend);
    let min_alpha = if blended { BLENDED_SHOWS } else { 128 };

    // The frames: Godot posed the clip and framed frond inspect's bounds.
    assert_eq!(result["camera"]["bounds_from"], "frond", "{what}: {result}");
    let renders = result["renders"].as_array().expect("renders");
    assert!(!renders.is_empty(), "{what}: no frames");
    renders
        .iter()
        .map(|render| {
            let time = render["time"].as_f64().expect("time");
            let what = format!("{what} at {time} s");
            assert_eq!(render["clip"], clip, "{what}: {render}");
            assert_eq!(render["saved"], true, "{what}: {render}");
            let godot_png = render["png"].as_str().expect("png");
            let sampled_png = render["png_frond_sampling"].as_str().expect("png");
            let frond = Silhouette::frond(
                Path::new(&godot_png.replace(".godot.png", ".frond.png")),
                min_alpha,
            );
            assert!(frond.area() > 1000, "{what}: frond's frame is empty");
            // Sampled alike, the silhouettes agree to a few pixels at a key (time 0): measured
            // IoU 0.993-1.000, area ratio 0.999-1.002, extents within 1 px (sapling chains,
            // pine_medium_blender's chain). Between keys Godot's 15-FPS bake moves the pine's
            // needles (IoU 0.873-0.944, see the module docs; sapling 0.990-0.998); a frame of
            // the wrong pose (time 0 against 1.3 s) scores 0.68-0.77.
            let min_iou = if time == 0.0 { 0.97 } else { 0.82 };
            let sampled = Silhouette::godot(Path::new(sampled_png)).compare(&frond);
            let (iou, ratio, edge) = sampled;
            assert!(
                iou > min_iou,
                "{what}: silhouette IoU {iou} (frond-like sampling)"
            );
            assert!((ratio - 1.0).abs() < 0.02, "{what}: area ratio {ratio}");
            assert!(edge <= 3, "{what}: extents {edge} px apart");
            // As imported, Godot's mipmaps thin thin alpha-tested foliage (pine needles: 13-25%
            // less area at 512 px) and repeat wraps leaf cards whose UVs leave [0, 1] (frond's
            // cards LODs: leaf fragments up to 9 px outside, +2-3% area). Measured IoU
            // 0.70-1.00, area ratio 0.75-1.03, extents within 4 px.
            let imported = Silhouette::godot(Path::new(godot_png)).compare(&frond);
            let (iou, ratio, edge) = imported;
            assert!(iou > 0.6, "{what}: silhouette IoU {iou} (as imported)");
            assert!(
                (0.65..1.1).contains(&ratio),
                "{what}: area ratio {ratio} (as imported)"
            );
            assert!(edge <= 8, "{what}: extents {edge} px apart (as imported)");
            Measured {
                time,
                sampled,
                imported,
            }
        })
        .collect()
}

/// Godot's view of a chain's combined file: loads, one skeleton per LOD. What else Godot makes of
/// it (all LODs visible, merged skins and materials, errors, how its frame compares with frond's
/// render of the file) is printed, not asserted.
fn describe_combined(file: &Path, result: &Value, lods: usize) {
    let what = file.display().to_string();
    assert_eq!(result["imported"], true, "{what}: not imported: {result}");
    assert_eq!(result["loaded"], true, "{what}: not loaded: {result}");
    let skeletons = result["skeletons"].as_array().expect("skeletons");
    assert_eq!(skeletons.len(), lods, "{what}: skeletons {skeletons:?}");
    let visible = result["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .filter(|m| m["visible"] == true)
        .count();
    let errors = godot_errors(result);
    let render = &result["renders"][0];
    let (iou, ratio, edge) = match render["png_frond_sampling"].as_str() {
        Some(png) => Silhouette::godot(Path::new(png)).compare(&Silhouette::frond(
            Path::new(&png.replace(".godot_frondsampling.png", ".frond.png")),
            128,
        )),
        None => (f64::NAN, f64::NAN, -1),
    };
    eprintln!(
        "note: {what} in Godot 3: {} skeletons, {visible} visible meshes, {} error entries{}; \
         frame at {} s vs frond render: IoU {iou:.3}, area ratio {ratio:.3}, extent {edge} px",
        skeletons.len(),
        errors.len(),
        errors
            .first()
            .map(|e| format!(" (first: {e})"))
            .unwrap_or_default(),
        render["time"]
    );
}

/// Writes the chain for `input` into `dir` (small test settings) and returns the report and the
/// LOD files.
fn chain(input: &Path, dir: &Path, extra: &[&str]) -> (LodReport, Vec<PathBuf>) {
    let report = frond_lod(input, dir, extra);
    let lods = report.lods.iter().map(|l| dir.join(&l.file)).collect();
    (report, lods)
}

fn combined(dir: &Path, report: &LodReport) -> PathBuf {
    dir.join(format!("{}_lods.glb", report.name))
}

fn print_measured(file: &Path, measured: &[Measured]) {
    for m in measured {
        eprintln!(
            "{} at {} s: silhouette vs frond render: IoU {:.3}, area ratio {:.3}, extent {} px \
             (frond-like sampling); IoU {:.3}, area ratio {:.3}, extent {} px (as imported)",
            file.file_name().expect("name").to_string_lossy(),
            m.time,
            m.sampled.0,
            m.sampled.1,
            m.sampled.2,
            m.imported.0,
            m.imported.1,
            m.imported.2
        );
    }
}

/// The frames' clip times: 0 (a key) and 0.325 of the period (between keys), as passed to
/// `frond render --time` and named in the files.
fn times(report: &LodReport) -> Vec<String> {
    let period = written_f64(report.period);
    vec!["0".to_string(), format!("{:.2}", 0.325 * period)]
}

/// The sample sapling's default chain (cards LODs) and its skeleton-method chain (billboard
/// atlases), plus the default chain's combined file.
#[test]
fn godot_imports_and_renders_the_sample_chains() {
    if skip_without_godot() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let input = root().join("samples/sapling.glb");
    // The default chain and its far end (`auto`'s impostor-class cloud of FFT clusters).
    let (report, lods) = chain(
        &input,
        &dir.path().join("cards"),
        &["--lods", "600,200,60,20", "--far-alpha", "blend"],
    );
    assert_eq!(
        report.lods[4].method.name(),
        "spectral-axis-phase",
        "the far end"
    );
    let (sk_report, sk_lods) = chain(
        &input,
        &dir.path().join("skeleton"),
        &["--method", "skeleton"],
    );
    // LOD0 is the input in both chains: once is enough.
    let mut files = lods.clone();
    files.extend(sk_lods.iter().skip(1).cloned());
    let all_lods = files.clone();
    let combined_file = combined(&dir.path().join("cards"), &report);
    files.push(combined_file.clone());
    let results = godot_run(&dir.path().join("godot"), &files, &times(&report));
    let report_of = |file: &PathBuf| {
        if sk_lods.contains(file) {
            &sk_report
        } else {
            &report
        }
    };
    check_chain(&all_lods, &combined_file, &results, report_of);
}

/// Checks each of `lods` against Godot's `results` and its chain's report, then describes
/// Godot's import of the combined file (a chain of as many LODs as the first chain has).
fn check_chain<'a>(
    lods: &[PathBuf],
    combined_file: &Path,
    results: &HashMap<String, Value>,
    report_of: impl Fn(&PathBuf) -> &'a LodReport,
) {
    for file in lods {
        let measured = check_lod(
            file,
            &results[file.to_str().expect("utf-8")],
            report_of(file),
        );
        print_measured(file, &measured);
    }
    check_lit_colour(lods, results);
    let chain_len = report_of(&lods[0]).lods.len();
    describe_combined(
        combined_file,
        &results[combined_file.to_str().expect("utf-8")],
        chain_len,
    );
}

/// The most the mean lit colour of a LOD may differ from LOD0's in Godot's frames (linear RGB,
/// 0..1): the bound of docs/metrics.md's colour shift, which frond's own lit render holds too.
const MAX_GODOT_COLOUR_SHIFT: f64 = 0.02;

/// Every LOD after the first of `lods` (LOD0, the input, first) shades like LOD0 in Godot: in
/// each frame Godot rendered (lit by its directional and ambient light, as imported), the mean
/// linear colour of the pixels both cover differs by at most [`MAX_GODOT_COLOUR_SHIFT`], as
/// frond's colour shift measures it (the signed difference averaged over those pixels, then
/// over the channels). A lighter or darker LOD is a visible pop when the engine swaps it in.
fn check_lit_colour(lods: &[PathBuf], results: &HashMap<String, Value>) {
    let frames = |file: &PathBuf| -> Vec<(f64, String)> {
        let result = &results[file.to_str().expect("utf-8")];
        (result["renders"].as_array().expect("renders").iter())
            .map(|r| {
                let time = r["time"].as_f64().expect("time");
                (time, r["png"].as_str().expect("png").to_string())
            })
            .collect()
    };
    let reference = frames(&lods[0]);
    for file in &lods[1..] {
        let (json, bin) = glb(file);
        let blended = gltf_materials(&json, &bin).iter().any(|m| m.blend);
        for ((time, png), (_, lod0_png)) in frames(file).iter().zip(&reference) {
            let frame = if blended {
                let frond_png = png.replace(".godot.png", ".frond.png");
                LitFrame::godot_blended(Path::new(png), Path::new(&frond_png))
            } else {
                LitFrame::godot(Path::new(png))
            };
            let shift = lit_colour_shift(&LitFrame::godot(Path::new(lod0_png)), &frame);
            // The chain's folder too: the sample's two chains name their LODs alike.
            let name = file
                .iter()
                .rev()
                .take(2)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect::<PathBuf>()
                .display()
                .to_string();
            eprintln!("{name} at {time} s: lit colour shift from LOD0 in Godot {shift:.4}");
            assert!(
                shift <= MAX_GODOT_COLOUR_SHIFT,
                "{name} at {time} s: Godot's lit colour shifts {shift:.4} from LOD0's"
            );
        }
    }
}

/// A Godot frame's covered pixels (not the magenta background) and their linear colour.
struct LitFrame {
    covered: Vec<bool>,
    linear: Vec<[f64; 3]>,
}

impl LitFrame {
    fn godot(png: &Path) -> LitFrame {
        let image = image::open(png).expect("Godot's PNG").to_rgb8();
        LitFrame {
            covered: image.pixels().map(|p| godot_covers(p.0)).collect(),
            linear: (image.pixels())
                .map(|p| p.0.map(|v| srgb_to_linear(f64::from(v) / 255.0)))
                .collect(),
        }
    }
}

impl LitFrame {
    /// A Godot frame of a blended LOD: each pixel's colour over the magenta background unmixed
    /// with the alpha frond's frame of the same view gives it (`frond_png`, as Godot blends: in
    /// linear light), kept where that alpha is at least a half so the background's share stays
    /// small.
    fn godot_blended(png: &Path, frond_png: &Path) -> LitFrame {
        let image = image::open(png).expect("Godot's PNG").to_rgb8();
        let frond = image::open(frond_png).expect("frond's PNG").to_rgba8();
        assert_eq!(image.dimensions(), frond.dimensions(), "frame sizes");
        let background = [1.0, 0.0, 1.0];
        let (covered, linear) = (image.pixels().zip(frond.pixels()))
            .map(|(p, f)| {
                let alpha = f64::from(f.0[3]) / 255.0;
                let shown = godot_covers(p.0) && alpha >= 0.5;
                let c = p.0.map(|v| srgb_to_linear(f64::from(v) / 255.0));
                let unmixed = std::array::from_fn(|k| {
                    ((c[k] - (1.0 - alpha) * background[k]) / alpha).clamp(0.0, 1.0)
                });
                (shown, if shown { unmixed } else { [0.0; 3] })
            })
            .unzip();
        LitFrame { covered, linear }
    }
}

/// The sRGB transfer function undone.
fn srgb_to_linear(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// `|mean(a − b)|` over the pixels both frames cover, averaged over the channels; 0 when they
/// share none.
fn lit_colour_shift(a: &LitFrame, b: &LitFrame) -> f64 {
    assert_eq!(a.covered.len(), b.covered.len(), "frame sizes");
    let (mut sum, mut shared) = (0.0, 0usize);
    for i in 0..a.covered.len() {
        if a.covered[i] && b.covered[i] {
            sum += (0..3).map(|c| a.linear[i][c] - b.linear[i][c]).sum::<f64>() / 3.0;
            shared += 1;
        }
    }
    if shared == 0 {
        0.0
    } else {
        (sum / shared as f64).abs()
    }
}

/// The shared Blender-exported pine's default chain and far end, where present.
#[test]
fn godot_imports_and_renders_the_pine_chain() {
    let tree = frond_testdata::require_tree!("pine_medium_blender.glb");
    if skip_without_godot() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    // The default chain and its far end, as for the sample.
    let (report, lods) = chain(
        &tree,
        &dir.path().join("chain"),
        &["--lods", "600,200,60,20", "--far-alpha", "blend"],
    );
    let combined_file = combined(&dir.path().join("chain"), &report);
    let mut files = lods.clone();
    files.push(combined_file.clone());
    let results = godot_run(&dir.path().join("godot"), &files, &times(&report));
    check_chain(&lods, &combined_file, &results, |_| &report);
}

/// The Godot 3 materials frond ships (`export/shaders/*_godot3.shader`: VAT, spectral motion,
/// LOD cross-fade) and their blended variants compile in Godot 3's own shader compiler and GL
/// driver (GLES3, what their `texelFetch`/`textureSize` need), each with the uniforms the
/// sidecars feed.
#[test]
fn godot_compiles_the_shipped_godot3_shaders() {
    if skip_without_godot() {
        return;
    }
    let shaders: Vec<PathBuf> = frond_export::shaders::SHADERS
        .iter()
        .chain(frond_export::shaders::SPECTRAL_SHADERS)
        .map(|(name, _)| *name)
        .filter(|name| name.ends_with("_godot3.shader"))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .map(|name| root().join("export/shaders").join(name))
        .collect();
    assert_eq!(shaders.len(), 3, "{shaders:?}");
    // Their blended variants, as frond writes them beside a blended far end.
    let variants_dir = tempfile::tempdir().expect("temp dir");
    let mut shaders = shaders;
    for (name, text) in frond_export::shaders::blended_variants(frond_export::shaders::SHADERS)
        .into_iter()
        .chain(frond_export::shaders::blended_variants(
            frond_export::shaders::SPECTRAL_SHADERS,
        ))
        .filter(|(name, _)| name.ends_with("_godot3.shader"))
        .collect::<std::collections::BTreeMap<_, _>>()
    {
        let path = variants_dir.path().join(name);
        std::fs::write(&path, text).expect("write a blended variant");
        shaders.push(path);
    }
    assert_eq!(shaders.len(), 6, "{shaders:?}");
    let _one_at_a_time = GODOT.lock().unwrap_or_else(|e| e.into_inner());
    let run = Command::new("bash")
        .arg(root().join("tests/godot/check_shaders.sh"))
        .args(&shaders)
        .output()
        .expect("bash runs tests/godot/check_shaders.sh");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "Godot 3 refused a shader ({}):\n{stdout}\n{}",
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    let lines: Vec<Value> = stdout
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    assert_eq!(lines.len(), shaders.len(), "{stdout}");
    for l in &lines {
        assert_eq!(l["ok"], true, "{l}");
        assert!(
            l["params"].as_array().is_some_and(|p| !p.is_empty()),
            "uniforms listed: {l}"
        );
        eprintln!("godot3 compiled {}: {}", l["shader"], l["params"]);
    }
}

/// A VAT LOD (`--animation vat`) in Godot 3: its textures imported beside it, its `_vat` mesh
/// given the shipped Godot 3 VAT material (export/shaders/frond_vat_rigid_godot3.shader) with the
/// sidecar's numbers, the pivot read from the pivot texture. Godot's frames at two clip times
/// must show the billboards where frond's render of the same LOD written skinned shows them (the
/// same cloud and motion: frond itself does not play VAT), so they move, and move right.
#[test]
fn godot_plays_a_vat_lod_where_frond_plays_it_skinned() {
    if skip_without_godot() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let input = root().join("samples/sapling.glb");
    let args = ["--lods", "200", "--method", "skeleton"];
    let (report, vat_lods) = chain(
        &input,
        &dir.path().join("vat"),
        &[&args[..], &["--animation", "vat"]].concat(),
    );
    let (_, skin_lods) = chain(&input, &dir.path().join("skin"), &args);
    let (vat, skin) = (&vat_lods[1], &skin_lods[1]);
    assert!(
        report.lods[1].vat.is_some(),
        "LOD1 has VAT files: {:?}",
        report.lods[1]
    );
    let results = godot_run_with(
        &dir.path().join("godot"),
        &[(vat.clone(), Some(skin.clone()))],
        &times(&report),
    );
    let result = &results[vat.to_str().expect("utf-8")];
    let what = vat.display().to_string();
    assert_eq!(result["imported"], true, "{what}: {result}");
    assert_eq!(result["loaded"], true, "{what}: {result}");
    let errors = godot_errors(result);
    assert!(errors.is_empty(), "{what}: Godot printed {errors:#?}");
    let set = &result["vat"];
    assert!(
        set["mesh"].is_string(),
        "{what}: VAT material not set: {set}"
    );
    assert_eq!(
        set["textures"], true,
        "{what}: VAT textures not loaded: {set}"
    );
    assert_eq!(set["atlas"], true, "{what}: {set}");
    let renders = result["renders"].as_array().expect("renders");
    assert_eq!(renders.len(), 2);
    let mut godot_frames = Vec::new();
    for render in renders {
        let time = render["time"].as_f64().expect("time");
        let sampled = render["png_frond_sampling"].as_str().expect("png");
        let frond = Silhouette::frond(
            Path::new(
                &render["png"]
                    .as_str()
                    .expect("png")
                    .replace(".godot.png", ".frond.png"),
            ),
            128,
        );
        let godot = Silhouette::godot(Path::new(sampled));
        let (iou, ratio, edge) = godot.compare(&frond);
        eprintln!(
            "{} at {time} s (VAT in Godot vs skinned in frond): IoU {iou:.3}, area ratio {ratio:.3}, extent {edge} px",
            vat.file_name().expect("name").to_string_lossy()
        );
        // Measured: IoU 0.970 at 0 s, 0.960 at 1.3 s (area ratio 0.996); with the material's
        // clip time held at 0 (billboards frozen in frame 0) the 1.3 s frame scores 0.739.
        assert!(iou > 0.85, "{what} at {time} s: silhouette IoU {iou}");
        assert!(
            (ratio - 1.0).abs() < 0.05,
            "{what} at {time} s: area ratio {ratio}"
        );
        godot_frames.push((godot, frond));
    }
    // The billboards moved between the two times in Godot as in frond, by about as much.
    let moved = |a: &Silhouette, b: &Silhouette| {
        a.covered
            .iter()
            .zip(&b.covered)
            .filter(|(x, y)| x != y)
            .count()
    };
    let godot_moved = moved(&godot_frames[0].0, &godot_frames[1].0);
    let frond_moved = moved(&godot_frames[0].1, &godot_frames[1].1);
    eprintln!("pixels changed between the frames: Godot {godot_moved}, frond {frond_moved}");
    assert!(
        frond_moved > 200,
        "frond's frames barely differ ({frond_moved} px)"
    );
    assert!(
        godot_moved as f64 > 0.5 * frond_moved as f64,
        "Godot's VAT billboards barely move: {godot_moved} px changed, frond's {frond_moved}"
    );
}
