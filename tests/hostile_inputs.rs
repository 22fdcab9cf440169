//! The bad-input corpus (`common::hostile`): what an attacker fed frond, each reproduced first
//! and then held to the rule. An oversized input is refused before its sizes are spent, in
//! under a second and 200 MB, with one line naming the file and the image or clip; what is
//! accepted costs memory in proportion (at most 4 × the decoded texture bytes + 500 MB); names
//! from a file reach HTML, terminals and spreadsheets inert.

use crate::common;

use std::path::Path;
use std::time::Duration;

use common::hostile::*;
use common::*;
use serde_json::json;

/// Refusals are made from headers and declared counts: well under a second in a release
/// build. Test builds are slower and CI machines share their cores, so the test allows this.
const REFUSAL_TIME: Duration = Duration::from_secs(3);
const REFUSAL_MEMORY: u64 = 200 << 20;
const LONG: Duration = Duration::from_secs(600);

/// Asserts a quick, small refusal: exit 1, one line naming `file` and each of `needles`,
/// no output folder.
#[track_caller]
fn refused_cheaply(m: &Measured, file: &Path, out: &Path, needles: &[&str]) {
    let err = m.stderr();
    assert_eq!(m.output.status.code(), Some(1), "refused: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(
        err.contains(&file.display().to_string()),
        "names the file: {err}"
    );
    for n in needles {
        assert!(err.contains(n), "says '{n}': {err}");
    }
    eprintln!("{}: refused, {}", file.display(), m.summary());
    assert!(m.wall < REFUSAL_TIME, "refused in {:?}", m.wall);
    assert!(
        m.peak_rss < REFUSAL_MEMORY,
        "refused within {} MB",
        m.peak_rss >> 20
    );
    assert!(!out.exists(), "no output folder");
}

fn lod_args<'a>(file: &'a Path, out: &'a Path) -> Vec<&'a str> {
    vec!["lod", file.to_str().unwrap(), "-o", out.to_str().unwrap()]
}

/// `frond lod FILE -o OUT --no-measure --no-preview` plus `extra`, measured.
fn lod_unmeasured(file: &Path, out: &Path, extra: &[&str]) -> Measured {
    let mut args = lod_args(file, out);
    args.extend(["--no-measure", "--no-preview"]);
    args.extend(extra);
    frond_measured(&args, LONG)
}

/// Decoded bytes (4 a texel) of every image a material map of `file` uses, each once.
fn decoded_texture_bytes(file: &Path) -> u64 {
    let src = frond_scene::gltf_source::GltfSource::open(file, &Default::default()).unwrap();
    let mut images = std::collections::BTreeSet::new();
    for m in &src.raw.materials {
        let mut m = m.clone();
        let _ = frond_scene::visit_texture_infos(&mut m, &mut |_, info| {
            let t = info["index"].as_u64().unwrap() as usize;
            images.insert(frond_scene::import::texture_image(&src, t, false));
            Ok::<(), ()>(())
        });
    }
    images
        .into_iter()
        .map(|i| {
            let bytes = src.image_bytes(i).unwrap();
            let (w, h) = match frond_scene::ktx2::read_info(&bytes) {
                Ok(k) => (k.width, k.height),
                Err(_) => image::ImageReader::new(std::io::Cursor::new(&bytes))
                    .with_guessed_format()
                    .unwrap()
                    .into_dimensions()
                    .unwrap(),
            };
            u64::from(w) * u64::from(h) * 4
        })
        .sum()
}

