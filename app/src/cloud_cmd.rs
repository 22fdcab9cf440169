//! `frond cloud`: a static billboard cloud of a tree's foliage in the average pose of its loop,
//! with the wood as it is, baked atlases, and `<name>_cloud_stats.json` (spec animated-billboard-clouds §2.4,
//! §5.4 for the coverage check).

use std::path::Path;

use anyhow::{Context, Result};
use frond_billboard::TriangleSoup;
use frond_billboard::cloud::{BillboardCloud, CloudParams, CloudStats, build_cloud};
use frond_export::textures::TextureSink;
use frond_metrics::{CoverageParams, coverage_error};
use frond_render::{Renderer, TreeParts, scene_from_positions};
use frond_scene::gltf_writer::*;
use frond_scene::{Length, Part, Tree};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::output_set::OutputSet;

/// What `frond cloud` was asked for.
#[derive(Clone, Debug)]
pub struct CloudRequest {
    /// ε as given: "5%" of the rest-pose bounding-box diagonal, or an absolute length.
    pub epsilon: Length,
    /// Plane search and bake settings; its ε is replaced by [`CloudRequest::epsilon`] resolved
    /// against the tree's diagonal.
    pub params: CloudParams,
    /// Uniform samples over the loop whose average pose the cloud is built from.
    pub samples: usize,
    /// Clip to sample (None: the first).
    pub clip: Option<String>,
    /// Coverage views (0 skips the check).
    pub coverage_views: u32,
    /// Screen height of the coverage check, pixels ([`frond_metrics::framing()`]).
    pub coverage_height: f32,
}

/// `<name>_cloud_stats.json`.
#[derive(Debug, Serialize, Deserialize)]
pub struct CloudReport {
    /// The input tree's path.
    pub input: String,
    /// ε in world units, and as given.
    pub epsilon: f32,
    /// ε as the request gave it (`5%` or a length), so the report can be rerun.
    pub epsilon_arg: String,
    /// Rest-pose bounding-box diagonal (world units): what a percentage ε is of.
    pub diagonal: f32,
    /// Candidate planes per iteration.
    pub planes: usize,
    /// Seed of the plane search's random candidate planes: same input and seed, same cloud.
    pub seed: u64,
    /// Billboards (textured quads) of the cloud.
    pub billboards: usize,
    /// Sum of the quads' areas (world units²): the cost measure beside the count.
    pub total_area: f64,
    /// Bytes of the colour and normal atlases as RGBA8 texels (decoded size, not the
    /// PNG files').
    pub texture_bytes: usize,
    /// Static coverage error of the cloud vs the original foliage (spec §5.4), or null if skipped.
    pub coverage_error: Option<f64>,
    /// Each coverage view's score, in view order; empty when the check was skipped.
    pub coverage_per_view: Vec<f64>,
    /// Wall time of each stage in seconds (`plane_search`, `rectangles`, `bake`, `total`):
    /// timing, so it differs between otherwise identical runs.
    pub timings_s: frond_billboard::cloud::CloudTimings,
    /// Every size and error fact of the built cloud.
    pub cloud: CloudStats,
    /// The files written, relative to the output folder, this stats file last.
    pub files: Vec<String>,
}

/// Builds the cloud and its report; writes nothing.
pub fn make_cloud(
    renderer: &Renderer,
    tree: &Tree,
    req: &CloudRequest,
) -> Result<(BillboardCloud, Vec<Vec3>, CloudReport)> {
    let path = tree.source.display().to_string();
    let diag = tree.bounds.diagonal();
    let epsilon = req.epsilon.resolve(diag);
    let sampled = frond_lod::chain::sample_foliage(tree, req.clip.as_deref(), req.samples)?;
    let frond_scene::Sampled {
        average, foliage, ..
    } = sampled;
    let soup = TriangleSoup::from_tree(tree, &average, &foliage);
    let mut params = req.params.clone();
    params.search.epsilon = epsilon;
    let full = scene_from_positions(tree, &average, None, TreeParts::Foliage);
    let cloud = build_cloud(
        renderer,
        &soup,
        &full.materials,
        &full.textures,
        &params,
        diag,
    )
    .with_context(|| format!("{path}: building the billboard cloud"))?;
    let (coverage, per_view) = if req.coverage_views > 0 {
        let cp = CoverageParams {
            views: req.coverage_views,
            screen_height: req.coverage_height,
            ..Default::default()
        };
        let r = coverage_error(
            renderer,
            &[full],
            &[cloud.draw_scene()],
            Vec3::from(tree.bounds.min),
            Vec3::from(tree.bounds.max),
            &cp,
        )
        .with_context(|| format!("{path}: measuring coverage"))?;
        (Some(r.mean), r.per_view)
    } else {
        (None, Vec::new())
    };
    let report = CloudReport {
        input: path,
        epsilon,
        epsilon_arg: req.epsilon.to_string(),
        diagonal: diag,
        planes: params.search.candidates,
        seed: params.search.seed,
        billboards: cloud.stats.billboards,
        total_area: cloud.stats.total_area,
        texture_bytes: cloud.stats.texture_bytes,
        coverage_error: coverage,
        coverage_per_view: per_view,
        timings_s: cloud.stats.timings_s.clone(),
        cloud: cloud.stats.clone(),
        files: Vec::new(),
    };
    Ok((cloud, average, report))
}

