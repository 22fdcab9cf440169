//! `frond lod` end to end: the files, `<name>_report.json`, the Khronos validator on every output, a
//! round trip through our own importer (billboard corners where the pipeline meant them), the
//! per-bone ε property, VAT decoding back to motion, skeleton LODs whose foliage stays on its
//! branches, determinism and bad arguments.

use crate::common;

use std::path::{Path, PathBuf};

use common::*;
use frond_billboard::cloud::CloudParams;
use frond_export::LodInput;
use frond_export::lod_file::{FileOptions, write_glb};
use frond_export::mapping::Mapping;
use frond_export::spectral::SpectralSidecar;
use frond_export::vat::{VatFormat, VatSpace, decode_pivots, decode_rigid};
use frond_lod::cloud_build::{build_animated_cloud, sampled_worlds};
use frond_lod::joint_budget::{BillboardAnimation, JointCap};
use frond_lod::methods::per_bone::per_bone_clusters;
use frond_lod::methods::skeleton::build_skeleton_cloud;
use frond_lod::methods::spectral::{SpectralParams, build_spectral_cloud};
use frond_lod::methods::static_cloud::static_clusters;
use frond_lod::motion_budget::{ScreenBudget, apply_budget};
use frond_lod::{AnimatedBillboardCloud, BuildContext, LodLevel, LoopClock, RigidMotion};
use frond_render::Renderer;
use frond_scene::wood::WoodMesh;
use frond_scene::{ImportOptions, SampleOptions, Sampled, Tree, import, import_bytes, sample};
use frond_skeleton::{BoneDescriptionKind, SkeletonParams};
use frond_spectral::description::SpectralKind;
use glam::Vec3;

fn sapling() -> PathBuf {
    root().join("samples/sapling.glb")
}

fn glbs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "glb"))
        .collect();
    v.sort();
    v
}

fn assert_valid(file: &Path) {
    let Some(v) = validate(file) else {
        return;
    };
    assert_eq!(v["errors"], 0, "{}: {}", file.display(), v["messages"]);
    assert_eq!(v["warnings"], 0, "{}: {}", file.display(), v["messages"]);
}

/// Validator message codes (the first word of each message) of `file`.
fn message_codes(v: &serde_json::Value) -> Vec<String> {
    v["messages"]
        .as_array()
        .map(|m| {
            m.iter()
                .filter_map(|x| x.as_str()?.split_whitespace().next().map(str::to_string))
                .collect()
        })
        .unwrap_or_default()
}

/// No error, and no warning the input itself does not have: LOD files pass the input's
/// materials through, so a warning about them (a normal map without tangents) is the input's.
fn assert_valid_like(file: &Path, input: &Path) {
    let (Some(v), Some(of_input)) = (validate(file), validate(input)) else {
        return;
    };
    assert_eq!(v["errors"], 0, "{}: {}", file.display(), v["messages"]);
    let inherited = message_codes(&of_input);
    for code in message_codes(&v) {
        assert!(
            inherited.contains(&code),
            "{}: {code} not in the input's messages: {}",
            file.display(),
            v["messages"]
        );
    }
}

/// The nodes of a glTF document's first scene's roots.
fn scene_roots(json: &serde_json::Value) -> Vec<&serde_json::Value> {
    json["scenes"][0]["nodes"]
        .as_array()
        .expect("roots")
        .iter()
        .map(|n| &json["nodes"][n.as_u64().expect("index") as usize])
        .collect()
}

/// A joint budget that never binds (the half-pixel merges still apply).
const UNLIMITED_JOINTS: JointCap = JointCap {
    joints: usize::MAX,
    channels: usize::MAX,
};

