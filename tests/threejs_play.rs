//! three.js plays our trees the way frond samples them: the world-space position of every vertex,
//! as three.js's GLTFLoader + AnimationMixer + SkinnedMesh.getVertexPosition compute it headlessly
//! in Node (`tools/three_sample.mjs`), matches `frond_scene::sampling::pose_at` at the same clip
//! time, within 1e-5 × tree height.
//!
//! Vertex correspondence: three.js makes one Mesh per glTF primitive whose vertices are the
//! POSITION accessor's, in order (strips and fans only get a new index buffer); frond concatenates
//! the triangle primitives of every mesh node, visiting nodes in `Tree::node_order`, without
//! deduplication. `frond_order` rebuilds that layout from the file's JSON and the node/primitive
//! indices the script reports, so vertices are compared one to one; when the layouts cannot be
//! lined up (a file frond reads differently) the comparison falls back to point sets: every
//! three.js vertex against the nearest frond vertex of the same time (grid hash).
//!
//! `three` comes from tools/package.json like the validator and gltfpack; when `node` or the
//! packages in `tools/node_modules` are missing (`.ci/run` installs them), a test that only plays
//! trees in three.js skips with one `skipped:` line (`common::node_tools`), and one that also
//! checks frond's own output skips only its three.js (and validator) steps.
//!
//! The same check runs on every file `frond lod` writes (LOD0, the billboard-cloud LODs and the
//! combined file): three.js plays our skins, billboards included, exactly where frond's importer
//! and sampler put them, and the LOD clips keep the input's phase and length.

use crate::common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use frond_scene::sampling::pose_at;
use frond_scene::{ImportOptions, Tree, import};
use glam::Vec3;

/// One three.js mesh (one glTF primitive) as sampled by `three_sample.mjs`.
#[derive(Debug, Clone)]
#[expect(
    dead_code,
    reason = "the sampler's output whole: its name and mesh index show in a failure's Debug"
)]
pub struct ThreeMesh {
    /// The three.js object's name (the glTF mesh's or node's, as GLTFLoader names it).
    pub name: String,
    /// glTF node index the object was made from (None when the script could not tell).
    pub node: Option<usize>,
    /// glTF mesh index the object was made from.
    pub mesh: Option<usize>,
    /// Index of the glTF primitive in its mesh that the object draws.
    pub primitive: Option<usize>,
    /// A three.js SkinnedMesh (bound to a skeleton), not a plain Mesh.
    pub skinned: bool,
    /// World positions, one Vec per requested time.
    pub positions: Vec<Vec<Vec3>>,
}

/// One clip as played by three.js.
#[derive(Debug, Clone)]
pub struct ThreeClip {
    /// None for a file without animations (rest pose).
    pub name: Option<String>,
    /// The clip's length in seconds as three.js counts it (its last key time).
    pub duration: f32,
    /// The clip times sampled, seconds of the file's own time base.
    pub times: Vec<f32>,
    /// Every mesh three.js made, in its scene traversal order.
    pub meshes: Vec<ThreeMesh>,
}

fn usize_of(v: &serde_json::Value) -> Option<usize> {
    v.as_u64().map(|n| n as usize)
}

/// Plays `glb` in three.js (`tools`: the `tools/` folder with the Node clients installed, from
/// `common::node_tools`): clip `clip` (None: the first clip, or the rest pose when the file has
/// none) at `times` seconds of the file's own time base; world positions per mesh and time.
pub fn three_play(tools: &Path, glb: &Path, clip: Option<&str>, times: &[f32]) -> ThreeClip {
    let times_arg = times
        .iter()
        .map(|t| format!("{t:?}"))
        .collect::<Vec<_>>()
        .join(",");
    let mut cmd = Command::new("node");
    cmd.arg(tools.join("three_sample.mjs"))
        .arg(glb)
        .arg("--times")
        .arg(&times_arg);
    if let Some(c) = clip {
        cmd.arg("--clip").arg(c);
    }
    let out = cmd.output().expect("node runs three_sample.mjs");
    assert!(
        out.status.success(),
        "three_sample.mjs {glb:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("three_sample.mjs prints JSON");
    let c = &doc["clips"][0];
    assert!(c.is_object(), "no clip in three_sample output for {glb:?}");
    let meshes = c["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .map(|m| {
            let count = usize_of(&m["vertex_count"]).expect("vertex_count");
            let positions = m["positions"]
                .as_array()
                .expect("positions")
                .iter()
                .map(|flat| {
                    let flat = flat.as_array().expect("flat positions");
                    assert_eq!(flat.len(), 3 * count);
                    flat.chunks_exact(3)
                        .map(|p| {
                            let f = |v: &serde_json::Value| v.as_f64().expect("number") as f32;
                            Vec3::new(f(&p[0]), f(&p[1]), f(&p[2]))
                        })
                        .collect()
                })
                .collect::<Vec<Vec<Vec3>>>();
            assert_eq!(positions.len(), times.len());
            ThreeMesh {
                name: m["name"].as_str().unwrap_or_default().to_owned(),
                node: usize_of(&m["node"]),
                mesh: usize_of(&m["mesh"]),
                primitive: usize_of(&m["primitive"]),
                skinned: m["skinned"].as_bool().unwrap_or(false),
                positions,
            }
        })
        .collect();
    ThreeClip {
        name: c["name"].as_str().map(str::to_owned),
        duration: c["duration"].as_f64().unwrap_or(0.0) as f32,
        times: times.to_vec(),
        meshes,
    }
}