/// A static GLB: the cloud's quads with the colour atlas (alpha-tested, double-sided) and the
/// wood at `positions` with its own material.
pub fn cloud_glb(tree: &Tree, positions: &[Vec3], cloud: &BillboardCloud) -> Result<Vec<u8>> {
    let mut doc = GltfBuilder::new(concat!("frond ", env!("CARGO_PKG_VERSION")));
    let mut sink = TextureSink::new(None, frond_export::TextureFormat::Png);
    let mat = sink
        .billboard_material(&mut doc, "cloud", &cloud.baked.atlas, true)
        .context("writing the billboard material")?;
    let q = cloud.quad_mesh();
    let quads = PrimitiveDesc {
        positions: q.positions,
        normals: Some(q.normals),
        uvs: Some(q.uvs),
        indices: q.indices,
        material: Some(mat),
        ..Default::default()
    };
    let cloud_mesh = doc.add_mesh("foliage_cloud", &[quads]);
    let node = doc.add_node(NodeDesc {
        name: "foliage_cloud".into(),
        mesh: Some(cloud_mesh),
        ..Default::default()
    });
    doc.add_root(node);
    // Wood: one primitive per material, un-indexed vertices re-used per primitive.
    let images = frond_export::downscale::Downscaler::new(tree);
    let mut prims = Vec::new();
    for m in 0..tree.materials.len() {
        let tris: Vec<_> = tree
            .triangles
            .iter()
            .filter(|t| t.part == Part::Wood && !t.degenerate && t.material as usize == m)
            .collect();
        if tris.is_empty() {
            continue;
        }
        let mat = sink
            .tree_material(&mut doc, &images, m, &Default::default())
            .context("writing a wood material")?;
        // The input's own texture coordinate sets: its material is written as it was.
        let sets = &tree.vertices.texcoords;
        let mut p = PrimitiveDesc {
            uvs: Some(Vec::new()),
            extra_uvs: vec![Vec::new(); sets.len().saturating_sub(1)],
            material: Some(mat),
            ..Default::default()
        };
        let mut remap = std::collections::HashMap::new();
        for t in tris {
            for &v in &t.v {
                let next = p.positions.len() as u32;
                let id = *remap.entry(v).or_insert_with(|| {
                    p.positions.push(positions[v as usize].to_array());
                    let vi = v as usize;
                    if let Some(u) = p.uvs.as_mut() {
                        let uv = match sets.first() {
                            Some(set) => set.get(vi).copied().unwrap_or_default(),
                            None => tree.vertices.uv[vi],
                        };
                        u.push(uv.to_array());
                    }
                    for (out, set) in p.extra_uvs.iter_mut().zip(sets.iter().skip(1)) {
                        out.push(set.get(vi).copied().unwrap_or_default().to_array());
                    }
                    next
                });
                p.indices.push(id);
            }
        }
        prims.push(p);
    }
    if !prims.is_empty() {
        let wood = doc.add_mesh("wood", &prims);
        let node = doc.add_node(NodeDesc {
            name: "wood".into(),
            mesh: Some(wood),
            ..Default::default()
        });
        doc.add_root(node);
    }
    Ok(doc.to_glb())
}

/// The file names of a cloud of the tree called `name` (the input's stem): the GLB, the two
/// atlases and the stats, each prefixed with the name so that a cloud never takes the name of
/// its input's own files (a `cloud.glb` or an `atlas_color.png` texture beside a `.gltf`).
pub fn cloud_file_names(name: &str) -> [String; 4] {
    [
        format!("{name}_cloud.glb"),
        format!("{name}_atlas_color.png"),
        format!("{name}_atlas_normal.png"),
        format!("{name}_cloud_stats.json"),
    ]
}

/// Builds the cloud and writes [`cloud_file_names`] into `out_dir` as one [`OutputSet`] (the
/// folder checked before the build, the set installed whole at the end; nothing written unless
/// everything was built, an input file never replaced).
pub fn run_cloud(
    renderer: &Renderer,
    tree: &Tree,
    req: &CloudRequest,
    out_dir: &Path,
) -> Result<CloudReport> {
    let name = crate::lod_cmd::lod_name(tree);
    let [glb_name, color_name, normal_name, stats_name] = cloud_file_names(&name);
    let mut set = OutputSet::prepare(
        out_dir,
        &format!("{name}_cloud"),
        &stats_name,
        &[&tree.source],
    )?;
    let names = [glb_name.clone(), color_name.clone(), normal_name.clone()];
    set.check_names(&names)?;
    let (cloud, average, mut report) = make_cloud(renderer, tree, req)?;
    let glb = cloud_glb(tree, &average, &cloud)?;
    let atlas = &cloud.baked.atlas;
    let color =
        encode_png(atlas.width, atlas.height, &atlas.color).context("encoding the colour atlas")?;
    let normal = encode_png(atlas.width, atlas.height, &atlas.normal)
        .context("encoding the normal atlas")?;
    set.stage(&glb_name, &glb)?;
    set.stage(&color_name, &color)?;
    set.stage(&normal_name, &normal)?;
    report.files = names.to_vec();
    report.files.push(stats_name);
    let json = serde_json::to_vec_pretty(&report).context("serialising the stats")?;
    set.commit(&json)?;
    Ok(report)
}