#[test]
fn every_material_map_counts_towards_the_texture_memory_limit() {
    let dir = tempfile::tempdir().unwrap();
    // An 11500² map declared in a 400-byte PNG: 504 MiB decoded, over the 384 MiB default,
    // in each slot frond used not to count.
    for slot in [
        "/normalTexture",
        "/occlusionTexture",
        "/emissiveTexture",
        "/pbrMetallicRoughness/metallicRoughnessTexture",
    ] {
        let mut glb = Glb::sample();
        let t = glb.add_image("bomb", "image/png", &png_header_only(11_500, 11_500));
        glb.set_map(1, slot, t);
        let name = format!("bomb{}.glb", slot.replace('/', "_"));
        let file = glb.write(dir.path(), &name);
        let out = dir.path().join(format!("out{}", slot.replace('/', "_")));
        let key = slot.rsplit('/').next().unwrap();
        refused_cheaply(
            &frond_measured(&lod_args(&file, &out), LONG),
            &file,
            &out,
            &[
                "image 2 ('bomb')",
                &format!("the {key} of material 1 ('leaves')"),
                "11500×11500",
                "--max-texture-memory",
            ],
        );
    }
    // A KTX2 map, budgeted from its header alike; and a map of 60000² named as itself (the
    // message once named the first image of the file).
    let mut glb = Glb::sample();
    let t = glb.add_ktx2("ktx2bomb", &ktx2_header_only(20_000, 20_000));
    glb.set_map(1, "/normalTexture", t);
    let file = glb.write(dir.path(), "ktx2bomb.glb");
    let out = dir.path().join("out_ktx2");
    refused_cheaply(
        &frond_measured(&lod_args(&file, &out), LONG),
        &file,
        &out,
        &["image 2 ('ktx2bomb')", "20000×20000"],
    );
    // Headers declaring 2³¹ texels a side (their bytes once overflowed the count).
    // (The PNG decoder refuses such a header itself, named alike.)
    for (name, bytes, mime, says) in [
        (
            "ktx2max",
            ktx2_header_only(1 << 31, 1 << 31),
            "image/ktx2",
            "over the texture memory limit",
        ),
        (
            "pngmax",
            png_header_only(0x7fff_ffff, 0x7fff_ffff),
            "image/png",
            "cannot read its size",
        ),
    ] {
        let mut glb = Glb::sample();
        let t = if mime == "image/ktx2" {
            glb.add_ktx2(name, &bytes)
        } else {
            glb.add_image(name, mime, &bytes)
        };
        glb.set_map(0, "/pbrMetallicRoughness/baseColorTexture", t);
        let file = glb.write(dir.path(), &format!("{name}.glb"));
        let out = dir.path().join(format!("out_{name}"));
        refused_cheaply(
            &frond_measured(&lod_args(&file, &out), LONG),
            &file,
            &out,
            &[&format!("image 2 ('{name}')"), says],
        );
    }
    let mut glb = Glb::sample();
    let t = glb.add_image("huge", "image/png", &png_header_only(60_000, 60_000));
    glb.set_map(0, "/occlusionTexture", t);
    let file = glb.write(dir.path(), "huge.glb");
    let out = dir.path().join("out_huge");
    refused_cheaply(
        &frond_measured(&lod_args(&file, &out), LONG),
        &file,
        &out,
        &["image 2 ('huge'), the occlusionTexture of material 0 ('bark')"],
    );
}

/// `frond lod` of `file` (every default: measured, with its preview) succeeds within the
/// memory rule: at most 4 × the decoded texture bytes + 500 MB.
#[track_caller]
fn lod_in_proportion(file: &Path, out: &Path) {
    let m = frond_measured(&lod_args(file, out), LONG);
    assert!(m.output.status.success(), "{}", m.stderr());
    let textures = decoded_texture_bytes(file);
    let bound = 4 * textures + (500 << 20);
    eprintln!(
        "{}: {}, {} MB of decoded textures",
        file.display(),
        m.summary(),
        textures >> 20
    );
    assert!(
        m.peak_rss <= bound,
        "{}: peak {} MB for {} MB of decoded textures (bound {} MB)",
        file.display(),
        m.peak_rss >> 20,
        textures >> 20,
        bound >> 20
    );
}

#[test]
fn accepted_maps_cost_memory_in_proportion() {
    let dir = tempfile::tempdir().unwrap();
    // An 8000² normal map (256 MB decoded): it took 5 GB once, each LOD file decoding and
    // resampling it at once through a float copy.
    let mut glb = Glb::sample();
    let t = glb.add_image(
        "n8000",
        "image/png",
        &png_solid(8000, 8000, [128, 128, 255]),
    );
    glb.set_map(1, "/normalTexture", t);
    let file = glb.write(dir.path(), "normal8000.glb");
    lod_in_proportion(&file, &dir.path().join("out_png"));
    // A 9000² KTX2 map of a few kilobytes (3.6 GB once).
    let mut glb = Glb::sample();
    let t = glb.add_ktx2("k9000", &ktx2_solid(9000, 9000));
    glb.set_map(1, "/normalTexture", t);
    let file = glb.write(dir.path(), "ktx9000.glb");
    assert!(std::fs::metadata(&file).unwrap().len() < 2 << 20);
    let out = dir.path().join("out_ktx2");
    lod_in_proportion(&file, &out);
    // A KTX2 map counts towards every LOD's texture memory and shrinks at the far end like
    // any other (its size was once unread: kept whole, counted as nothing).
    let report = lod_report(&out, "ktx9000");
    let bytes: Vec<u64> = report.lods.iter().map(|l| l.texture_bytes as u64).collect();
    assert!(bytes[0] >= 9000 * 9000 * 4, "{bytes:?}");
    assert!(bytes.last() < bytes.first(), "{bytes:?}");
}

