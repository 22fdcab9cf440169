//! The wood mesh of a LOD: `WoodMesh::from_tree` reproduces the tree's wood at rest (and, through
//! its per-bone skin, in motion), and `WoodMesh::simplify` stays within its error budget, measured
//! as true point-to-surface distances rather than trusting the simplifier's estimate.
//!
//! Trees: generated ones, ez-tree's bush_1 (`tests/fixtures/`), and the larger shared trees
//! (`FROND_TEST_TREES`; tests that need them skip with one line where they are absent).

use std::path::Path;
use std::time::Instant;

use frond_scene::generator::{Preset, generate};
use frond_scene::sampling::{pose_at, world_at};
use frond_scene::skinning::skin_positions;
use frond_scene::surface_distance::SurfaceBvh;
use frond_scene::wood::{NO_BONE, WoodMesh, WoodPrimitive};
use frond_scene::{ImportOptions, Part, Tree, import, import_bytes};
use glam::{Mat4, Vec3};

fn load(path: &Path) -> Tree {
    import(path, &ImportOptions::default()).expect("tree imports")
}

/// ez-tree's bush_1, committed as a fixture.
fn bush() -> Tree {
    load(&frond_testdata::fixture("bush_1.glb"))
}

/// The file name of `path`, for messages.
fn name_of(path: &Path) -> String {
    path.file_name()
        .expect("file name")
        .to_string_lossy()
        .into_owned()
}

fn generated(seed: u64) -> Tree {
    let g = generate(Preset::Small, seed).expect("generates");
    import_bytes(
        Path::new("generated.glb"),
        &g.glb,
        &ImportOptions::default(),
    )
    .expect("generated tree imports")
}

// ---------------------------------------------------------------- geometry helpers

fn triangles_of(mesh: &WoodMesh, positions: &[Vec3]) -> Vec<[Vec3; 3]> {
    mesh.primitives
        .iter()
        .flat_map(|p| p.indices.chunks_exact(3))
        .map(|t| [0, 1, 2].map(|k| positions[t[k] as usize]))
        .collect()
}

/// Largest distance from any of `points` to the surface `bvh`.
fn one_sided(points: &[Vec3], bvh: &SurfaceBvh) -> f32 {
    use rayon::prelude::*;
    points
        .par_iter()
        .map(|p| bvh.distance(*p))
        .reduce(|| 0.0, f32::max)
}

/// Points spread over a mesh's triangles: centroids and edge midpoints.
fn surface_samples(tris: &[[Vec3; 3]]) -> Vec<Vec3> {
    tris.iter()
        .flat_map(|t| {
            [
                (t[0] + t[1] + t[2]) / 3.0,
                (t[0] + t[1]) * 0.5,
                (t[1] + t[2]) * 0.5,
                (t[2] + t[0]) * 0.5,
            ]
        })
        .collect()
}

/// The mesh's vertices animated with per-bone palettes `world(bone, t) · rest_world(bone)⁻¹`.
fn skin_mesh(tree: &Tree, mesh: &WoodMesh, clip: Option<usize>, t: f32) -> Vec<Vec3> {
    let rest = world_at(tree, None, 0.0);
    let now = world_at(tree, clip, t);
    let palette: Vec<Mat4> = tree
        .bones
        .iter()
        .map(|b| now[b.node] * rest[b.node].inverse())
        .collect();
    mesh.positions
        .iter()
        .zip(mesh.bones.iter().zip(&mesh.weights))
        .map(|(p, (b, w))| {
            let mut acc = Vec3::ZERO;
            for s in 0..4 {
                if w[s] > 0.0 {
                    let m = if b[s] == NO_BONE {
                        Mat4::IDENTITY
                    } else {
                        palette[b[s] as usize]
                    };
                    acc += m.transform_point3(*p) * w[s];
                }
            }
            acc
        })
        .collect()
}

