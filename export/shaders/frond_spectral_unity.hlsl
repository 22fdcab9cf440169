// frond spectral billboard motion, layout "frond-spectral-2" (the sidecar's `layout`;
// export/src/spectral.rs), for Unity Shader Graph: a Custom Function file (Type: File, Name:
// FrondSpectral). The numbers come from the LOD's sidecar `<tree>_LOD<k>_spectral.json`:
// Terms = `terms`, PerRow = `per_row`, StartS = `start_s`, PeriodS = `period_s`; the texture is
// `texture` (RGBA half EXR). Same sum as frond_spectral.wgsl (the tested reference), plus Unity's
// import conventions.
//
// glTF to Unity: glTFast and UnityGLTF negate x and flip every UV set's v, and Unity stores
// images bottom row first. The index is in UV1.x (u is not flipped); texture row r (from the
// top, as written) is Unity row height - 1 - r; the offset's x is negated like the mesh's.
//
// Graph (vertex stage): Position = Position node (Object), IndexUV = UV node UV1 (TEXCOORD_1),
// Time = clip time in seconds, Coefficients = Texture2D property; OutPosition -> Vertex Position.
// Import the EXR with sRGB off, Non-Power of 2 = None, no mipmaps, Filter Point, Compression
// None (RGBA Half).
//
// Space: frond adds the offset before skinning, in the followed bone's rest frame. Unity skins
// a SkinnedMeshRenderer before the graph's vertex stage, so here the offset lands in object
// space after skinning: off by the bone's rotation from its rest pose (for a bone turned by a
// few degrees, a few percent of an offset that is itself small). Exact only for bones at rest.

#ifndef FROND_SPECTRAL_UNITY_INCLUDED
#define FROND_SPECTRAL_UNITY_INCLUDED

// Sum of a_j cos(2 pi f_j u + phi_j) per axis over billboard `index`'s terms, in glTF space.
float3 FrondSpectralOffset(UnityTexture2D coefficients, int index, int terms, int perRow, float u)
{
    int height = (int)coefficients.texelSize.w;
    int row = height - 1 - index / max(perRow, 1);
    int base = 2 * terms * (index % max(perRow, 1));
    float3 offset = float3(0.0, 0.0, 0.0);
    for (int j = 0; j < terms; j++)
    {
        float4 fa = LOAD_TEXTURE2D_LOD(coefficients.tex, int2(base + 2 * j, row), 0);
        float4 ph = LOAD_TEXTURE2D_LOD(coefficients.tex, int2(base + 2 * j + 1, row), 0);
        offset += fa.yzw * cos(6.28318530718 * fa.x * u + ph.xyz);
    }
    return offset;
}

// Position plus the billboard's own motion at clip time Time (object space, Unity axes).
void FrondSpectral_float(float3 Position, float2 IndexUV, float Time, UnityTexture2D Coefficients,
                         float Terms, float PerRow, float StartS, float PeriodS,
                         out float3 OutPosition)
{
    int index = (int)floor(IndexUV.x);
    float u = frac((Time - StartS) / PeriodS);
    float3 offset = FrondSpectralOffset(Coefficients, index, (int)Terms, (int)PerRow, u);
    OutPosition = Position + float3(-offset.x, offset.y, offset.z);
}

// Half-precision graphs: computed in float, but the inputs arrive as half (the index is exact
// only below 1024, time in 2 s steps after 2048 s): set this node to Float precision.
void FrondSpectral_half(half3 Position, half2 IndexUV, half Time, UnityTexture2D Coefficients,
                        half Terms, half PerRow, half StartS, half PeriodS,
                        out half3 OutPosition)
{
    float3 position;
    FrondSpectral_float((float3)Position, (float2)IndexUV, (float)Time, Coefficients,
                        (float)Terms, (float)PerRow, (float)StartS, (float)PeriodS, position);
    OutPosition = (half3)position;
}

#endif // FROND_SPECTRAL_UNITY_INCLUDED