#[test]
fn skin_lods_are_valid_and_reported() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("o");
    // Billboards, at the sizes' ε and texel density (the sample's textures are too small for a
    // billboard atlas within the cost budgets: the default chain is cards, checked elsewhere).
    let report = frond_lod(
        &sapling(),
        &out,
        &[
            "--lods",
            "300,60",
            "--method",
            "skeleton",
            "--no-cost-budgets",
        ],
    );
    let lods = &report.lods;
    assert_eq!(lods.len(), 3, "LOD0 plus one per --lods entry");
    // Triangles, billboards, bones, texture bytes, what was dropped and the method are
    // required fields of `LodEntry`: the typed read of the report checks each LOD has them.
    for (k, l) in lods.iter().enumerate() {
        assert_eq!(l.file, format!("sapling_LOD{k}.glb"));
        assert!(out.join(&l.file).exists());
        if k > 0 {
            assert!(l.epsilon.expect("epsilon") > 0.0);
            assert!(out.join(l.mapping.as_deref().expect("mapping")).exists());
            assert!(l.billboards > 0);
        }
    }
    assert_eq!(lods[1].method.name(), "skeleton-axis-angle");
    assert_eq!(lods[2].method.name(), "skeleton-axis-angle");
    // Nearer LODs cost more: ε grows and billboards shrink in number with distance.
    assert!(lods[2].epsilon.expect("epsilon") > lods[1].epsilon.expect("epsilon"));
    assert!(lods[2].triangles < lods[0].triangles);
    assert!(out.join("sapling_lods.glb").exists());
    for f in glbs(&out) {
        assert_valid(&f);
    }
    // The combined file: each LOD's mesh node a scene root named for UnityGLTF (starts with
    // LOD) and the suffix convention (one base, `_LOD<k>`); one animation per clip name.
    let tree = import(&out.join("sapling_lods.glb"), &ImportOptions::default()).expect("import");
    let json = gltf_json(&out.join("sapling_lods.glb"));
    let roots = scene_roots(&json);
    for k in 0..3 {
        let name = format!("LOD_sapling_LOD{k}");
        assert!(tree.rig.nodes.iter().any(|n| n.name == name), "{name} node");
        assert!(
            roots
                .iter()
                .any(|r| r["name"] == name.as_str() && r["mesh"].is_u64()),
            "{name} is a scene root with the LOD's mesh"
        );
    }
    let input = import(&sapling(), &ImportOptions::default()).expect("input");
    assert_eq!(tree.rig.clips.len(), input.rig.clips.len());
    for (a, b) in tree.rig.clips.iter().zip(&input.rig.clips) {
        assert_eq!(a.name, b.name);
        assert!(
            (a.duration() - b.duration()).abs() < 1e-4,
            "same clip length"
        );
    }
    // Mapping: every billboard's triangles are input foliage triangles, none twice.
    let m: Mapping = read_json(&out.join("sapling_LOD1.mapping.json"));
    let mut seen = std::collections::HashSet::new();
    for b in &m.billboards {
        for &t in &b.triangles {
            assert_eq!(input.triangles[t].part, frond_scene::Part::Foliage);
            assert!(seen.insert(t), "triangle {t} mapped twice");
        }
    }
}

#[test]
fn msft_lod_external_textures_and_vat_are_valid() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("o");
    let report = frond_lod(
        &sapling(),
        &out,
        &[
            "--lods",
            "120",
            "--msft-lod",
            "--external-textures",
            "--animation",
            "vat",
            "--method",
            "static",
        ],
    );
    for f in glbs(&out) {
        assert_valid(&f);
    }
    let l1 = &report.lods[1];
    let vat = l1.vat.as_ref().expect("vat files");
    for f in vat {
        assert!(out.join(f).exists(), "{f}");
    }
    assert!(out.join("shaders/frond_vat_rigid.wgsl").exists());
    let combined = std::fs::read(out.join("sapling_lods.glb")).expect("combined");
    let text = String::from_utf8_lossy(&combined);
    assert!(text.contains("MSFT_lod") && text.contains("MSFT_screencoverage"));
    // LOD0's mesh node carries the chain and names LOD1's, which is no scene root.
    let json = gltf_json(&out.join("sapling_lods.glb"));
    let nodes = json["nodes"].as_array().expect("nodes");
    let roots = scene_roots(&json);
    let lod0 = roots
        .iter()
        .find(|r| r["name"] == "LOD_sapling_LOD0")
        .expect("LOD0 mesh node is a root");
    let ids = lod0["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .expect("ids");
    assert_eq!(ids.len(), 1);
    assert_eq!(
        nodes[ids[0].as_u64().expect("id") as usize]["name"],
        "LOD_sapling_LOD1"
    );
    assert!(!roots.iter().any(|r| r["name"] == "LOD_sapling_LOD1"));
    assert!(
        std::fs::read_dir(&out)
            .expect("dir")
            .any(|e| e.is_ok_and(|e| e.path().extension().is_some_and(|x| x == "png"))),
        "external PNG textures written"
    );
}

