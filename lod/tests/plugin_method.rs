//! A method added from outside the crate: one type implementing the method trait with its
//! plugin, and one line putting it into a registry. Its name parses, a chain built on the
//! bundled sapling runs it, and its report section appears in the LOD's report entry.

use std::sync::Arc;

use frond_billboard::BakeRasteriser;
use frond_lod::chain::{ChainRequest, CloudOptions, build_chain, chain_levels};
use frond_lod::joint_budget::BillboardAnimation;
use frond_lod::method_api::{
    BuildContext, ClusteringMethod, Foliage, MethodName, MethodOptions, MethodOutput, MethodPlugin,
    MethodSection, Registry, uses_no_options,
};
use frond_lod::methods::REGISTRY;
use frond_lod::methods::static_cloud::StaticCloud;
use frond_lod::{LodError, LodReport, ReportTimings};
use frond_render::Renderer;
use frond_scene::{ImportOptions, import};
use serde::Serialize;

/// The test method's name.
const FLAT: MethodName = MethodName::new("test-flat");

/// The static cloud under a name of its own, with a report section of its own.
#[derive(Debug)]
struct Flat;

/// What [`Flat`] reports.
#[derive(Serialize)]
struct FlatReport {
    billboards: usize,
}

impl ClusteringMethod for Flat {
    fn name(&self) -> MethodName {
        FLAT
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let mut out = StaticCloud.build(ctx)?;
        let billboards = match &out.foliage {
            Foliage::Cloud(cloud) => cloud.billboards.len(),
            Foliage::Cards(_) => 0,
        };
        out.section = Some(MethodSection::new("flat", &FlatReport { billboards })?);
        Ok(out)
    }
}

/// [`Flat`] as a registry lists it.
const FLAT_PLUGIN: MethodPlugin = MethodPlugin {
    names: &[("test-flat", FLAT)],
    configure: |_, _, _| Ok(Arc::new(Flat)),
    uses: uses_no_options,
};

#[test]
fn a_method_registered_by_one_line_is_parsed_built_and_reported() {
    // The crate's methods and the test's: its one registry line.
    let plugins: Vec<MethodPlugin> = REGISTRY.0.iter().copied().chain([FLAT_PLUGIN]).collect();
    let registry = Registry::new(&plugins);

    // Its name parses in this registry (after every name of the crate's), not in the crate's.
    assert_eq!(registry.parse("test-flat"), Some(FLAT));
    assert_eq!(REGISTRY.parse("test-flat"), None);
    assert_eq!(registry.names().last(), Some(("test-flat", FLAT)));
    assert_eq!(registry.parse("static"), REGISTRY.parse("static"));
    assert!(registry.ignored_options(FLAT, true, true, false).len() == 2);

    // The chain runs it.
    let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sapling");
    let renderer = Renderer::new().expect("renderer");
    let req = ChainRequest {
        method: registry
            .configure(FLAT, &MethodOptions::default())
            .expect("configured"),
        screen_heights: vec![60.0],
        pixel_error: 1.0,
        epsilon: None,
        animation: BillboardAnimation::Joints,
        seed: 1,
        max_joints: None,
        triangle_ratio: 0.5,
        cost_budgets: true,
        samples: 8,
        clip: None,
        cloud: CloudOptions {
            far_blend: false,
            planes: 20,
            view_penalty: None,
            increased_density: false,
            max_atlas: 512,
            supersample: 2,
            padding: 2,
            rasteriser: BakeRasteriser::Cpu,
        },
    };
    let levels = chain_levels(&tree, &req).expect("levels");
    let chain = build_chain(&renderer, &tree, &req, &levels, &|_| {}).expect("chain");
    let lod1 = &chain.lods[1].entry;
    assert_eq!(lod1.method, FLAT);
    let billboards = chain.lods[1].cloud().expect("a cloud").billboards.len();
    assert!(billboards > 0);

    // Its section is written into the LOD's entry, beside the sections it does not have.
    let report = LodReport {
        schema_version: frond_lod::LOD_REPORT_SCHEMA_VERSION,
        input: String::new(),
        name: "sapling".into(),
        clip: None,
        period: 0.0,
        samples: 8,
        seed: 1,
        pixel_error: 1.0,
        animation: "skin".into(),
        tree_height: tree.height(),
        switching: None,
        lods: chain.lods.iter().map(|l| l.entry.clone()).collect(),
        texture_memory: None,
        combined: String::new(),
        files: Vec::new(),
        warnings: Vec::new(),
        timings_s: ReportTimings::default(),
    };
    // The written form, not a read of the report: the section's key in the entry, the other
    // methods' sections written as null and LOD0 without one.
    let json: serde_json::Value = serde_json::to_value(&report).expect("json");
    let entry = &json["lods"][1];
    assert_eq!(entry["method"], "test-flat");
    assert_eq!(entry["method_reason"], "given with --method");
    // What the method built, before the motion budget dropped any.
    let built = entry["flat"]["billboards"].as_u64().expect("a count") as usize;
    assert!(built >= billboards, "{built} < {billboards}");
    assert!(entry["spectral"].is_null() && entry["skeleton"].is_null());
    assert!(json["lods"][0].get("flat").is_none());
    // And it reads back.
    let text = serde_json::to_string_pretty(&report).expect("text");
    let back: LodReport = serde_json::from_str(&text).expect("reads back");
    assert_eq!(back.lods[1].method, FLAT);
    assert!(back.lods[1].sections.get("flat").is_some());
}