/// World positions three.js gives `glb` at `times` of clip `clip`: per time, every mesh's
/// vertices in the script's (scene traversal) order, flattened.
pub fn three_positions(
    tools: &Path,
    glb: &Path,
    clip: Option<&str>,
    times: &[f32],
) -> Vec<Vec<Vec3>> {
    flatten(&three_play(tools, glb, clip, times))
}

fn flatten(play: &ThreeClip) -> Vec<Vec<Vec3>> {
    (0..play.times.len())
        .map(|s| {
            play.meshes
                .iter()
                .flat_map(|m| m.positions[s].iter().copied())
                .collect()
        })
        .collect()
}

/// For every vertex of `flatten(play)`, its index in `tree.vertices`, when the layouts line up:
/// frond visits `tree.rig.order`, and appends the vertices of each triangle-mode primitive
/// (modes 4, 5, 6) of each mesh node. None when any three.js mesh lacks its indices or the counts
/// disagree.
pub fn frond_order(glb: &Path, tree: &Tree, play: &ThreeClip) -> Option<Vec<usize>> {
    let json = common::gltf_json(glb);
    let mut base: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
    let mut next = 0usize;
    for &ni in &tree.rig.order {
        let Some(mi) = usize_of(&json["nodes"][ni]["mesh"]) else {
            continue;
        };
        let prims = json["meshes"][mi]["primitives"].as_array()?;
        for (pi, p) in prims.iter().enumerate() {
            let mode = usize_of(&p["mode"]).unwrap_or(4);
            if !(4..=6).contains(&mode) {
                continue;
            }
            let acc = usize_of(&p["attributes"]["POSITION"])?;
            let count = usize_of(&json["accessors"][acc]["count"])?;
            base.insert((ni, pi), (next, count));
            next += count;
        }
    }
    if next != tree.vertices.len() {
        return None;
    }
    let mut order = Vec::with_capacity(next);
    for m in &play.meshes {
        let (start, count) = *base.get(&(m.node?, m.primitive?))?;
        if count != m.positions.first().map_or(0, Vec::len) {
            return None;
        }
        order.extend(start..start + count);
    }
    (order.len() == next).then_some(order)
}

/// Largest distance from a point of `a` to the nearest point of `b`, searched within `radius`
/// (grid hash with cells of that size); infinity when some point of `a` has no point of `b`
/// that near.
pub fn nearest_max_distance(a: &[Vec3], b: &[Vec3], radius: f32) -> f32 {
    assert!(radius > 0.0);
    let cell = |p: Vec3| (p / radius).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    for (i, &p) in b.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i as u32);
    }
    let mut worst = 0.0f32;
    for &p in a {
        let c = cell(p);
        let mut best = f32::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) {
                        for &j in list {
                            best = best.min(p.distance(b[j as usize]));
                        }
                    }
                }
            }
        }
        if best > radius {
            best = f32::INFINITY;
        }
        worst = worst.max(best);
    }
    worst
}

/// How three.js and frond agree on one clip.
#[derive(Debug)]
pub struct Agreement {
    /// Largest vertex distance over all times.
    pub max_distance: f32,
    /// Per time.
    pub per_time: Vec<f32>,
    /// Compared one to one (else as point sets).
    pub one_to_one: bool,
    /// Vertices three.js drew at the first time.
    pub vertices: usize,
    /// Largest displacement of a vertex from its time-0 position in three.js (proves the clip moves).
    pub max_motion: f32,
}