/// Distances between two wood meshes: (original vertices → simplified surface,
/// simplified surface samples → original surface), at rest.
fn rest_distances(original: &WoodMesh, simplified: &WoodMesh) -> (f32, f32) {
    let simp = SurfaceBvh::new(triangles_of(simplified, &simplified.positions));
    let orig_tris = triangles_of(original, &original.positions);
    let used: Vec<Vec3> = used_vertices(original)
        .into_iter()
        .map(|i| original.positions[i])
        .collect();
    let forward = one_sided(&used, &simp);
    let back = one_sided(
        &surface_samples(&triangles_of(simplified, &simplified.positions)),
        &SurfaceBvh::new(orig_tris),
    );
    (forward, back)
}

fn used_vertices(mesh: &WoodMesh) -> Vec<usize> {
    let mut used = vec![false; mesh.positions.len()];
    for p in &mesh.primitives {
        for &i in &p.indices {
            used[i as usize] = true;
        }
    }
    (0..used.len()).filter(|&i| used[i]).collect()
}

/// Largest distance from the original's animated vertices to the simplified animated surface
/// over `times` of clip 0.
fn animated_distance(
    tree: &Tree,
    original: &WoodMesh,
    simplified: &WoodMesh,
    times: &[f32],
) -> f32 {
    let used = used_vertices(original);
    times
        .iter()
        .map(|&t| {
            let a = skin_mesh(tree, original, Some(0), t);
            let b = skin_mesh(tree, simplified, Some(0), t);
            let bvh = SurfaceBvh::new(triangles_of(simplified, &b));
            let pts: Vec<Vec3> = used.iter().map(|&i| a[i]).collect();
            one_sided(&pts, &bvh)
        })
        .fold(0.0, f32::max)
}

fn assert_well_formed(mesh: &WoodMesh, bones: usize) {
    let n = mesh.positions.len();
    assert_eq!(mesh.normals.len(), n);
    assert_eq!(mesh.uvs.len(), n);
    assert_eq!(mesh.bones.len(), n);
    assert_eq!(mesh.weights.len(), n);
    for p in &mesh.primitives {
        assert_eq!(p.indices.len() % 3, 0);
        assert!(!p.indices.is_empty());
        assert!(p.indices.iter().all(|&i| (i as usize) < n));
    }
    let mut mats: Vec<usize> = mesh.primitives.iter().map(|p| p.material).collect();
    mats.dedup();
    assert_eq!(
        mats.len(),
        mesh.primitives.len(),
        "one primitive per material"
    );
    assert_eq!(used_vertices(mesh).len(), n, "no unused vertex");
    for (i, (b, w)) in mesh.bones.iter().zip(&mesh.weights).enumerate() {
        let sum: f32 = w.iter().sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {i}: weights {w:?}");
        assert!(w.iter().all(|x| *x >= 0.0));
        for s in 0..4 {
            if s > 0 {
                assert!(w[s] <= w[s - 1], "vertex {i}: unsorted {w:?}");
            }
            if w[s] == 0.0 {
                assert_eq!(b[s], b[0], "vertex {i}: unused slot");
            } else if b[s] == NO_BONE {
                assert_eq!(*w, [1.0, 0.0, 0.0, 0.0], "vertex {i}: NO_BONE blended");
            } else {
                assert!((b[s] as usize) < bones, "vertex {i}: bone {}", b[s]);
                assert!(!b[..s].contains(&b[s]), "vertex {i}: repeated bone");
            }
        }
        assert!(
            (mesh.normals[i].length() - 1.0).abs() < 1e-4,
            "vertex {i}: normal"
        );
    }
}

fn wood_triangles(tree: &Tree) -> usize {
    tree.triangles
        .iter()
        .filter(|t| t.part == Part::Wood && !t.degenerate)
        .count()
}

