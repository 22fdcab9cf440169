// frond LOD cross-fade (dithered), no texture layout: reads only a fade value the engine computes
// per instance and the fragment's pixel position. HLSL (SM 4.0+) functions; equivalent to
// frond_lod_dither.wgsl (see it for the full contract) and frond_lod_dither.glsl. Also a Unity
// Shader Graph Custom Function file (FrondLodDither_float / _half).
//
// LOD k fades into LOD k+1 over a band: fade = 0 at the band's near edge (LOD k only), 1 at its
// far edge (LOD k+1 only). Draw LOD k with incoming = false and LOD k+1 with incoming = true;
// each discards the pixels the other keeps, so every pixel is drawn exactly once:
//   FrondLodDitherClip(fade, input.position.xy, incoming);   // input.position: SV_Position
// It relies on every LOD playing the sampled clip in phase (same clip time for the skinned
// LODs, the VAT frame and the spectral loop fraction) and on both draws using the same fade
// (computed per instance, not per fragment). Unity's own LOD cross-fade value (unity_LODFade.x
// with LOD_FADE_CROSSFADE) may be mapped onto fade; the partition needs both LODs to use this
// function, not Unity's dither on one side.

// Ordered-dither threshold (b + 0.5) / 16 of the pixel at fragXY, b its 4x4 Bayer index
// (rows 0 8 2 10 / 12 4 14 6 / 3 11 1 9 / 15 7 13 5) from the bits of x and y.
float FrondLodDitherThreshold(float2 fragXY)
{
    float2 p = floor(fragXY) - 4.0 * floor(floor(fragXY) / 4.0);
    float2 lo = p - 2.0 * floor(p / 2.0);
    float2 hi = floor(p / 2.0);
    float b = 8.0 * abs(lo.x - lo.y) + 4.0 * lo.y + 2.0 * abs(hi.x - hi.y) + hi.y;
    return (b + 0.5) / 16.0;
}

// Whether this LOD draws the pixel at fragXY at fade in [0, 1]: the incoming LOD takes the
// pixels whose threshold is below fade, the outgoing LOD the others.
bool FrondLodDitherKeep(float fade, float2 fragXY, bool incoming)
{
    bool toIncoming = FrondLodDitherThreshold(fragXY) < fade;
    return toIncoming == incoming;
}

// Discards the pixel where the other LOD draws it (pixel shaders only).
void FrondLodDitherClip(float fade, float2 fragXY, bool incoming)
{
    clip(FrondLodDitherKeep(fade, fragXY, incoming) ? 1.0 : -1.0);
}

// Shader Graph Custom Function (fragment stage): Keep = 1 where this LOD draws the pixel, else 0.
// Multiply it into Alpha with Alpha Clipping on (threshold 0.5 or the material's cutoff).
// PixelPosition: Screen Position node in Pixel mode (.xy); Incoming: 0 for LOD k, 1 for LOD k+1.
void FrondLodDither_float(float Fade, float2 PixelPosition, float Incoming, out float Keep)
{
    Keep = FrondLodDitherKeep(Fade, PixelPosition, Incoming > 0.5) ? 1.0 : 0.0;
}

void FrondLodDither_half(half Fade, half2 PixelPosition, half Incoming, out half Keep)
{
    // Half holds pixel positions exactly only up to 2048: set the node to Float precision on
    // wider targets.
    Keep = FrondLodDitherKeep((float)Fade, (float2)PixelPosition, Incoming > 0.5) ? 1.0 : 0.0;
}