/// Plays clip `clip` of `glb` (already imported as `tree`) in three.js at `rel_times` seconds
/// after the clip's start and compares every vertex with frond's `pose_at` at the same time.
/// Point-set fallback searches within `radius`.
pub fn compare_with_frond(
    tools: &Path,
    glb: &Path,
    tree: &Tree,
    clip: usize,
    rel_times: &[f32],
    radius: f32,
) -> Agreement {
    let c = &tree.rig.clips[clip];
    let abs: Vec<f32> = rel_times.iter().map(|t| c.start + t).collect();
    let play = three_play(tools, glb, Some(&c.name), &abs);
    compare_play(glb, tree, clip, &play, radius)
}

/// [`compare_with_frond`] on a clip already played by [`three_play`] (at absolute clip times).
pub fn compare_play(
    glb: &Path,
    tree: &Tree,
    clip: usize,
    play: &ThreeClip,
    radius: f32,
) -> Agreement {
    let c = &tree.rig.clips[clip];
    let abs = &play.times;
    assert_eq!(play.name.as_deref(), Some(c.name.as_str()));
    assert!(
        (play.duration - c.end).abs() <= 1e-4 * c.end.max(1.0),
        "three.js clip duration {} vs frond end {}",
        play.duration,
        c.end
    );
    let three = flatten(play);
    let order = frond_order(glb, tree, play);
    let mut per_time = Vec::with_capacity(abs.len());
    for (s, &t) in abs.iter().enumerate() {
        let frond = pose_at(tree, Some(clip), t);
        let d = match &order {
            Some(order) => three[s]
                .iter()
                .zip(order)
                .map(|(p, &i)| p.distance(frond[i]))
                .fold(0.0, f32::max),
            None => nearest_max_distance(&three[s], &frond, radius),
        };
        per_time.push(d);
    }
    let max_motion = three
        .iter()
        .flat_map(|pose| pose.iter().zip(&three[0]).map(|(p, q)| p.distance(*q)))
        .fold(0.0, f32::max);
    Agreement {
        max_distance: per_time.iter().copied().fold(0.0, f32::max),
        per_time,
        one_to_one: order.is_some(),
        vertices: three.first().map_or(0, Vec::len),
        max_motion,
    }
}

/// Trees to check: the sample sapling and ez-tree's bush_1 (a fixture).
fn trees() -> Vec<PathBuf> {
    vec![
        common::root().join("samples/sapling.glb"),
        common::fixture("bush_1.glb"),
    ]
}

#[test]
fn threejs_plays_trees_like_frond_samples_them() {
    let Some(tools) = common::node_tools() else {
        return;
    };
    for path in trees() {
        let tree = import(&path, &ImportOptions::default()).expect("tree imports");
        assert!(!tree.rig.clips.is_empty(), "{path:?} has a clip");
        let height = tree.bounds.height();
        // frond skins in f32 (three.js in f64 from the same f32 data): a few dozen ulps through
        // the bone chain and the weighted sum, ~1e-6 of the coordinates. Measured: 2e-7 × height
        // (sapling, bush_1). The brief's bound was 1e-4 × height; 1e-5 still leaves 40× headroom.
        let tolerance = 1e-5 * height;
        let period = tree.rig.clips[0].duration();
        // The four quarter points of the loop, plus one between keys (interpolation).
        let times = [
            0.0,
            period / 4.0,
            period / 2.0,
            3.0 * period / 4.0,
            0.37 * period,
        ];
        let a = compare_with_frond(&tools, &path, &tree, 0, &times, 10.0 * tolerance);
        eprintln!(
            "{}: {} vertices, {}, height {height:.3}, max distance {:.3e} ({:.3e} × height) per time {:?}, motion {:.3e}",
            path.file_name().unwrap_or_default().to_string_lossy(),
            a.vertices,
            if a.one_to_one {
                "one to one"
            } else {
                "as point sets"
            },
            a.max_distance,
            a.max_distance / height,
            a.per_time,
            a.max_motion,
        );
        assert_eq!(a.vertices, tree.vertices.len(), "{path:?}: vertex count");
        assert!(a.one_to_one, "{path:?}: vertices line up one to one");
        assert!(
            a.max_distance <= tolerance,
            "{path:?}: three.js and frond differ by {} (> {tolerance})",
            a.max_distance
        );
        // The comparison is not of two rest poses: the wind moves the tree far more than that.
        assert!(
            a.max_motion > 100.0 * tolerance,
            "{path:?}: the clip barely moves ({})",
            a.max_motion
        );
    }
}