/// Every check point of `original` (vertices used by triangles) and of `simplified` (points
/// spread over its triangles) against the other surface, at rest, in units of `e`.
fn assert_within(name: &str, original: &WoodMesh, simplified: &WoodMesh, e: f32, tol: f32) {
    let (forward, back) = rest_distances(original, simplified);
    assert!(
        forward <= e + tol,
        "{name}: an original vertex is {forward} from the simplified surface (budget {e})"
    );
    assert!(
        back <= e + tol,
        "{name}: a simplified surface point is {back} from the original (budget {e})"
    );
}

fn assert_same(a: &WoodMesh, b: &WoodMesh) {
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.normals, b.normals);
    assert_eq!(a.uvs, b.uvs);
    assert_eq!(a.bones, b.bones);
    assert_eq!(a.weights, b.weights);
    assert_eq!(a.primitives.len(), b.primitives.len());
    for (p, q) in a.primitives.iter().zip(&b.primitives) {
        assert_eq!(p.material, q.material);
        assert_eq!(p.indices, q.indices);
    }
}

// ---------------------------------------------------------------- from_tree

fn check_from_tree(name: &str, tree: &Tree) {
    let (mesh, source) = WoodMesh::from_tree_mapped(tree);
    assert_eq!(WoodMesh::from_tree(tree).positions, mesh.positions);
    assert_eq!(source.len(), mesh.positions.len());
    assert_eq!(
        mesh.triangles(),
        wood_triangles(tree),
        "{name}: wood triangles"
    );
    assert_well_formed(&mesh, tree.bones.len());

    // Same triangles, material by material, as tree vertices.
    let mut ours: Vec<(usize, [u32; 3])> = mesh
        .primitives
        .iter()
        .flat_map(|p| {
            p.indices
                .chunks_exact(3)
                .map(|t| (p.material, [0, 1, 2].map(|k| source[t[k] as usize])))
        })
        .collect();
    let mut theirs: Vec<(usize, [u32; 3])> = tree
        .triangles
        .iter()
        .filter(|t| t.part == Part::Wood && !t.degenerate)
        .map(|t| (t.material as usize, t.v))
        .collect();
    ours.sort_unstable();
    theirs.sort_unstable();
    assert_eq!(ours, theirs, "{name}: triangles");
    // Welded: one vertex per (material, tree vertex).
    let mut keys: Vec<(usize, u32)> = mesh
        .primitives
        .iter()
        .flat_map(|p| p.indices.iter().map(|&i| (p.material, source[i as usize])))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), mesh.positions.len(), "{name}: welding");

    // Rest positions are exactly the tree's skinned rest positions; UVs are the tree's.
    let rest = skin_positions(tree, &world_at(tree, None, 0.0));
    for (i, &s) in source.iter().enumerate() {
        assert_eq!(mesh.positions[i], rest[s as usize], "{name}: vertex {i}");
        assert_eq!(mesh.uvs[i], tree.vertices.uv[s as usize], "{name}: uv {i}");
    }
    // The per-bone skin moves the mesh exactly as the tree's own skinning does.
    if !tree.rig.clips.is_empty() {
        let tol = 1e-4 * tree.bounds.height();
        let period = tree.rig.clips[0].duration();
        for f in [0.13, 0.5, 0.81] {
            let t = tree.rig.clips[0].start + f * period;
            let want = pose_at(tree, Some(0), t);
            let got = skin_mesh(tree, &mesh, Some(0), t);
            for (i, &s) in source.iter().enumerate() {
                let d = got[i].distance(want[s as usize]);
                assert!(d <= tol, "{name}: vertex {i} at t = {t} is {d} off");
            }
        }
    }
}

#[test]
fn from_tree_reproduces_the_wood_of_bush_1() {
    check_from_tree("bush_1.glb", &bush());
}

#[test]
fn from_tree_reproduces_the_wood_of_shared_trees() {
    for path in frond_testdata::require_trees!(["pine_medium.glb", "oak_medium.glb"]) {
        check_from_tree(&name_of(&path), &load(&path));
    }
}

