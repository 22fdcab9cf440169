// Spectral billboard motion as frond-export writes it (`--animation spectral`, layout in the
// sidecar and export/src/spectral.rs). HLSL (SM 4.0+) functions only; equivalent to
// frond_spectral.wgsl (which a test runs) and frond_spectral.glsl.
//
// Per vertex: i = frond_spectral_index(uv1.x); position += frond_spectral_offset(...); then skin
// as usual (the offset is in the followed bone's rest frame, like the mesh's positions).
// `terms` and `per_row` come from the sidecar.

static const float FROND_TAU = 6.28318530718;

// The billboard's index from TEXCOORD_1.x = index + 0.5.
int frond_spectral_index(float uv1_x) {
    return (int)floor(uv1_x);
}

// Loop fraction u in [0, 1) of time t (seconds) for the sidecar's start_s and period_s.
float frond_spectral_phase(float t, float start_s, float period_s) {
    return frac((t - start_s) / period_s);
}

// Sum of a_j cos(2 pi f_j u + phi_j) per axis over billboard i's terms: its block of 2 terms
// texels starts at column 2 terms (i % per_row) of row i / per_row (texel 2j: f, a_xyz;
// texel 2j+1: phi_xyz). Unused terms are zero and add nothing.
float3 frond_spectral_offset(Texture2D<float4> coefficients, int i, int terms, int per_row, float u) {
    int row = i / per_row;
    int base = 2 * terms * (i % per_row);
    float3 offset = float3(0.0, 0.0, 0.0);
    for (int j = 0; j < terms; j++) {
        float4 fa = coefficients.Load(int3(base + 2 * j, row, 0));
        float4 ph = coefficients.Load(int3(base + 2 * j + 1, row, 0));
        offset += fa.yzw * cos(FROND_TAU * fa.x * u + ph.xyz);
    }
    return offset;
}