#[test]
fn point_set_fallback_agrees_with_the_one_to_one_match() {
    let Some(tools) = common::node_tools() else {
        return;
    };
    let path = common::root().join("samples/sapling.glb");
    let tree = import(&path, &ImportOptions::default()).expect("sapling imports");
    let t = 0.3 * tree.rig.clips[0].duration();
    let three = three_positions(
        &tools,
        &path,
        Some(&tree.rig.clips[0].name),
        &[tree.rig.clips[0].start + t],
    );
    let frond = pose_at(&tree, Some(0), tree.rig.clips[0].start + t);
    let tolerance = 1e-4 * tree.bounds.height();
    let d = nearest_max_distance(&three[0], &frond, 10.0 * tolerance);
    assert!(d <= tolerance, "nearest distance {d}");
    // And it does notice a vertex that is off.
    let mut moved = three[0].clone();
    moved[7] += Vec3::new(0.0, 20.0 * tolerance, 0.0);
    assert!(nearest_max_distance(&moved, &frond, 10.0 * tolerance) > tolerance);
}

/// Largest displacement of a vertex of `mesh` from its position at the first sampled time.
fn max_displacement(mesh: &ThreeMesh) -> f32 {
    let first = &mesh.positions[0];
    mesh.positions
        .iter()
        .flat_map(|pose| pose.iter().zip(first).map(|(p, q)| p.distance(*q)))
        .fold(0.0, f32::max)
}

