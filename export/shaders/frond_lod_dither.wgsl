// frond LOD cross-fade (dithered), no texture layout: reads only a fade value the engine computes
// per instance and the fragment's pixel position. Equivalent to frond_lod_dither.glsl,
// frond_lod_dither.hlsl and the functions of the same name in the Godot materials; a test
// (export/tests/shader_compile.rs) checks that the two sides partition every 4x4 tile.
//
// LOD k fades into LOD k+1 over a band (a distance or screen-size range the engine picks, e.g.
// around the MSFT_lod coverage of the combined file): fade = 0 at the band's near edge (LOD k
// only), 1 at its far edge (LOD k+1 only). Both LODs are drawn inside the band: LOD k with
// incoming = false, LOD k+1 with incoming = true, and each discards the pixels the other keeps,
// so every pixel both cover is drawn by exactly one of them (no blending, no sorting, depth
// writes stay on): frond_lod_dither_discard(fade, position.xy, incoming) in the fragment stage.
//
// Requirements:
// - Every LOD plays the sampled clip in phase: the same clip time drives the skinned LODs'
//   animation, the VAT frame and the spectral loop fraction. Out of phase, the two halves of the
//   dither show two different poses and the fade shimmers.
// - Both draws use the same fade value for a pixel: compute it once per instance (from the
//   object's position or screen size), not per fragment from each LOD's own depth.
// - frag_xy is the framebuffer pixel position (@builtin(position).xy; any half-pixel origin
//   works as long as both LODs use the same one).

// Ordered-dither threshold of the pixel at frag_xy: (b + 0.5) / 16 with b the 4x4 Bayer index
//    0  8  2 10
//   12  4 14  6
//    3 11  1  9
//   15  7 13  5
// (row = y mod 4, column = x mod 4), built from the bits of x and y: b = 8 (x0 ^ y0) + 4 y0 +
// 2 (x1 ^ y1) + y1. Float arithmetic only, so every dialect computes the same value.
fn frond_lod_dither_threshold(frag_xy: vec2<f32>) -> f32 {
    let p = floor(frag_xy) - 4.0 * floor(floor(frag_xy) / 4.0);
    let lo = p - 2.0 * floor(p / 2.0);
    let hi = floor(p / 2.0);
    let b = 8.0 * abs(lo.x - lo.y) + 4.0 * lo.y + 2.0 * abs(hi.x - hi.y) + hi.y;
    return (b + 0.5) / 16.0;
}

// Whether this LOD draws the pixel at frag_xy at fade in [0, 1]: the incoming LOD takes the
// pixels whose threshold is below fade, the outgoing LOD the others. fade <= 0 leaves all to
// the outgoing LOD, fade >= 1 all to the incoming one.
fn frond_lod_dither_keep(fade: f32, frag_xy: vec2<f32>, incoming: bool) -> bool {
    let to_incoming = frond_lod_dither_threshold(frag_xy) < fade;
    return to_incoming == incoming;
}

// Discards the fragment where the other LOD draws the pixel (call from the fragment stage).
fn frond_lod_dither_discard(fade: f32, frag_xy: vec2<f32>, incoming: bool) {
    if !frond_lod_dither_keep(fade, frag_xy, incoming) {
        discard;
    }
}
