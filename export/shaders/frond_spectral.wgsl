// Spectral billboard motion as frond-export writes it (`--animation spectral`, layout in the
// sidecar and export/src/spectral.rs). Core functions only: no bindings, no entry point, so a
// pipeline appends its own declarations and calls them from its vertex (or compute) stage.
// Equivalent to frond_spectral.glsl and frond_spectral.hlsl.
//
// Per vertex: i = frond_spectral_index(TEXCOORD_1.x); position += frond_spectral_offset(...);
// then skin as usual (the offset is in the followed bone's rest frame, like the mesh's
// positions). `terms` and `per_row` come from the sidecar.

const FROND_TAU: f32 = 6.28318530718;

// The billboard's index from TEXCOORD_1.x = index + 0.5.
fn frond_spectral_index(uv1_x: f32) -> i32 {
    return i32(floor(uv1_x));
}

// Loop fraction u in [0, 1) of time t (seconds) for the sidecar's start_s and period_s.
fn frond_spectral_phase(t: f32, start_s: f32, period_s: f32) -> f32 {
    return fract((t - start_s) / period_s);
}

// Σ_j a_j cos(2π f_j u + φ_j) per axis over billboard i's `terms` terms: its block of 2·terms
// texels starts at column 2·terms·(i % per_row) of row i / per_row (texel 2j: f, a_xyz;
// texel 2j+1: φ_xyz). Unused terms are zero and add nothing.
fn frond_spectral_offset(coefficients: texture_2d<f32>, i: i32, terms: i32, per_row: i32, u: f32) -> vec3<f32> {
    let row = i / per_row;
    let base = 2 * terms * (i % per_row);
    var offset = vec3<f32>(0.0, 0.0, 0.0);
    for (var j = 0; j < terms; j = j + 1) {
        let fa = textureLoad(coefficients, vec2<i32>(base + 2 * j, row), 0);
        let ph = textureLoad(coefficients, vec2<i32>(base + 2 * j + 1, row), 0);
        offset = offset + fa.yzw * cos(vec3<f32>(FROND_TAU * fa.x * u) + ph.xyz);
    }
    return offset;
}