/// Runs `frond lod` on the sapling with `extra` at 1 and 2 threads; every file but the report
/// must be byte-identical.
fn same_bytes_at_1_and_2_threads(extra: &[&str]) {
    let dir = tempfile::tempdir().expect("tmp");
    let run = |threads: &str, name: &str| {
        let out = dir.path().join(name);
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_frond"))
            .args(["lod", sapling().to_str().expect("utf-8"), "-o"])
            .arg(&out)
            .args(["--lods", "150,40", "--samples", "12", "--planes", "40"])
            .args(extra)
            .env("RAYON_NUM_THREADS", threads)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .status()
            .expect("runs");
        assert!(status.success());
        out
    };
    let a = run("1", "a");
    let b = run("2", "b");
    for f in std::fs::read_dir(&a).expect("dir") {
        let p = f.expect("entry").path();
        if p.file_name()
            .is_some_and(|n| n.to_string_lossy().ends_with("_report.json"))
            || p.is_dir()
        {
            continue;
        }
        let q = b.join(p.file_name().expect("name"));
        assert_eq!(
            std::fs::read(&p).expect("a"),
            std::fs::read(&q).expect("b"),
            "{} differs between thread counts",
            p.display()
        );
    }
}

#[test]
fn same_seed_same_bytes_whatever_the_threads() {
    same_bytes_at_1_and_2_threads(&[]);
}

#[test]
fn spectral_same_bytes_whatever_the_threads() {
    same_bytes_at_1_and_2_threads(&["--method", "spectral", "--animation", "spectral"]);
}

#[test]
fn spectral_lods_validate_and_carry_their_coefficients() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("o");
    let report = frond_lod(
        &sapling(),
        &out,
        &[
            "--lods",
            "150,40",
            "--method",
            "spectral",
            "--animation",
            "spectral",
        ],
    );
    assert_eq!(report.animation, "spectral");
    let lods = &report.lods;
    for (l, k) in lods[1..].iter().zip([15usize, 4]) {
        assert_eq!(l.method.name(), "spectral-axis-phase");
        let sp = spectral_section(l).expect("spectral section");
        assert_eq!(sp.clusters, k, "the k rule: height / 10");
        assert!(sp.residual < sp.motion_rms);
        let files = l.spectral_files.as_ref().expect("spectral files");
        let sidecar: SpectralSidecar = read_json(&out.join(&files[1]));
        assert_eq!(sidecar.billboards as usize, l.billboards);
        assert_eq!(sidecar.clip.as_deref(), Some("Wind"));
        let tex = std::fs::read(out.join(&files[0])).expect("texture");
        assert_eq!(sidecar.bytes, tex.len());
        assert_eq!(l.animation_bytes, tex.len());
        assert!(
            l.vat_equivalent_bytes.expect("VAT size beside it") > tex.len(),
            "the coefficients are smaller than VAT"
        );
        let img = image::load_from_memory_with_format(&tex, image::ImageFormat::OpenExr)
            .expect("EXR decodes");
        // Blocks of 2·terms texels per billboard, `per_row` to a row.
        let n = l.billboards as u64;
        let per_row = u64::from(sidecar.per_row);
        let terms = u64::from(sidecar.terms);
        assert_eq!(u64::from(img.height()), n.div_ceil(per_row));
        assert_eq!(u64::from(img.width()), 2 * terms * per_row);
        // Billboards need no motion joints: the skin holds rig nodes only, never more than the
        // input's own joints (LOD0).
        assert!(l.bones <= lods[0].bones);
    }
    assert!(out.join("shaders/frond_spectral.wgsl").exists());
    for f in glbs(&out) {
        assert_valid(&f);
    }
    // A method whose motion has no spectral form is refused, with no output.
    let bad = dir.path().join("bad");
    let o = frond(&[
        "lod",
        sapling().to_str().expect("utf-8"),
        "-o",
        bad.to_str().expect("utf-8"),
        "--method",
        "static",
        "--animation",
        "spectral",
        "--lods",
        "60",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("sampled rigid motion"), "{err}");
    assert!(!bad.exists(), "no partial output");
}

