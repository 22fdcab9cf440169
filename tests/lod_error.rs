//! Each LOD's error at its own size: `frond lod` measures it on the written files and reports
//! the numbers `frond eval INPUT LOD --screen-height H` gives (the coverage error, its ratio and
//! the binary error, on the same framing), with the switch pop against the LOD before it; warns
//! about a LOD over `--max-error` and writes it all the same; the card LODs of the sample stay
//! within the errors their coverage-driven thinning reaches.

use crate::common;

use common::*;
use frond_lod::report::LOD_REPORT_SCHEMA_VERSION;
use frond_lod::{LodEntry, LodReport};

/// Runs `frond lod` on the sample at `lods` with the error measured against `max_error`;
/// returns the report.
fn measured_chain(out: &std::path::Path, lods: &str, max_error: &str) -> LodReport {
    let sample = root().join("samples/sapling.glb");
    frond_lod_measured(&sample, out, &["--lods", lods, "--max-error", max_error])
}

/// The highest coverage error of the sample's card LOD at 200 px: every card is kept (trimmed
/// to its texture's alpha), the wood simplified, so the LOD draws the tree's outline all but
/// exactly.
const MAX_ERROR_200: f64 = 0.005;

/// The highest coverage error of the sample's card LOD at 60 px: cards thinned where the others
/// cover for them, the rest scaled to keep the covered area.
const MAX_ERROR_60: f64 = 0.03;

#[test]
fn the_report_gives_each_lods_error_as_frond_eval_measures_it() {
    let out = tempfile::tempdir().expect("tempdir");
    let report = measured_chain(out.path(), "200,60", "0.15");
    assert_eq!(report.schema_version, LOD_REPORT_SCHEMA_VERSION);
    assert_eq!(LOD_REPORT_SCHEMA_VERSION, 3);
    let lods = &report.lods;
    // The chain's texture memory counts each image once: at most every file's images added
    // up, at least the largest file's.
    let memory = report.texture_memory.expect("the chain's texture memory");
    let decoded: Vec<u64> = (lods.iter())
        .map(|l| l.cost.as_ref().expect("cost").texture_decoded_bytes)
        .collect();
    let largest = decoded.iter().copied().max().unwrap_or(0);
    assert!(
        (largest..=decoded.iter().sum()).contains(&memory.decoded_bytes),
        "{memory:?} against {decoded:?}"
    );
    assert_eq!(lods.len(), 3);
    assert!(lods[0].error.is_none(), "LOD0 is the input");
    // The input's renders, drawn beside the build, are timed apart; the export's time is its own.
    let t = &report.timings_s;
    assert!(
        t.measure_input
            .unwrap_or_else(|| panic!("timings_s.measure_input: {t:?}"))
            > 0.0,
        "{t:?}"
    );
    assert!((0.0..t.total).contains(&t.export), "{t:?}");
    let sample = root().join("samples/sapling.glb");
    for (k, (lod, (h, bound))) in lods[1..]
        .iter()
        .zip([(200u32, MAX_ERROR_200), (60, MAX_ERROR_60)])
        .enumerate()
    {
        let file = lod.file.as_str();
        let e = lod.error.as_ref().expect("error");
        let coverage = e.coverage;
        let eval = frond_eval(
            &sample,
            &out.path().join(file),
            &["--screen-height", &h.to_string()],
        );
        let measured = eval.coverage.animated.mean.expect("mean");
        assert!(
            (coverage - measured).abs() < 1e-9,
            "{file}: report {coverage}, frond eval {measured}"
        );
        // The same renders: frond eval's ratio, binary error and framing.
        assert!(
            (e.coverage_ratio - eval.coverage.ratio).abs() < 1e-9,
            "{file}: ratio {} against frond eval's {}",
            e.coverage_ratio,
            eval.coverage.ratio
        );
        let binary = eval.coverage.binary.mean;
        assert!(
            e.coverage_binary
                .zip(binary)
                .is_some_and(|(a, b)| (a - b).abs() < 1e-9),
            "{file}: binary {:?} against frond eval's {binary:?}",
            e.coverage_binary
        );
        assert_eq!(e.image, eval.size, "{file}");
        assert_eq!(e.samples_per_side, eval.samples_per_side, "{file}");
        assert_eq!(
            (e.views, &e.elevations_deg, e.frames),
            (eval.views, &eval.elevations_deg, eval.frames),
            "{file}"
        );
        assert_eq!(e.within_target, coverage <= 0.15);
        assert_eq!(lod.method.name(), "cards");
        assert!(coverage <= bound, "{file}: error {coverage} at {h} px");
        // The cards are scaled to keep the tree's covered area: neither thinned nor bloated.
        assert!(
            (e.coverage_ratio - 1.0).abs() <= 0.02,
            "{file}: coverage ratio {} at {h} px",
            e.coverage_ratio
        );
        // The switch pop: LOD1 replaces the input itself, so its pop is its error; a later
        // LOD's is against the LOD before it, a number of its own.
        assert!(
            e.switch_pop.is_finite() && (0.0..1.0).contains(&e.switch_pop),
            "{file}: switch pop {}",
            e.switch_pop
        );
        if k == 0 {
            assert_eq!(e.switch_pop, coverage, "{file}");
        }
    }
    // The default chain keeps the monotone rule on every cost read back from its files, and
    // each LOD its own budgets (the cards grow only within the input's alpha-tested area): no
    // warning names one.
    let warnings = &report.warnings;
    assert!(
        !warnings
            .iter()
            .any(|w| w.contains("costs more than") || w.contains("over its budget")),
        "{warnings:?}"
    );
    let (near, far) = (&lods[1], &lods[2]);
    // Depth complexity (fragments per covered sample) at each LOD's size: a LOD draws fewer
    // layers than the input seen at the same size, and the far one fewer than the near one.
    let error = |l: &LodEntry| l.error.clone().expect("error");
    for l in [near, far] {
        let (lod, input) = (error(l).depth_complexity, error(l).input_depth_complexity);
        assert!(
            lod >= 1.0 && lod < input,
            "LOD {lod} against the input's {input}"
        );
    }
    assert!(error(far).depth_complexity <= error(near).depth_complexity);
    // Drawn area is shared by every instance of a species: each LOD's budget is the input's
    // area, whatever the LOD before it drew, and no LOD draws more.
    let area = |l: &LodEntry| l.cost.as_ref().expect("cost").alpha_tested_area;
    let input = area(&lods[0]);
    for l in [near, far] {
        let budget = l.budget.as_ref().expect("area budget").alpha_tested_area;
        assert!(
            (budget - input).abs() <= 1e-3 * input,
            "{}: area budget {budget}, the input's area {input}",
            l.file
        );
        assert!(area(l) <= input * (1.0 + 1e-6), "{}: {}", l.file, area(l));
    }
}

#[test]
fn a_lod_over_its_error_target_is_written_with_a_warning() {
    let out = tempfile::tempdir().expect("tempdir");
    let report = measured_chain(out.path(), "40", "0.01");
    let lod = &report.lods[1];
    let file = lod.file.as_str();
    assert!(out.path().join(file).is_file(), "{file} is written");
    assert!(!lod.error.as_ref().expect("error").within_target);
    let warnings = &report.warnings;
    assert!(
        warnings
            .iter()
            .any(|w| w.contains(file) && w.contains("--max-error")),
        "{warnings:?}"
    );
}
