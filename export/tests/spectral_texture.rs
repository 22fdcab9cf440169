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

/// Many billboards with up to 3 terms each, so the blocks wrap onto further rows.
fn many(n: usize) -> Vec<Vec<SpectralTerm>> {
    (0..n)
        .map(|i| {
            (0..i % 4)
                .map(|j| SpectralTerm {
                    frequency: (1 + (i + j) % 9) as f32,
                    amplitude: [0.01 * (i % 13) as f32, 0.2, 0.05 * j as f32],
                    phase: [0.1 * (i % 31) as f32 - 1.5, 0.3 * j as f32, -0.7],
                })
                .collect()
        })
        .collect()
}

/// Billboard `i`'s term `j` as the texture holds it.
fn held(texels: &[f32], width: u32, per_row: u32, terms: u32, i: usize, j: usize) -> SpectralTerm {
    let (w, per_row, block) = (width as usize, per_row as usize, 2 * terms as usize);
    let start = (i / per_row) * w + block * (i % per_row) + 2 * j;
    let fa = &texels[start * 4..start * 4 + 4];
    let ph = &texels[(start + 1) * 4..(start + 1) * 4 + 4];
    SpectralTerm {
        frequency: fa[0],
        amplitude: [fa[1], fa[2], fa[3]],
        phase: [ph[0], ph[1], ph[2]],
    }
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
    assert_eq!(tex.sidecar.per_row, 3, "three billboards fit one row");
    assert_eq!((tex.sidecar.width, tex.sidecar.height), (12, 1));
    assert_eq!(tex.sidecar.terms, 2);
    assert_eq!(tex.sidecar.terms_used, 3);
    assert_eq!(tex.sidecar.bytes, tex.image.bytes.len());
    let check = |t: &[Vec<SpectralTerm>], tex: &frond_export::spectral::SpectralTextures| {
        let (w, h, texels) = decode(&tex.image.bytes);
        assert_eq!((w, h), (tex.sidecar.width, tex.sidecar.height));
        for (i, row) in t.iter().enumerate() {
            for j in 0..tex.sidecar.terms as usize {
                let got = held(&texels, w, tex.sidecar.per_row, tex.sidecar.terms, i, j);
                let Some(want) = row.get(j) else {
                    assert_eq!(got.amplitude, [0.0; 3], "unused terms are zero");
                    continue;
                };
                assert_eq!(got.frequency, want.frequency);
                for c in 0..3 {
                    assert!(
                        (got.amplitude[c] - want.amplitude[c]).abs()
                            <= 1e-3 * want.amplitude[c].abs() + 1e-7
                    );
                    assert!((got.phase[c] - want.phase[c]).abs() <= 2e-3);
                }
            }
            assert_eq!(tex.row_uv[i], [i as f32 + 0.5, 0.0]);
        }
    };
    check(&t, &tex);
    // 5,000 billboards of up to 3 terms: blocks of 6 texels, 1,365 a row, 4 rows.
    let big = many(5000);
    let tex_big = encode_spectral(&big, 4.0, 0.0, None, "y.exr").expect("encodes");
    assert_eq!(tex_big.sidecar.per_row, 1365);
    assert_eq!((tex_big.sidecar.width, tex_big.sidecar.height), (8190, 4));
    check(&big, &tex_big);
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
    // Half floats hold whole numbers exactly only up to 2048.
    let high = vec![vec![SpectralTerm {
        frequency: 2049.0,
        amplitude: [0.1, 0.0, 0.0],
        phase: [0.0; 3],
    }]];
    assert!(matches!(
        encode_spectral(&high, 1.0, 0.0, None, "x.exr"),
        Err(VatError::FrequencyTooHigh { piece: 0, .. })
    ));
}

/// The WGSL reference behind a compute entry point: one (row, u) query per invocation.
const HARNESS: &str = r#"
struct Query { index_uv: f32, per_row: f32, terms: f32, time: f32 }

@group(0) @binding(0) var coefficients: texture_2d<f32>;
@group(0) @binding(1) var<storage, read> queries: array<Query>;
@group(0) @binding(2) var<storage, read_write> answers: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    let i = frond_spectral_index(q.index_uv);
    let u = frond_spectral_phase(q.time, 0.5, 4.0);
    answers[id.x] = vec4<f32>(frond_spectral_offset(coefficients, i, i32(q.terms), i32(q.per_row), u), 0.0);
}
"#;

#[test]
fn wgsl_reference_shader_evaluates_the_texture() {
    let Some(gpu) = common::open_compute("frond_spectral.wgsl") else {
        return;
    };
    // Enough billboards to wrap onto four rows.
    let t = many(5000);
    let tex = encode_spectral(&t, 4.0, 0.5, None, "x.exr").expect("encodes");
    let (w, h, texels) = decode(&tex.image.bytes);
    let sc = &tex.sidecar;
    // Queries: billboards on every row at several times, before the start and past a loop.
    let times = [0.5f32, 0.9, 1.7, 3.3, 4.49, 6.1, -0.4];
    let mut queries = Vec::new();
    let mut want = Vec::new();
    for i in [0usize, 1, 2, 3, 1364, 1365, 2731, 4095, 4999] {
        let held: Vec<SpectralTerm> = (0..t[i].len())
            .map(|j| held(&texels, w, sc.per_row, sc.terms, i, j))
            .collect();
        for &time in &times {
            queries.extend_from_slice(&[
                tex.row_uv[i][0],
                sc.per_row as f32,
                sc.terms as f32,
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