#[test]
fn from_tree_reproduces_the_wood_of_a_generated_tree() {
    let g = generate(Preset::Small, 3).expect("generates");
    let tree = import_bytes(
        Path::new("generated.glb"),
        &g.glb,
        &ImportOptions::default(),
    )
    .expect("imports");
    assert_eq!(WoodMesh::from_tree(&tree).triangles(), g.wood_triangles);
    check_from_tree("generated", &tree);
    // The generator blends weights across joints: some vertices have two influences.
    let mesh = WoodMesh::from_tree(&tree);
    assert!(mesh.weights.iter().any(|w| w[1] > 0.0));
}

#[test]
fn a_tree_without_wood_gives_an_empty_mesh() {
    let options = ImportOptions {
        foliage_materials: vec!["branches".into()],
        ..ImportOptions::default()
    };
    let tree = import(&frond_testdata::fixture("bush_1.glb"), &options).expect("imports");
    assert_eq!(wood_triangles(&tree), 0);
    let mesh = WoodMesh::from_tree(&tree);
    assert_eq!(mesh.triangles(), 0);
    assert!(mesh.positions.is_empty() && mesh.primitives.is_empty());
    assert!(mesh.used_bones().is_empty());
    let (s, err) = mesh.simplify(1.0);
    assert_eq!((s.triangles(), s.positions.len(), err), (0, 0, 0.0));
    let (s, err) = WoodMesh::default().simplify(0.0);
    assert_eq!((s.triangles(), s.positions.len(), err), (0, 0, 0.0));
}

// ---------------------------------------------------------------- simplify

/// Simplifies at `frac` of the tree height and checks every promise; returns the triangles.
fn check_simplify(name: &str, tree: &Tree, mesh: &WoodMesh, frac: f32, animated: bool) -> usize {
    let h = tree.bounds.height();
    let e = frac * h;
    let tol = 1e-5 * h;
    let (s, err) = mesh.simplify(e);
    assert!(err <= e, "{name}: reported error {err} > {e}");
    assert!(err >= 0.0);
    assert_well_formed(&s, tree.bones.len());
    assert!(s.triangles() <= mesh.triangles());
    // Every vertex is an original vertex, unchanged (position, normal, UV, skin).
    let key = |m: &WoodMesh, i: usize| {
        (
            m.positions[i].to_array().map(f32::to_bits),
            m.normals[i].to_array().map(f32::to_bits),
            m.uvs[i].to_array().map(f32::to_bits),
            m.bones[i],
            m.weights[i].map(f32::to_bits),
        )
    };
    let originals: std::collections::HashSet<_> =
        (0..mesh.positions.len()).map(|i| key(mesh, i)).collect();
    for i in 0..s.positions.len() {
        assert!(originals.contains(&key(&s, i)), "{name}: vertex {i} is new");
    }
    let used: Vec<u32> = s.used_bones();
    let all = mesh.used_bones();
    assert!(used.iter().all(|b| all.contains(b)), "{name}: new bones");
    // Materials: only those of the original.
    for p in &s.primitives {
        assert!(mesh.primitives.iter().any(|q| q.material == p.material));
    }
    assert_within(name, mesh, &s, e, tol);
    if animated && !tree.rig.clips.is_empty() {
        // Moving, the bound loosens a little: linear-blend skinning is not linear in the
        // weights, so a triangle spanning a joint bends differently than the finer original
        // (measured at most 1.37 e on the shared trees).
        let d = animated_distance(tree, mesh, &s, &[0.5, 1.3, 2.1, 3.7]);
        assert!(
            d <= 1.5 * e + tol,
            "{name}: animated distance {d} > 1.5 × {e}"
        );
    }
    // Deterministic.
    let (again, err2) = mesh.simplify(e);
    assert_same(&s, &again);
    assert_eq!(err.to_bits(), err2.to_bits());
    s.triangles()
}

