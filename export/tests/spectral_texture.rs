//! `--animation spectral`: the coefficient texture decodes back to the terms (half-float
//! precision), the CPU evaluation is the inverse DFT of the terms, and the WGSL reference shader
//! computes the same offsets on a GPU (or llvmpipe) compute pass.

mod common;

use frond_export::spectral::{SPECTRAL_LAYOUT, SpectralTerm, encode_spectral, evaluate};
use frond_export::vat::VatError;

fn terms() -> Vec<Vec<SpectralTerm>> {
    vec![
        vec![
            SpectralTerm {
                frequency: 1.0,
                amplitude: [0.5, 0.0, -0.0],
                phase: [0.3, 0.0, 0.0],
            },
            SpectralTerm {
                frequency: 3.0,
                amplitude: [0.1, 0.25, 0.05],
                phase: [-2.0, 1.0, 3.0],
            },
        ],
        Vec::new(),
        vec![SpectralTerm {
            frequency: 7.0,
            amplitude: [0.0, 1.5, 0.2],
            phase: [0.0, -1.2, 0.7],
        }],
    ]
}

fn decode(bytes: &[u8]) -> (u32, u32, Vec<f32>) {
    let img = image::load_from_memory_with_format(bytes, image::ImageFormat::OpenExr)
        .expect("own EXR")
        .into_rgba32f();
    (img.width(), img.height(), img.into_raw())
}

#[test]
fn texture_holds_the_terms_and_evaluates_like_the_dft() {
    let t = terms();
    let tex = encode_spectral(&t, 4.0, 0.5, Some("Wind".into()), "x.exr").expect("encodes");
    assert_eq!(tex.sidecar.layout, SPECTRAL_LAYOUT);
    assert_eq!((tex.sidecar.width, tex.sidecar.height), (4, 3));
    assert_eq!(tex.sidecar.terms, 2);
    assert_eq!(tex.sidecar.terms_used, 3);
    assert_eq!(tex.sidecar.bytes, tex.image.bytes.len());
    let (w, h, texels) = decode(&tex.image.bytes);
    assert_eq!((w, h), (4, 3));
    for (r, row) in t.iter().enumerate() {
        for (j, term) in row.iter().enumerate() {
            let at = |x: usize| &texels[(r * 4 + x) * 4..(r * 4 + x) * 4 + 4];
            let (fa, ph) = (at(2 * j), at(2 * j + 1));
            assert_eq!(fa[0], term.frequency);
            for c in 0..3 {
                assert!((fa[1 + c] - term.amplitude[c]).abs() <= 1e-3 * term.amplitude[c].abs());
                assert!((ph[c] - term.phase[c]).abs() <= 2e-3);
            }
        }
        // Rows hold (r + 0.5) / height.
        assert_eq!(tex.row_uv[r], [(r as f32 + 0.5) / 3.0, 0.0]);
    }
    // The CPU evaluation is the cosine sum: at u = 0 the x of billboard 0 is Σ a cos φ.
    let x0 = evaluate(&t[0], 0.0)[0];
    assert!((x0 - (0.5 * 0.3f32.cos() + 0.1 * (-2.0f32).cos())).abs() < 1e-6);
    assert_eq!(evaluate(&t[1], 0.3), [0.0; 3]);
    // Loops: u and u + 1 agree.
    let (a, b) = (evaluate(&t[2], 0.2), evaluate(&t[2], 1.2));
    for c in 0..3 {
        assert!((a[c] - b[c]).abs() < 1e-4);
    }
    assert!(matches!(
        encode_spectral(&[], 1.0, 0.0, None, "x.exr"),
        Err(VatError::NoPieces)
    ));
    let bad = vec![vec![SpectralTerm {
        frequency: 1.0,
        amplitude: [f32::NAN, 0.0, 0.0],
        phase: [0.0; 3],
    }]];
    assert!(encode_spectral(&bad, 1.0, 0.0, None, "x.exr").is_err());
}

/// The WGSL reference behind a compute entry point: one (row, u) query per invocation.
const HARNESS: &str = r#"
struct Query { row_uv: f32, height: f32, terms: f32, time: f32 }

@group(0) @binding(0) var coefficients: texture_2d<f32>;
@group(0) @binding(1) var<storage, read> queries: array<Query>;
@group(0) @binding(2) var<storage, read_write> answers: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    let row = frond_spectral_row(q.row_uv, q.height);
    let u = frond_spectral_phase(q.time, 0.5, 4.0);
    answers[id.x] = vec4<f32>(frond_spectral_offset(coefficients, row, i32(q.terms), u), 0.0);
}
"#;

#[test]
fn wgsl_reference_shader_evaluates_the_texture() {
    let Some(gpu) = common::open_compute("frond_spectral.wgsl") else {
        return;
    };
    let t = terms();
    let tex = encode_spectral(&t, 4.0, 0.5, None, "x.exr").expect("encodes");
    let (w, h, texels) = decode(&tex.image.bytes);
    // Queries: every billboard at several times, including before the start and past a loop.
    let times = [0.5f32, 0.9, 1.7, 3.3, 4.49, 6.1, -0.4];
    let mut queries = Vec::new();
    let mut want = Vec::new();
    for (r, row) in t.iter().enumerate() {
        // The terms as the texture holds them (half floats).
        let held: Vec<SpectralTerm> = (0..row.len())
            .map(|j| {
                let at = |x: usize| &texels[(r * w as usize + x) * 4..(r * w as usize + x) * 4 + 4];
                let (fa, ph) = (at(2 * j), at(2 * j + 1));
                SpectralTerm {
                    frequency: fa[0],
                    amplitude: [fa[1], fa[2], fa[3]],
                    phase: [ph[0], ph[1], ph[2]],
                }
            })
            .collect();
        for &time in &times {
            queries.extend_from_slice(&[
                tex.row_uv[r][0],
                h as f32,
                tex.sidecar.terms as f32,
                time,
            ]);
            let u = ((time - 0.5) / 4.0).rem_euclid(1.0);
            want.push(evaluate(&held, u));
        }
    }
    let source = format!(
        "{}\n{HARNESS}",
        include_str!("../shaders/frond_spectral.wgsl")
    );
    let out = common::run_compute(
        &gpu,
        &source,
        &texels,
        w,
        h,
        bytemuck::cast_slice(&queries),
        want.len() as u32,
        (want.len() * 16) as u64,
    );
    let got: &[f32] = bytemuck::cast_slice(&out);
    for (i, w) in want.iter().enumerate() {
        for c in 0..3 {
            let g = got[4 * i + c];
            assert!(
                (g - w[c]).abs() <= 1e-4,
                "query {i} axis {c}: shader {g}, CPU {}",
                w[c]
            );
        }
    }
}
