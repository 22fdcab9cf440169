//! Each LOD's error at its own size: `frond lod` measures it on the written
//! files and reports the number `frond eval INPUT LOD --screen-height H` gives, warns about a
//! LOD over `--max-error` and writes it all the same; the card LODs of the sample stay within
//! the errors their coverage-driven thinning reached when it was written.

mod common;

use common::*;
use frond_lod::{LodEntry, LodReport};

/// Runs `frond lod` on the sample at `lods` with the error measured against `max_error`;
/// returns the report.
fn measured_chain(out: &std::path::Path, lods: &str, max_error: &str) -> LodReport {
    let sample = root().join("samples/sapling.glb");
    frond_lod_measured(&sample, out, &["--lods", lods, "--max-error", max_error])
}

#[test]
fn the_report_gives_each_lods_error_as_frond_eval_measures_it() {
    let out = tempfile::tempdir().expect("tempdir");
    let report = measured_chain(out.path(), "200,60", "0.15");
    let lods = &report.lods;
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
    // The card LODs' errors when coverage-driven thinning was written: 0.093 and 0.216.
    for (lod, (h, bound)) in lods[1..].iter().zip([(200u32, 0.12), (60, 0.26)]) {
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
        assert_eq!(e.image, [(h * 4).div_ceil(3), h]);
        assert_eq!(e.within_target, coverage <= 0.15);
        assert_eq!(lod.method.name(), "cards");
        assert!(coverage <= bound, "{file}: error {coverage} at {h} px");
    }
    // The default chain keeps the monotone rule on every cost read back from its files (the
    // 60 px cards grow only within the 200 px LOD's alpha-tested area): no warning names one.
    let warnings = &report.warnings;
    assert!(
        !warnings.iter().any(|w| w.contains("costs more than")),
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
    let area = |l: &LodEntry| l.cost.as_ref().expect("cost").alpha_tested_area;
    assert!(area(far) <= area(near), "overdraw grows at 60 px");
    assert!(
        (far.budget.as_ref().expect("area budget").alpha_tested_area - area(near)).abs()
            <= 1e-3 * area(near),
        "the 60 px LOD's area budget is the 200 px LOD's area"
    );
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
