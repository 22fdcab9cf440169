// frond LOD cross-fade (dithered), no texture layout: reads only a fade value the engine computes
// per instance and the fragment's pixel position. GLSL 3.30 / GLSL ES 3.00 functions to paste or
// #include in a fragment shader; equivalent to frond_lod_dither.wgsl (see it for the full
// contract) and frond_lod_dither.hlsl.
//
// LOD k fades into LOD k+1 over a band: fade = 0 at the band's near edge (LOD k only), 1 at its
// far edge (LOD k+1 only). Draw LOD k with incoming = false and LOD k+1 with incoming = true;
// each discards the pixels the other keeps, so every pixel is drawn exactly once:
//   frondLodDitherDiscard(uFade, gl_FragCoord.xy, uIncoming);
// It relies on every LOD playing the sampled clip in phase (same clip time for the skinned
// LODs, the VAT frame and the spectral loop fraction) and on both draws using the same fade
// (computed per instance, not per fragment).

// Ordered-dither threshold (b + 0.5) / 16 of the pixel at fragXY, b its 4x4 Bayer index
// (rows 0 8 2 10 / 12 4 14 6 / 3 11 1 9 / 15 7 13 5) from the bits of x and y.
float frondLodDitherThreshold(vec2 fragXY) {
    vec2 p = floor(fragXY) - 4.0 * floor(floor(fragXY) / 4.0);
    vec2 lo = p - 2.0 * floor(p / 2.0);
    vec2 hi = floor(p / 2.0);
    float b = 8.0 * abs(lo.x - lo.y) + 4.0 * lo.y + 2.0 * abs(hi.x - hi.y) + hi.y;
    return (b + 0.5) / 16.0;
}

// Whether this LOD draws the pixel at fragXY at fade in [0, 1]: the incoming LOD takes the
// pixels whose threshold is below fade, the outgoing LOD the others.
bool frondLodDitherKeep(float fade, vec2 fragXY, bool incoming) {
    bool toIncoming = frondLodDitherThreshold(fragXY) < fade;
    return toIncoming == incoming;
}

// Discards the fragment where the other LOD draws the pixel (fragment shaders only).
void frondLodDitherDiscard(float fade, vec2 fragXY, bool incoming) {
    if (!frondLodDitherKeep(fade, fragXY, incoming)) {
        discard;
    }
}
