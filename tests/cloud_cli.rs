//! `frond cloud` end to end: files, `<name>_cloud_stats.json` keys, validity, determinism, bad arguments.

use crate::common;

use common::*;
use frond_app::cloud_cmd::CloudReport;

fn cloud(args: &[&str], out: &std::path::Path) -> std::process::Output {
    let mut all = vec![
        "cloud",
        "samples/sapling.glb",
        "--coverage-views",
        "3",
        "--coverage-height",
        "120",
    ];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", out.to_str().expect("utf-8")]);
    std::process::Command::new(env!("CARGO_BIN_EXE_frond"))
        .args(&all)
        .current_dir(root())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("frond runs")
}

#[test]
fn cloud_writes_a_valid_glb_atlases_and_stats() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("c");
    let run = cloud(&["--epsilon", "5%", "--planes", "100", "--seed", "3"], &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for f in [
        "sapling_cloud.glb",
        "sapling_atlas_color.png",
        "sapling_atlas_normal.png",
        "sapling_cloud_stats.json",
    ] {
        assert!(out.join(f).exists(), "{f} written");
    }
    // The typed read requires ε, the planes, the seed, the billboards, their area, the texture
    // bytes and the plane search's, bake's and total timings.
    let stats: CloudReport = read_json(&out.join("sapling_cloud_stats.json"));
    assert!(
        stats.coverage_error.is_some(),
        "the stats have coverage_error"
    );
    assert_eq!(stats.planes, 100);
    assert_eq!(stats.seed, 3);
    let billboards = stats.billboards as u64;
    assert!(
        (2..200).contains(&billboards),
        "{billboards} billboards for 2000 leaf triangles at 5%"
    );
    let cov = stats.coverage_error.expect("coverage");
    assert!(cov > 0.0 && cov < 0.6, "coverage error {cov}");
    // ε = 5 % of the diagonal bounds every vertex's distance to its billboard.
    let eps = written_f64(stats.epsilon);
    let diag = written_f64(stats.diagonal);
    assert!((eps - 0.05 * diag).abs() < 1e-4 * diag);
    assert!(written_f64(stats.cloud.max_distance) <= eps * (1.0 + 1e-5));
    // Real clients accept the GLB: quads + wood, textured, no errors.
    if let Some(report) = validate(&out.join("sapling_cloud.glb")) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["info"]["hasTextures"], true);
        let tris = report["info"]["totalTriangleCount"]
            .as_u64()
            .expect("triangles");
        assert!(tris >= 2 * billboards, "{tris} triangles");
    }
    // The atlas is an RGBA image whose alpha marks the baked leaves.
    let atlas = image::open(out.join("sapling_atlas_color.png"))
        .expect("png")
        .to_rgba8();
    let opaque = atlas.pixels().filter(|p| p[3] >= 128).count();
    assert!(opaque > 0 && opaque < (atlas.width() * atlas.height()) as usize);
}

#[test]
fn same_seed_gives_byte_identical_files_whatever_the_thread_count() {
    let dir = tempfile::tempdir().expect("tmp");
    let run = |name: &str, threads: &str| {
        let out = dir.path().join(name);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_frond"))
            .args([
                "cloud",
                "samples/sapling.glb",
                "--epsilon",
                "3%",
                "--planes",
                "60",
                "--seed",
                "9",
            ])
            .args(["--coverage-views", "0", "-o"])
            .arg(&out)
            .current_dir(root())
            .env("RAYON_NUM_THREADS", threads)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let a = run("a", "1");
    let b = run("b", "2");
    for f in [
        "sapling_cloud.glb",
        "sapling_atlas_color.png",
        "sapling_atlas_normal.png",
    ] {
        let (x, y) = (
            std::fs::read(a.join(f)).expect("a"),
            std::fs::read(b.join(f)).expect("b"),
        );
        assert!(x == y, "{f} differs between 1 and 2 threads");
    }
}

#[test]
fn bad_epsilon_is_a_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("never");
    for eps in ["-1", "five", "-3%"] {
        let arg = format!("--epsilon={eps}");
        let run = cloud(&[&arg], &out);
        // A length is parsed at the edge: a usage error (clap's exit code 2).
        assert_eq!(run.status.code(), Some(2), "{eps}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains("--epsilon"), "{err}");
        assert!(err.contains("percentage"), "{err}");
        assert!(!out.exists(), "nothing written for a bad ε");
    }
}

#[test]
fn increased_density_keeps_the_planes_and_fills_the_cloud() {
    // Baking every triangle valid for a plane (spec §2.4, §3.6.2) leaves the plane choice alone
    // and counters the sparse look: the cloud covers more of what the original covers.
    use frond_app::cloud_cmd::{CloudRequest, make_cloud};
    use frond_billboard::cloud::CloudParams;
    let tree = frond_scene::import(&root().join("samples/sapling.glb"), &Default::default())
        .expect("imports");
    let renderer = frond_render::Renderer::new().expect("adapter");
    let run = |increased_density: bool| {
        let mut params = CloudParams {
            increased_density,
            ..Default::default()
        };
        params.search.candidates = 100;
        params.search.seed = 2;
        params.bake.texels_per_unit = 24.0;
        let req = CloudRequest {
            epsilon: frond_scene::Length::Percent(5.0),
            params,
            samples: 16,
            clip: None,
            coverage_views: 3,
            coverage_height: 120.0,
        };
        make_cloud(&renderer, &tree, &req).expect("cloud").2
    };
    let plain = run(false);
    let dense = run(true);
    assert_eq!(plain.billboards, dense.billboards);
    assert_eq!(plain.total_area, dense.total_area);
    let (a, b) = (
        plain.coverage_error.expect("measured"),
        dense.coverage_error.expect("measured"),
    );
    assert!(b < a, "coverage error with increased density {b} vs {a}");
}