#[test]
fn threejs_plays_every_lod_file_like_frond_samples_it() {
    // Without the Node clients, frond's own reading of each file (its Wind clip in phase with the
    // input's) is still checked.
    let tools = common::node_tools_for(Some("three.js playback"));
    let input_path = common::root().join("samples/sapling.glb");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("lods");
    // Billboards with motion joints (card LODs are skinned meshes like LOD0, which this plays
    // too); at the sizes' own ε, as the sample's textures leave no atlas room in the budgets.
    let report = common::frond_lod(
        &input_path,
        &out,
        &[
            "--lods",
            "300,60",
            "--method",
            "static",
            "--no-cost-budgets",
        ],
    );
    let lods = &report.lods;
    assert_eq!(lods.len(), 3, "LOD0, LOD1, LOD2");
    let billboards: Vec<usize> = lods.iter().map(|l| l.billboards).collect();
    // Billboards that copy an input card (the hybrid cloud) are drawn by a primitive of their
    // own, after the baked ones'.
    let copies: Vec<usize> = lods.iter().map(|l| l.input_textured_billboards).collect();
    let mut files: Vec<PathBuf> = lods.iter().map(|l| out.join(&l.file)).collect();
    files.push(out.join(&report.combined));

    let input = import(&input_path, &ImportOptions::default()).expect("sapling imports");
    let wind = |tree: &Tree| tree.rig.clips.iter().position(|c| c.name == "Wind");
    let clip_in = &input.rig.clips[wind(&input).expect("the sapling has a Wind clip")];
    let period = clip_in.duration();
    assert!(period > 0.0);
    let height = input.bounds.height();
    // Measured: at most 5.5e-7 × height (LOD2 and the combined file at 0.37 P; 1.9e-7 × height
    // for LOD0 and LOD1), f32 skinning noise as for the input trees.
    let tolerance = 1e-4 * height;
    // Quarter points, one time between keys, and the loop's end: three.js wraps t = P to the
    // clip's first pose, frond's sampler clamps to the last keys, so agreement there also says
    // the written clip closes its loop.
    let rel = [
        0.0,
        period / 4.0,
        0.37 * period,
        period / 2.0,
        3.0 * period / 4.0,
        period,
    ];

    let mut moved = Vec::new();
    for file in &files {
        let label = file.file_name().unwrap_or_default().to_string_lossy();
        let tree = import(file, &ImportOptions::default()).expect("LOD file imports");
        let ci = wind(&tree).unwrap_or_else(|| panic!("{label}: no Wind clip"));
        let c = &tree.rig.clips[ci];
        // In phase and the same length as the input's clip (frond's reading of the file).
        assert!(
            (c.start - clip_in.start).abs() <= 1e-4 && (c.end - clip_in.end).abs() <= 1e-4,
            "{label}: Wind keys span [{}, {}], input [{}, {}]",
            c.start,
            c.end,
            clip_in.start,
            clip_in.end
        );
        let Some(tools) = &tools else {
            continue;
        };
        let abs: Vec<f32> = rel.iter().map(|t| c.start + t).collect();
        let play = three_play(tools, file, Some("Wind"), &abs);
        // three.js's clip duration is its last key time.
        assert!(
            (play.duration - clip_in.end).abs() <= 1e-4,
            "{label}: three.js Wind lasts {} s, input clip ends at {} s",
            play.duration,
            clip_in.end
        );
        let a = compare_play(file, &tree, ci, &play, 10.0 * tolerance);
        eprintln!(
            "{label}: {} vertices, {}, three.js duration {} s, max distance {:.3e} ({:.3e} × height) per time {:?}, motion {:.3e}",
            a.vertices,
            if a.one_to_one {
                "one to one"
            } else {
                "as point sets"
            },
            play.duration,
            a.max_distance,
            a.max_distance / height,
            a.per_time,
            a.max_motion,
        );
        assert_eq!(a.vertices, tree.vertices.len(), "{label}: vertex count");
        assert!(a.one_to_one, "{label}: vertices line up one to one");
        assert!(
            a.max_distance <= tolerance,
            "{label}: three.js and frond differ by {} (> {tolerance})",
            a.max_distance
        );

        // Billboards: the first primitives of each billboard LOD's mesh node (the baked ones',
        // then the copies' on the sample's one leaf material), 4 vertices each.
        let json = common::gltf_json(file);
        let nodes = json["nodes"].as_array().expect("nodes");
        for (k, &count) in billboards.iter().enumerate().skip(1) {
            let name = format!("sapling_LOD{k}");
            // In the combined file the LOD's mesh node is `LOD_<name>`.
            let Some(ni) = nodes.iter().position(|n| {
                (n["name"] == name.as_str() || n["name"] == format!("LOD_{name}").as_str())
                    && n["mesh"].is_u64()
            }) else {
                continue;
            };
            let primitives = usize::from(count > copies[k]) + usize::from(copies[k] > 0);
            let meshes: Vec<&ThreeMesh> = (0..primitives)
                .map(|p| {
                    play.meshes
                        .iter()
                        .find(|m| m.node == Some(ni) && m.primitive == Some(p))
                        .unwrap_or_else(|| {
                            panic!("{label}: three.js has no primitive {p} of {name}")
                        })
                })
                .collect();
            assert!(
                meshes.iter().all(|m| m.skinned),
                "{label}: {name}'s billboards are skinned"
            );
            assert_eq!(
                meshes.iter().map(|m| m.positions[0].len()).sum::<usize>(),
                4 * count,
                "{label}: {name} has 4 vertices per billboard"
            );
            let d = meshes
                .iter()
                .map(|m| max_displacement(m))
                .fold(0.0, f32::max);
            eprintln!("{label}: {name} billboards ({count}) move up to {d:.3e} in three.js");
            // Far above float noise (the wind moves them by ~2 m; 100 × tolerance is 0.1 m).
            assert!(
                d > 100.0 * tolerance,
                "{label}: {name}'s billboards barely move ({d})"
            );
            moved.push(name);
        }
    }
    // Both billboard LODs were seen moving, in their own files and in the combined one.
    for k in (1..3).filter(|_| tools.is_some()) {
        let name = format!("sapling_LOD{k}");
        assert_eq!(
            moved.iter().filter(|n| **n == name).count(),
            2,
            "{name}: billboards checked in its file and the combined file"
        );
    }
}