#[test]
fn six_4096_maps_on_bark_and_leaves_are_accepted_at_the_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let mut glb = Glb::sample();
    for m in 0..2 {
        let colour = glb.add_image(
            &format!("c{m}"),
            "image/png",
            &png_solid(4096, 4096, [90, 120, 60]),
        );
        let normal = glb.add_image(
            &format!("n{m}"),
            "image/png",
            &png_solid(4096, 4096, [128, 128, 255]),
        );
        let orm = glb.add_image(
            &format!("orm{m}"),
            "image/png",
            &png_solid(4096, 4096, [255, 200, 0]),
        );
        glb.set_map(m, "/pbrMetallicRoughness/baseColorTexture", colour);
        glb.set_map(m, "/normalTexture", normal);
        glb.set_map(m, "/occlusionTexture", orm);
        glb.set_map(m, "/pbrMetallicRoughness/metallicRoughnessTexture", orm);
    }
    let file = glb.write(dir.path(), "six4096.glb");
    assert_eq!(decoded_texture_bytes(&file), 384 << 20);
    lod_in_proportion(&file, &dir.path().join("out"));
}

#[test]
fn animations_past_the_key_limit_are_refused_from_their_counts() {
    let dir = tempfile::tempdir().unwrap();
    // The sample's clip copied 2,000 times (12.5 MB of JSON, every copy on the same keys): it
    // took 6 GB once, every copy written into every LOD file.
    let mut glb = Glb::sample();
    let clip = glb.json["animations"][0].clone();
    glb.json["animations"] = json!(
        (0..2000)
            .map(|i| {
                let mut c = clip.clone();
                c["name"] = json!(format!("Wind{i}"));
                c
            })
            .collect::<Vec<_>>()
    );
    let file = glb.write(dir.path(), "clips2000.glb");
    let out = dir.path().join("out");
    refused_cheaply(
        &frond_measured(&lod_args(&file, &out), LONG),
        &file,
        &out,
        &[
            "its 2000 animations add up to 14036000 keys",
            "animation 'Wind0'",
            "--max-animation-keys",
        ],
    );
    // Raised, it is read.
    let m = frond_measured(
        &[
            "inspect",
            file.to_str().unwrap(),
            "--max-animation-keys",
            "20000000",
        ],
        LONG,
    );
    assert!(m.output.status.success(), "{}", m.stderr());
}