#[test]
fn spectral_skin_round_trip() {
    let (tree, sampled, params, pixel) = setup(&sapling(), 150.0);
    let renderer = Renderer::new().expect("renderer");
    let sp = SpectralParams {
        kind: SpectralKind::AxisPhase,
        clusters: 5,
        zone_size: 0.02 * tree.bounds.size(),
        bins: 4,
        restarts: 1,
        seed: 1,
        max_iterations: 10,
        shared_bone: true,
        one_motion_per_cluster: false,
    };
    let (mut cloud, _, _) = with_context(&renderer, &tree, &sampled, &params, pixel, |ctx| {
        build_spectral_cloud(ctx, &sp)
    })
    .expect("spectral cloud");
    apply_budget(
        &mut cloud,
        &mut WoodMesh::default(),
        &tree,
        &sampled,
        &ScreenBudget {
            pixel,
            epsilon: pixel,
            joints: UNLIMITED_JOINTS,
            keep_sub_pixel_motion: false,
        },
        BillboardAnimation::Joints,
    );
    assert!(
        cloud
            .billboards
            .iter()
            .any(|b| matches!(b.motion, Some(RigidMotion::Spectral(_)))),
        "some billboards keep spectral motion"
    );
    round_trip(&Built {
        tree,
        sampled,
        cloud,
        epsilon: pixel,
    });
}