/// Simplifies at 0.1 %, 1 % and 5 % of the height: within budget, and at 1 % down to
/// `at_1_percent` of the triangles.
fn check_budget(name: &str, tree: &Tree, at_1_percent: f32) {
    let mesh = WoodMesh::from_tree(tree);
    let n = mesh.triangles() as f32;
    let fine = check_simplify(name, tree, &mesh, 0.001, false);
    let one = check_simplify(name, tree, &mesh, 0.01, true);
    let coarse = check_simplify(name, tree, &mesh, 0.05, false);
    println!("{name}: {n} wood triangles; 0.1 % of height: {fine}, 1 %: {one}, 5 %: {coarse}");
    assert!(
        (one as f32) <= at_1_percent * n,
        "{name}: only down to {one} of {n} triangles at 1 %"
    );
    assert!(
        coarse <= one && one <= fine,
        "{name}: more error, fewer triangles"
    );
}

#[test]
fn simplify_stays_within_the_budget_and_reduces_on_bush_1() {
    check_budget("bush_1.glb", &bush(), 0.45);
}

#[test]
fn simplify_stays_within_the_budget_and_reduces_on_shared_trees() {
    let names = ["pine_medium.glb", "oak_medium.glb"];
    let paths = frond_testdata::require_trees!(names);
    for ((name, at_1_percent), path) in names.into_iter().zip([0.35, 0.5]).zip(&paths) {
        check_budget(name, &load(path), at_1_percent);
    }
}

/// Simplifying with no error keeps (almost) every triangle; nonsense budgets count as zero.
fn check_no_error(name: &str, tree: &Tree) {
    let mesh = WoodMesh::from_tree(tree);
    let (s, err) = mesh.simplify(0.0);
    assert!(err <= 1e-6 * tree.bounds.size(), "{name}: error {err}");
    assert!(
        s.triangles() as f32 >= 0.99 * mesh.triangles() as f32,
        "{name}: {} of {} triangles at zero error",
        s.triangles(),
        mesh.triangles()
    );
    assert_within(name, &mesh, &s, 0.0, 1e-5 * tree.bounds.height());
    for bad in [-1.0, f32::NAN] {
        let (t, e) = mesh.simplify(bad);
        assert_same(&s, &t);
        assert_eq!(e.to_bits(), err.to_bits());
    }
}

#[test]
fn simplify_with_no_error_keeps_the_mesh_of_bush_1() {
    check_no_error("bush_1.glb", &bush());
}

#[test]
fn simplify_with_no_error_keeps_the_mesh_of_oak_medium() {
    let path = frond_testdata::require_tree!("oak_medium.glb");
    check_no_error("oak_medium.glb", &load(&path));
}

#[test]
fn simplify_a_generated_tree() {
    let tree = generated(7);
    let mesh = WoodMesh::from_tree(&tree);
    let n = mesh.triangles();
    let one = check_simplify("generated", &tree, &mesh, 0.01, true);
    println!("generated small tree: {n} wood triangles, {one} at 1 % of the height");
    assert!(one * 2 <= n, "generated: {one} of {n}");
}

#[test]
fn simplified_again_stays_a_subset() {
    let tree = bush();
    let mesh = WoodMesh::from_tree(&tree);
    let e = 0.01 * tree.bounds.height();
    let (once, _) = mesh.simplify(e);
    let (twice, err) = once.simplify(e);
    assert!(err <= e);
    assert!(twice.triangles() <= once.triangles());
    assert_well_formed(&twice, tree.bones.len());
}