#[test]
fn duplicate_animation_targets_keep_the_first_channel() {
    let dir = tempfile::tempdir().unwrap();
    // Every channel repeated 2,000 times (the validator's ANIMATION_DUPLICATE_TARGETS): 8.4 GB
    // and 1.97 GB written once.
    let mut glb = Glb::sample();
    let channels = glb.json["animations"][0]["channels"]
        .as_array()
        .unwrap()
        .clone();
    let n = channels.len();
    glb.json["animations"][0]["channels"] = json!(
        (0..2000)
            .flat_map(|_| channels.iter().cloned())
            .collect::<Vec<_>>()
    );
    let file = glb.write(dir.path(), "dup.glb");
    let out = dir.path().join("out");
    let m = lod_unmeasured(&file, &out, &[]);
    assert!(m.output.status.success(), "{}", m.stderr());
    assert!(
        m.stderr()
            .contains(&format!("{} channels drive a target", n * 1999)),
        "{}",
        m.stderr()
    );
    assert!(m.peak_rss < 1 << 30, "{} MB", m.peak_rss >> 20);
    let written = gltf_json(&out.join("dup_LOD0.glb"));
    assert_eq!(
        written["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .len(),
        n
    );
}

/// The sample with its clip named `clip` and its leaf material named `material`.
fn named(dir: &Path, file: &str, clip: &str, material: &str) -> std::path::PathBuf {
    let mut glb = Glb::sample();
    glb.json["animations"][0]["name"] = json!(clip);
    glb.json["materials"][1]["name"] = json!(material);
    glb.write(dir, file)
}

#[test]
fn names_reach_pages_terminals_and_spreadsheets_inert() {
    let dir = tempfile::tempdir().unwrap();
    // A clip name that opened an HTML comment inside the page's config script (the live view
    // died), and escape sequences that retitle and clear a terminal.
    let clip = "Wind<!--<script>\u{1b}]0;pwned\u{7}\u{1b}[2J";
    let file = named(dir.path(), "names.glb", clip, "leaves\u{9b}31m");
    let out = dir.path().join("out");
    let m = frond_measured(&lod_args(&file, &out), LONG);
    assert!(m.output.status.success(), "{}", m.stderr());
    let page = std::fs::read_to_string(out.join("names_preview.html")).unwrap();
    let open = "<script type=\"application/json\" id=\"frond-config\">";
    let start = page.find(open).expect("config script") + open.len();
    let text = &page[start..start + page[start..].find("</script>").unwrap()];
    assert!(!text.contains('<') && !text.contains('>'), "{text}");
    let config: serde_json::Value = serde_json::from_str(text).unwrap();
    assert!(config.to_string().contains("Wind<!--<script>"), "{config}");
    // The terminal: inspect's text and an error naming the clip show escapes, not controls.
    let shown = frond_measured(&["inspect", file.to_str().unwrap()], LONG);
    let stdout = String::from_utf8_lossy(&shown.output.stdout).into_owned();
    assert!(
        stdout.contains("Wind<!--<script>\\x1b]0;pwned\\x07\\x1b[2J"),
        "{stdout}"
    );
    assert!(stdout.contains("leaves\\u{9b}31m"), "{stdout}");
    for text in [&stdout, &shown.stderr()] {
        assert!(
            !text
                .chars()
                .any(|c| c.is_control() && c != '\n' && c != '\t'),
            "{text:?}"
        );
    }
    let mut glb = Glb::read(&file);
    let input = glb.json["animations"][0]["samplers"][0]["input"]
        .as_u64()
        .unwrap() as usize;
    glb.json["accessors"][input]["min"] = json!([-1.0]);
    let at = glb.accessor_offset(input);
    glb.bin[at..at + 4].copy_from_slice(&(-1.0f32).to_le_bytes());
    let broken = glb.write(dir.path(), "broken.glb");
    let failed = frond_measured(&["inspect", broken.to_str().unwrap()], LONG);
    assert_eq!(failed.output.status.code(), Some(1));
    assert!(
        failed.stderr().contains("\\x1b]0;pwned"),
        "{}",
        failed.stderr()
    );
    assert!(!failed.stderr().contains('\u{1b}'), "{:?}", failed.stderr());
    // A spreadsheet: a tree named as a formula is text in the batch's summary.
    let library = dir.path().join("library");
    std::fs::create_dir_all(&library).unwrap();
    std::fs::copy(&file, library.join("=HYPERLINK(\"http:x\").glb")).unwrap();
    let batch_out = dir.path().join("batch");
    let b = frond_measured(
        &[
            "batch",
            library.to_str().unwrap(),
            "-o",
            batch_out.to_str().unwrap(),
            "--jobs",
            "1",
        ],
        LONG,
    );
    assert!(b.output.status.success(), "{}", b.stderr());
    let csv = std::fs::read_to_string(batch_out.join("summary.csv")).unwrap();
    let row = csv.lines().nth(1).expect("a tree's row");
    assert!(row.starts_with("\"'=HYPERLINK("), "{row}");
}

#[test]
fn texture_coordinates_far_outside_the_texture_are_baked() {
    // What the lod_chain fuzz target found: a coordinate of 3e38 floors to i64::MAX texels in
    // the bake's bilinear footprint, whose `+ 1` overflowed (a panic where overflow is
    // checked: this test's build).
    let dir = tempfile::tempdir().unwrap();
    let mut glb = Glb::sample();
    let uv = glb.attribute("leaves", "TEXCOORD_0");
    let at = glb.accessor_offset(uv);
    glb.bin[at..at + 4].copy_from_slice(&3e38f32.to_le_bytes());
    glb.bin[at + 12..at + 16].copy_from_slice(&(-3e38f32).to_le_bytes());
    let huge = glb.write(dir.path(), "hugeuv.glb");
    let found: Vec<_> = ["lod_bake_uv_overflow.glb", "lod_bake_uv_floor_overflow.glb"]
        .iter()
        .map(|name| {
            let copy = dir.path().join(name);
            std::fs::copy(root().join("fuzz/regressions").join(name), &copy).unwrap();
            copy
        })
        .collect();
    for (file, method) in [
        (&huge, "static"),
        (&huge, "per-bone"),
        (&found[0], "static"),
        (&found[0], "spectral"),
        (&found[1], "static"),
        (&found[1], "skeleton"),
    ] {
        let out = dir.path().join(format!(
            "out_{}_{method}",
            file.file_stem().unwrap().to_string_lossy()
        ));
        let _ = std::fs::remove_dir_all(&out);
        let m = lod_unmeasured(
            file,
            &out,
            &[
                "--method",
                method,
                "--lods",
                "200,60",
                "--samples",
                "8",
                "--planes",
                "30",
            ],
        );
        // The fuzzer's file is broken in other ways too: a clean refusal is fine, a panic not.
        let clean =
            m.output.status.success() || (file != &huge && m.output.status.code() == Some(1));
        assert!(
            clean && !m.stderr().contains("panicked"),
            "{method}: {}",
            m.stderr()
        );
    }
    // The measuring renders and the preview draw those coordinates too.
    let m = frond_measured(&lod_args(&huge, &dir.path().join("measured")), LONG);
    assert!(m.output.status.success(), "{}", m.stderr());
}

#[test]
fn a_stray_vertex_far_away_does_not_blow_up_the_card_coverage_grid() {
    // What the lod_chain fuzz target found: one leaf vertex thousands of tree heights away.
    // The cards method's coverage grid followed the height for its spacing and the bounds for
    // its size: 33 GB asked for, and an abort.
    let dir = tempfile::tempdir().unwrap();
    let mut glb = Glb::sample();
    let pos = glb.attribute("leaves", "POSITION");
    let at = glb.accessor_offset(pos);
    glb.bin[at + 8..at + 12].copy_from_slice(&20_000f32.to_le_bytes());
    glb.json["accessors"][pos]["max"][2] = json!(20_000.0);
    let file = glb.write(dir.path(), "stray.glb");
    let out = dir.path().join("out");
    let m = lod_unmeasured(&file, &out, &[]);
    eprintln!("stray vertex: {}", m.summary());
    assert!(m.output.status.success(), "{}", m.stderr());
    assert!(m.peak_rss < 1 << 30, "{} MB", m.peak_rss >> 20);
}

#[test]
fn a_ktx2_map_frond_cannot_decode_is_passed_through_and_counted() {
    // An ETC1S (BasisLZ) map: frond decodes UASTC only, so it is written as it was, but its
    // size still counts towards the texture memory limit.
    let mut ktx2 = ktx2_header_only(64, 64);
    let dfd = u32::from_le_bytes(ktx2[48..52].try_into().unwrap()) as usize;
    ktx2[dfd + 12] = 163; // KHR_DF_MODEL_ETC1S
    let dir = tempfile::tempdir().unwrap();
    let mut glb = Glb::sample();
    let t = glb.add_ktx2("etc1s", &ktx2);
    glb.set_map(1, "/occlusionTexture", t);
    let file = glb.write(dir.path(), "etc1s.glb");
    let out = dir.path().join("out");
    let m = lod_unmeasured(&file, &out, &[]);
    assert!(m.output.status.success(), "{}", m.stderr());
    let written = gltf_json(&out.join("etc1s_LOD0.glb"));
    let images: Vec<&str> = written["images"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|i| i["mimeType"].as_str())
        .collect();
    assert!(images.contains(&"image/ktx2"), "{images:?}");
    // 64² counts: a limit just under the sample's own maps plus it refuses the file.
    let m = frond_measured(
        &[
            "inspect",
            file.to_str().unwrap(),
            "--max-texture-memory",
            "16K",
        ],
        LONG,
    );
    assert_eq!(m.output.status.code(), Some(1), "{}", m.stderr());
    assert!(
        m.stderr().contains("'etc1s'") || m.stderr().contains("images decode"),
        "{}",
        m.stderr()
    );
}