#[test]
fn bad_arguments_fail_cleanly_without_output() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("o");
    for args in [
        vec!["--lods", "0"],
        vec!["--pixel-error", "-1"],
        vec!["--epsilon", "abc"],
    ] {
        let mut all = vec![
            "lod".to_string(),
            sapling().to_str().expect("utf-8").to_string(),
        ];
        all.extend(args.iter().map(|s| s.to_string()));
        all.extend(["-o".to_string(), out.display().to_string()]);
        let refs: Vec<&str> = all.iter().map(|s| s.as_str()).collect();
        let r = frond(&refs);
        assert!(!r.status.success(), "{args:?} must fail");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    let missing = frond(&[
        "lod",
        "no/such/tree.glb",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/tree.glb"));
}

// ---- Round trips through the library, with the pipeline's own intent to compare against ----

struct Built {
    tree: Tree,
    sampled: Sampled,
    cloud: AnimatedBillboardCloud,
    epsilon: f32,
}

/// The tree at `path` sampled 16 times, cloud parameters for a LOD `screen` pixels tall, and
/// that LOD's pixel size.
fn setup(path: &Path, screen: f32) -> (Tree, Sampled, CloudParams, f32) {
    let tree = import(path, &ImportOptions::default()).expect("import");
    let sampled = sample(
        &tree,
        &SampleOptions {
            clip: None,
            samples: 16,
        },
    )
    .expect("sample");
    let pixel = tree.bounds.height() / screen;
    let mut params = CloudParams::default();
    params.search.epsilon = pixel;
    params.search.candidates = 60;
    params.bake.texels_per_unit = 1.0 / pixel;
    (tree, sampled, params, pixel)
}

/// Runs `f` with the build context of a LOD whose pixel is `pixel` world units.
fn with_context<R>(
    renderer: &Renderer,
    tree: &Tree,
    sampled: &Sampled,
    params: &CloudParams,
    pixel: f32,
    f: impl FnOnce(&BuildContext) -> R,
) -> R {
    let level = LodLevel {
        screen_height: tree.bounds.height() / pixel,
        pixel,
        epsilon: pixel,
        texels_per_unit: 1.0 / pixel,
        wood_error: pixel,
    };
    let clock = LoopClock::of(tree, sampled);
    f(&BuildContext {
        renderer,
        tree,
        sampled,
        clock: &clock,
        level: &level,
        index: 0,
        cloud: params,
        scale: tree.bounds.size(),
        seed: params.search.seed,
        max_billboards: None,
        max_foliage_triangles: None,
        max_alpha_tested_area: None,
        max_joints: None,
        baked_wood: None,
    })
}

fn build(path: &Path, per_bone: bool, screen: f32) -> Built {
    let (tree, sampled, params, pixel) = setup(path, screen);
    let clusters = if per_bone {
        per_bone_clusters(&tree, &sampled)
    } else {
        static_clusters(&sampled)
    };
    let renderer = Renderer::new().expect("renderer");
    let name = if per_bone { "per-bone" } else { "static" };
    let (mut cloud, _) = with_context(&renderer, &tree, &sampled, &params, pixel, |ctx| {
        build_animated_cloud(ctx, tree.rig.clone(), false, &clusters, name)
    })
    .expect("cloud");
    apply_budget(
        &mut cloud,
        &mut WoodMesh::default(),
        &tree,
        &sampled,
        &ScreenBudget {
            pixel,
            epsilon: pixel,
            joints: UNLIMITED_JOINTS,
            keep_sub_pixel_motion: false,
        },
        BillboardAnimation::Joints,
    );
    Built {
        tree,
        sampled,
        cloud,
        epsilon: pixel,
    }
}

/// Writes the cloud alone, re-imports it and compares every billboard corner at every clock
/// sample with `corners_at`.
fn round_trip(b: &Built) {
    let images = frond_export::downscale::Downscaler::new(&b.tree);
    let file = write_glb(
        &[LodInput {
            name: "t_LOD1".into(),
            tree: &b.tree,
            images: &images,
            rig: &b.cloud.rig,
            parts: Vec::new(),
            cloud: Some(&b.cloud),
            clips: b.cloud.playable_clips.clone(),
            image_sizes: &Default::default(),
            vat_uvs: None,
            spectral_uvs: None,
            // As `frond lod` writes every LOD but LOD0.
            byte_weights: true,
            billboard_normals: Default::default(),
        }],
        &FileOptions::default(),
    )
    .expect("write");
    let back = import_bytes(
        Path::new("t_LOD1.glb"),
        &file.glb,
        &ImportOptions::default(),
    )
    .expect("re-import");
    let clip = b
        .cloud
        .clock
        .clip
        .map(|c| b.cloud.rig.clips[c].name.clone());
    let clip_back = clip.as_ref().and_then(|n| back.clip_index(Some(n)));
    let worlds = sampled_worlds(&b.cloud.rig, &b.cloud.clock);
    let rest = b.cloud.rest_inverse();
    let n = worlds.len();
    let h = b.tree.bounds.height();
    let mut worst = 0.0f32;
    for (s, world) in worlds.iter().enumerate() {
        let pose = frond_scene::sampling::pose_at(&back, clip_back, b.cloud.clock.time(s));
        for i in 0..b.cloud.billboards.len() {
            let want = b.cloud.corners_at(i, world, &rest, s, n);
            for (c, w) in want.iter().enumerate() {
                worst = worst.max(pose[4 * i + c].distance(*w));
            }
        }
    }
    assert!(
        worst <= 1e-4 * h,
        "billboard corners after the round trip are off by {worst} (tree height {h})"
    );
}

#[test]
fn per_bone_round_trip_and_epsilon_in_every_sample() {
    let b = build(&sapling(), true, 300.0);
    round_trip(&b);
    // Every foliage triangle's centre stays within ε of its billboard's plane in every sample.
    let worlds = sampled_worlds(&b.cloud.rig, &b.cloud.clock);
    let rest = b.cloud.rest_inverse();
    let n = worlds.len();
    let k_of: std::collections::HashMap<usize, usize> = b
        .sampled
        .foliage
        .iter()
        .enumerate()
        .map(|(k, &t)| (t, k))
        .collect();
    let mut worst = 0.0f32;
    for (i, bb) in b.cloud.billboards.iter().enumerate() {
        for (s, world) in worlds.iter().enumerate() {
            let c = b.cloud.corners_at(i, world, &rest, s, n);
            let normal = (c[1] - c[0]).cross(c[2] - c[1]).normalize();
            for t in &bb.triangles {
                let centre = b.sampled.trajectory(k_of[t])[s];
                worst = worst.max((centre - c[0]).dot(normal).abs());
            }
        }
    }
    assert!(
        worst <= b.epsilon * 1.001,
        "a triangle centre is {worst} from its plane, ε = {}",
        b.epsilon
    );
}

#[test]
fn static_round_trip_on_a_real_exporters_tree() {
    let b = build(&fixture("bush_1.glb"), false, 120.0);
    assert!(b.cloud.billboards.iter().any(|x| x.motion.is_some()));
    round_trip(&b);
}

#[test]
fn vat_textures_decode_back_to_the_motion_in_every_space() {
    let b = build(&sapling(), false, 150.0);
    for space in [VatSpace::Gltf, VatSpace::Unity, VatSpace::Unreal] {
        for format in [VatFormat::ExrHalf, VatFormat::Png16] {
            let vat = frond_export::cloud_motion::vat_textures(&b.cloud, format, "t", space)
                .expect("vat");
            assert_eq!(vat.sidecar.version, frond_export::vat::SIDECAR_VERSION);
            assert_eq!(vat.sidecar.space, space);
            assert_eq!(vat.sidecar.coordinate_system, space.coordinate_system());
            assert_eq!(vat.sidecar.clips.len(), 1);
            assert_eq!(vat.sidecar.clips[0].name.as_deref(), Some("Wind"));
            assert_eq!(vat.sidecar.clips[0].frames, vat.sidecar.frames);
            let frames = decode_rigid(&vat.position.bytes, &vat.rotation.bytes, &vat.sidecar)
                .expect("decode");
            let pivots = decode_pivots(&vat.pivot.bytes, &vat.sidecar).expect("pivots");
            let worlds = sampled_worlds(&b.cloud.rig, &b.cloud.clock);
            let rest = b.cloud.rest_inverse();
            let n = worlds.len();
            let size = b.tree.bounds.size();
            // Half floats keep 11 bits (of centimetres for Unreal); PNG16 maps the bounds onto
            // 65535 steps.
            let tol = match format {
                VatFormat::ExrHalf => size * 2e-3,
                VatFormat::Png16 => size * 2e-4,
            };
            let mut worst = 0.0f32;
            for (i, bb) in b.cloud.billboards.iter().enumerate() {
                let pivot = bb.quad.center;
                // The engine reads the rest pivot as (uv2.x, uv3.x, uv3.y) after its importer
                // flips v (Unity) or not.
                let [[px, _], [py, pz]] = vat.pivot_uv[i];
                let read = match space {
                    VatSpace::Unity => Vec3::new(px, py, 1.0 - pz),
                    _ => Vec3::new(px, py, pz),
                };
                assert!(space.point_to_gltf(read).distance(pivot) < 1e-4);
                // The pivot texture holds the same point, to half-float precision.
                assert!(pivots[i].distance(read) <= read.abs().max_element() * 1e-3 + 1e-4);
                for s in 0..n {
                    let want = b.cloud.corners_at(i, &worlds[s], &rest, s, n);
                    let f = frames[i][s];
                    for (c, w) in bb.quad.corners().iter().zip(want) {
                        // The importer turned the mesh's corner into the engine's space.
                        let got = f.rotation * (space.point(*c) - read) + f.position;
                        worst = worst.max(space.point_to_gltf(got).distance(w));
                    }
                }
            }
            assert!(
                worst <= tol,
                "{space:?} {format:?}: decoded corners off by {worst} > {tol}"
            );
        }
    }
}

#[test]
fn fixture_trees_every_method_and_mode_validate() {
    let trees = [fixture("bush_1.glb"), fixture("sapling_blender.glb")];
    every_method_and_mode_validates(&trees, 0);
}

#[test]
fn shared_trees_every_method_and_mode_validate() {
    let trees = frond_testdata::require_trees!([
        "pine_medium.glb",
        "pine_medium_blender.glb",
        "oak_medium.glb",
        "oak_medium_blendedleaves.glb",
    ]);
    every_method_and_mode_validates(&trees, 1);
}

/// `frond lod` on each of `trees` twice (two LODs; one LOD with VAT animation and a method),
/// every output through the Khronos validator. The VAT format and the method alternate with
/// the tree's index counted from `first`.
fn every_method_and_mode_validates(trees: &[PathBuf], first: usize) {
    let dir = tempfile::tempdir().expect("tmp");
    for (i, input) in (first..).zip(trees) {
        let name = input.file_name().expect("file name").to_string_lossy();
        let tree = import(input, &ImportOptions::default()).expect("import");
        let vat = if i % 2 == 0 { "vat" } else { "vat-png16" };
        let method = if i % 2 == 0 { "per-bone" } else { "static" };
        for (k, extra) in [
            vec!["--lods", "200,60"],
            vec!["--lods", "100", "--animation", vat, "--method", method],
        ]
        .iter()
        .enumerate()
        {
            let out = dir.path().join(format!("{i}_{k}"));
            let report = frond_lod(input, &out, extra);
            let lods = &report.lods;
            // LOD0 is the input: every non-degenerate triangle, wood and foliage.
            let kept = tree.triangles.iter().filter(|t| !t.degenerate).count();
            assert_eq!(lods[0].triangles, kept, "{name} LOD0");
            for l in &lods[1..] {
                assert!(l.method.name() == "cards" || l.billboards > 0, "{name}");
                assert!(
                    l.triangles < lods[0].triangles,
                    "{name}: a LOD is smaller than the input"
                );
            }
            for f in glbs(&out) {
                assert_valid_like(&f, input);
            }
        }
    }
}

#[test]
fn distances_give_screen_heights_by_holst_eq_3() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("o");
    let report = frond_lod(
        &sapling(),
        &out,
        &["--distances", "40", "--fov", "90", "--resolution", "1000"],
    );
    let h = written_f64(report.tree_height);
    // 90° fov: pc = 500 pixels per unit of height/distance.
    let want = h / 40.0 * 500.0;
    let got = written_f64(report.lods[1].screen_height.expect("screen height"));
    assert!((got - want).abs() < 1e-3 * want, "{got} vs {want}");
    let eps = written_f64(report.lods[1].epsilon.expect("eps"));
    assert!((eps - h / want).abs() < 1e-4 * eps, "ε is one pixel");
}

/// `samples/sapling.glb` with its clip duplicated under a second name.
fn two_clip_sapling(dir: &Path) -> PathBuf {
    let bytes = std::fs::read(sapling()).expect("sapling");
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().expect("header")) as usize;
    let mut json: serde_json::Value =
        serde_json::from_slice(&bytes[20..20 + json_len]).expect("json chunk");
    let mut gust = json["animations"][0].clone();
    gust["name"] = serde_json::json!("Gust");
    json["animations"]
        .as_array_mut()
        .expect("animations")
        .push(gust);
    let bin_chunk = &bytes[20 + json_len..];
    let bin =
        &bin_chunk[8..8 + u32::from_le_bytes(bin_chunk[0..4].try_into().expect("bin")) as usize];
    let glb =
        frond_scene::gltf_writer::glb_container(&serde_json::to_vec(&json).expect("json"), bin);
    let path = dir.join("two_clips.glb");
    std::fs::write(&path, glb).expect("write");
    path
}