/// A mesh whose primitives share vertices (not how from_tree builds it) still simplifies, and a
/// second material keeps its own triangles.
#[test]
fn simplify_keeps_materials_apart() {
    let tree = bush();
    let mut mesh = WoodMesh::from_tree(&tree);
    // Split the single wood primitive in two materials, alternating triangles.
    let p = mesh.primitives.remove(0);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (k, t) in p.indices.chunks_exact(3).enumerate() {
        if k % 2 == 0 { &mut a } else { &mut b }.extend_from_slice(t);
    }
    let (na, nb) = (a.len() / 3, b.len() / 3);
    mesh.primitives = vec![
        WoodPrimitive {
            material: p.material,
            indices: a,
        },
        WoodPrimitive {
            material: p.material + 1,
            indices: b,
        },
    ];
    let e = 0.01 * tree.bounds.height();
    let (s, err) = mesh.simplify(e);
    assert!(err <= e);
    assert_eq!(s.primitives.len(), 2);
    assert!(s.primitives[0].indices.len() / 3 <= na);
    assert!(s.primitives[1].indices.len() / 3 <= nb);
    assert_within("two materials", &mesh, &s, e, 1e-5 * tree.bounds.height());
}

// ---------------------------------------------------------------- numbers for the report

/// Prints triangle counts, errors, measured distances and timings: a heavy case, in `.ci/run`'s
/// optimised run (`--nocapture` shows the figures).
#[test]
fn heavy_report_numbers() {
    if !heavy() {
        return;
    }
    let names = [
        "bush_1.glb",
        "pine_medium.glb",
        "oak_medium.glb",
        "oak_dense.glb",
    ];
    for (name, path) in names.iter().zip(frond_testdata::require_trees!(names)) {
        let tree = load(&path);
        let h = tree.bounds.height();
        let t0 = Instant::now();
        let mesh = WoodMesh::from_tree(&tree);
        let build = t0.elapsed().as_secs_f32();
        println!(
            "{name}: height {h:.3}, wood triangles {}, vertices {}, bones {} (from_tree {build:.3} s)",
            mesh.triangles(),
            mesh.positions.len(),
            mesh.used_bones().len()
        );
        for frac in [0.0, 0.001, 0.005, 0.01, 0.02, 0.05] {
            let e = frac * h;
            let t0 = Instant::now();
            let (s, err) = mesh.simplify(e);
            let dt = t0.elapsed().as_secs_f32();
            let (fwd, back) = rest_distances(&mesh, &s);
            let anim = animated_distance(&tree, &mesh, &s, &[0.5, 1.3, 2.1, 3.7]);
            let unit = if e > 0.0 { e } else { 1.0 };
            println!(
                "  {frac:>5} h = {e:.4}: {:>6} triangles ({:5.1} %), {:>6} vertices, error {err:.4}, {dt:.3} s; distances (÷ e) orig→simp {:.3}, simp→orig {:.3}, animated {:.3}; bones {}",
                s.triangles(),
                100.0 * s.triangles() as f32 / mesh.triangles() as f32,
                s.positions.len(),
                fwd / unit,
                back / unit,
                anim / unit,
                s.used_bones().len()
            );
        }
    }
}

/// Release timing of the densest shared tree's wood: a heavy case, in `.ci/run`'s
/// optimised run.
#[test]
fn heavy_time_oak_dense() {
    if !heavy() {
        return;
    }
    let tree = load(&frond_testdata::require_tree!("oak_dense.glb"));
    let mesh = WoodMesh::from_tree(&tree);
    for frac in [0.001, 0.01, 0.05] {
        let e = frac * tree.bounds.height();
        let t0 = Instant::now();
        let runs = 5;
        let mut tris = 0;
        for _ in 0..runs {
            tris = mesh.simplify(e).0.triangles();
        }
        println!(
            "oak_dense wood {} → {tris} triangles at {frac} h: {:.1} ms per simplify ({} threads)",
            mesh.triangles(),
            t0.elapsed().as_secs_f64() * 1000.0 / runs as f64,
            rayon::current_num_threads()
        );
    }
}

/// Whether the heavy cases run ([`frond_testdata::heavy`]); else one skip line.
fn heavy() -> bool {
    frond_testdata::heavy(env!("CARGO_CRATE_NAME"))
}