/// The far end of `auto` (an impostor-class LOD: baked billboards, one joint per FFT cluster)
/// plays in three.js as frond samples it, its billboards moving with the wind.
#[test]
fn threejs_plays_the_far_end_like_frond_samples_it() {
    let tools = common::node_tools_for(Some("three.js playback of the far end"));
    let input_path = common::root().join("samples/sapling.glb");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("lods");
    let report = common::frond_lod(&input_path, &out, &["--lods", "60,20"]);
    let far = common::far_end_of_auto(&report);
    let file = out.join(&far.file);
    let tree = import(&file, &ImportOptions::default()).expect("the far LOD imports");
    let ci = (tree.rig.clips.iter())
        .position(|c| c.name == "Wind")
        .expect("the far LOD plays Wind");
    let c = &tree.rig.clips[ci];
    let Some(tools) = tools else {
        return;
    };
    let period = c.end - c.start;
    let times: Vec<f32> = [0.0, 0.25, 0.37, 0.5, 0.75]
        .iter()
        .map(|f| c.start + f * period)
        .collect();
    let play = three_play(&tools, &file, Some("Wind"), &times);
    let tolerance = 1e-4 * tree.bounds.height();
    let a = compare_play(&file, &tree, ci, &play, 10.0 * tolerance);
    eprintln!(
        "{}: {} vertices, max distance {:.3e}, motion {:.3e}",
        far.file, a.vertices, a.max_distance, a.max_motion
    );
    assert!(a.one_to_one, "vertices line up one to one");
    assert!(
        a.max_distance <= tolerance,
        "three.js and frond differ by {} (> {tolerance})",
        a.max_distance
    );
    let moving = (play.meshes.iter())
        .filter(|m| m.skinned)
        .map(max_displacement)
        .fold(0.0, f32::max);
    assert!(
        moving > 100.0 * tolerance,
        "the far LOD's billboards barely move in three.js ({moving})"
    );
}

/// `frond lod --compress`: every file validates with `EXT_meshopt_compression` and
/// `KHR_mesh_quantization` required, is smaller, and three.js (its meshopt decoder registered
/// by `three_sample.mjs`, as a web app does) plays it where it plays the uncompressed file;
/// frond reads it back with the same triangles.
#[test]
fn compressed_chains_validate_and_play_in_threejs_like_plain_ones() {
    // Without the Node clients, the files' extensions, sizes and frond's reading of them are
    // still checked.
    let tools = common::node_tools_for(Some("the glTF validator and three.js playback"));
    let input = common::root().join("samples/sapling.glb");
    let dir = tempfile::tempdir().expect("temp dir");
    let args = [
        "--lods",
        "300,60",
        "--method",
        "static",
        "--no-cost-budgets",
    ];
    let plain = dir.path().join("plain");
    let packed = dir.path().join("packed");
    let report = common::frond_lod(&input, &plain, &args);
    common::frond_lod(&input, &packed, &[&args[..], &["--compress"]].concat());
    let mut files: Vec<String> = report.lods.iter().map(|l| l.file.clone()).collect();
    files.push(report.combined.clone());
    let times = [0.0, 0.9, 2.3];
    for file in &files {
        let (a, b) = (plain.join(file), packed.join(file));
        if let Some(v) = common::validate(&b) {
            assert_eq!(v["errors"], 0, "{file}: {}", v["messages"]);
        }
        let json = common::gltf_json(&b);
        for ext in ["EXT_meshopt_compression", "KHR_mesh_quantization"] {
            assert!(
                json["extensionsRequired"]
                    .as_array()
                    .is_some_and(|r| r.iter().any(|e| e == ext)),
                "{file}: {ext} required"
            );
        }
        let (na, nb) = (
            std::fs::metadata(&a).expect("plain").len(),
            std::fs::metadata(&b).expect("packed").len(),
        );
        eprintln!("{file}: {na} bytes plain, {nb} compressed");
        assert!(nb < na, "{file}: compressed {nb} ≥ plain {na}");
        if let Some(tools) = &tools {
            let (pa, pb) = (
                three_positions(tools, &a, None, &times),
                three_positions(tools, &b, None, &times),
            );
            assert_eq!(pa.len(), pb.len());
            for (x, y) in pa.iter().zip(&pb) {
                assert_eq!(x.len(), y.len(), "{file}: vertex count");
                let worst = x
                    .iter()
                    .zip(y)
                    .map(|(p, q)| p.distance(*q))
                    .fold(0.0f32, f32::max);
                // Positions stay floats, rotation keys become normalized shorts (3e-5 rad a key,
                // adding up along the bone chains).
                eprintln!("{file}: three.js poses differ by up to {worst}");
                assert!(worst < 2e-3, "{file}: three.js poses differ by {worst}");
            }
        }
        let (ta, tb) = (
            import(&a, &ImportOptions::default()).expect("plain imports"),
            import(&b, &ImportOptions::default()).expect("compressed imports"),
        );
        assert_eq!(ta.triangles.len(), tb.triangles.len(), "{file}");
        assert_eq!(ta.vertices.position, tb.vertices.position, "{file}");
    }
}