#[test]
fn bone_bound_lods_keep_every_clip_and_rigid_fit_lods_say_what_they_drop() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = two_clip_sapling(dir.path());
    let out = dir.path().join("o");
    // The default chain of a card tree: cards follow their bones, so every clip plays.
    let cards = frond_lod(&input, &dir.path().join("c"), &["--lods", "300,60"]);
    for k in 0..3 {
        assert_eq!(cards.lods[k].clips, ["Wind", "Gust"], "LOD{k}");
    }
    // Skeleton at 300 px merges nothing unseen on the sapling: per-bone clouds on the input's
    // bones, so every clip plays.
    let skeleton = frond_lod(
        &input,
        &dir.path().join("s"),
        &["--lods", "300", "--method", "skeleton", "--no-cost-budgets"],
    );
    assert_eq!(skeleton.lods[1].clips, ["Wind", "Gust"]);
    let report = frond_lod(
        &input,
        &out,
        &[
            "--lods",
            "300,60",
            "--method",
            "static",
            "--no-cost-budgets",
        ],
    );
    let clips = |k: usize| -> &[String] { &report.lods[k].clips };
    assert_eq!(clips(0), ["Wind", "Gust"]);
    // Static billboards carry motion sampled from the first clip only.
    assert_eq!(clips(2), ["Wind"]);
    let dropped = &report.lods[2].dropped.clips;
    assert!(dropped.iter().any(|d| d.starts_with("Gust")));
    for f in glbs(&out) {
        assert_valid(&f);
    }
    // The combined file has both clips, each as long as the input's.
    let tree = import(&out.join("two_clips_lods.glb"), &ImportOptions::default()).expect("import");
    let names: Vec<&str> = tree.rig.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Wind", "Gust"]);
}

#[test]
fn skeleton_lods_validate_and_report_what_they_did() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("sk");
    // 40 px: above the impostor class, whose few billboards would cap the clouds.
    let report = frond_lod(
        &sapling(),
        &out,
        &["--method", "skeleton", "--lods", "150,40"],
    );
    for f in glbs(&out) {
        assert_valid(&f);
    }
    let lods = &report.lods;
    let sk = |k: usize| skeleton_section(&lods[k]).expect("skeleton section");
    for (k, l) in lods.iter().enumerate().skip(1) {
        let sk = sk(k);
        assert_eq!(l.method.name(), "skeleton-axis-angle");
        assert!(
            sk.budget.is_none(),
            "no --clouds: merges that cannot be seen"
        );
        assert!(!sk.trunk_on_original_skeleton);
        assert!(sk.collapses.is_empty());
        // Attached: no leaf moves more than half a pixel off its branch.
        let tol = written_f64(sk.attach_tolerance);
        assert!(written_f64(sk.detachment_max) <= tol * 1.01 + 1e-5);
        assert!(written_f64(sk.foliage_error_rms) <= written_f64(sk.displacement_tolerance) * 1.5);
    }
    let clouds = |k: usize| sk(k).clouds;
    assert!(clouds(2) < sk(2).foliage_bones);
    assert!(clouds(2) <= clouds(1), "farther LODs merge more");
    // A budget CJR alone cannot reach: collapses, the trunk on the input's skeleton.
    let out1 = dir.path().join("sk1");
    let report = frond_lod(
        &sapling(),
        &out1,
        &[
            "--method",
            "skeleton-axis-angle",
            "--lods",
            "60",
            "--clouds",
            "2",
        ],
    );
    for f in glbs(&out1) {
        assert_valid(&f);
    }
    let sk = skeleton_section(&report.lods[1]).expect("skeleton section");
    assert!(sk.trunk_on_original_skeleton);
    assert!(!sk.collapses.is_empty());
    assert!(sk.clouds == 2 || sk.stopped_by.is_some());
    assert_eq!(report.lods[1].clips.len(), 1);
}

/// Skeleton clouds of the sapling at `screen` px with `clouds` (None: the default rule).
fn build_skeleton(screen: f32, clouds: Option<usize>) -> (Built, frond_skeleton::SkeletonReport) {
    let (tree, sampled, params, pixel) = setup(&sapling(), screen);
    let renderer = Renderer::new().expect("renderer");
    let sk = SkeletonParams {
        kind: BoneDescriptionKind::RotationSpectral,
        clouds,
        average_bone: false,
        bins: 4,
        attach_tolerance: 0.5 * pixel,
        displacement_tolerance: pixel,
    };
    let (cloud, _, report) = with_context(&renderer, &tree, &sampled, &params, pixel, |ctx| {
        build_skeleton_cloud(ctx, &sk)
    })
    .expect("cloud");
    (
        Built {
            tree,
            sampled,
            cloud,
            epsilon: pixel,
        },
        report,
    )
}

#[test]
fn skeleton_billboards_stay_on_the_wood_they_grew_from() {
    let (b, report) = build_skeleton(30.0, None);
    assert!(report.merges > 0, "the test needs merged bones");
    assert!(!report.trunk_on_original_skeleton);
    let worlds = sampled_worlds(&b.cloud.rig, &b.cloud.clock);
    let rest = b.cloud.rest_inverse();
    let n = worlds.len();
    let mut worst = 0.0f32;
    let mut merged = 0;
    for (i, bb) in b.cloud.billboards.iter().enumerate() {
        // The wood its triangles grew from: their input bone, which the LOD's wood follows.
        let t = bb.triangles[0];
        let bone = b.tree.triangles[t].bone.expect("bound") as usize;
        let wood = b.tree.bones[bone].node;
        if bb.follows != Some(wood) {
            merged += 1;
        }
        let local: Vec<glam::Vec3> = (0..n)
            .map(|s| {
                let centre = b
                    .cloud
                    .transform_at(i, &worlds[s], &rest, s, n)
                    .transform_point3(bb.quad.center);
                worlds[s][wood].inverse().transform_point3(centre)
            })
            .collect();
        for l in &local {
            worst = worst.max(l.distance(local[0]));
        }
    }
    assert!(merged > 0, "some billboards follow a common-rotation bone");
    // Within the attachment tolerance (half a pixel), as the report says.
    assert!(
        worst <= report.attach_tolerance * 1.01 + 1e-5,
        "a billboard drifts {worst} off its wood (tolerance {})",
        report.attach_tolerance
    );
    assert!(report.detachment_max <= report.attach_tolerance * 1.01 + 1e-5);
}

#[test]
fn skeleton_round_trip_with_a_resampled_and_collapsed_rig() {
    for clouds in [None, Some(2)] {
        let (mut b, report) = build_skeleton(60.0, clouds);
        assert_eq!(report.trunk_on_original_skeleton, clouds.is_some());
        apply_budget(
            &mut b.cloud,
            &mut WoodMesh::default(),
            &b.tree,
            &b.sampled,
            &ScreenBudget {
                pixel: b.epsilon,
                epsilon: b.epsilon,
                joints: UNLIMITED_JOINTS,
                keep_sub_pixel_motion: false,
            },
            BillboardAnimation::Joints,
        );
        assert_eq!(b.cloud.playable_clips, vec![0], "the resampled clip only");
        round_trip(&b);
    }
}
