// frond rigid VAT, layout "houdini-vat3-rigid" (the sidecar's `layout`; export/VAT.md), for Unity
// Shader Graph: a Custom Function file (Type: File, Name: FrondVatRigid). The numbers come from
// the LOD's sidecar `<tree>_LOD<k>_vat.json`: Frames = `frames`, Fps = `fps`, BoundMin /
// BoundMax = `bound_min` / `bound_max`, Hdr = `hdr` (1 for EXR, 0 for PNG16); the textures are
// `textures.position` and `textures.rotation`. Same decoding as frond_vat_rigid.wgsl (the tested
// reference), plus Unity's import conventions.
//
// glTF to Unity: glTFast and UnityGLTF import the mesh with x negated and every UV set's v
// flipped (v' = 1 - v), and Unity stores images bottom row first. So this file reads the pivot as
// (-uv2.x, uv3.x, 1 - uv3.y), steps frames upwards in the texture (row_step = -1), and mirrors
// the decoded data: P = (-P.x, P.y, P.z), q = (q.x, -q.y, -q.z, q.w). An importer that does not
// mirror x or flip v needs the plain reference (frond_vat_rigid.hlsl) instead.
//
// Graph (vertex stage), inputs in this order:
//   RestPosition  Position node, Object space      RestNormal  Normal Vector node, Object space
//   PieceUV       UV node, UV1 (TEXCOORD_1)         PivotXY     UV2 (TEXCOORD_2)
//   PivotYZ       UV3 (TEXCOORD_3)                  Time        clip time in seconds (Time node)
//   PositionTex, RotationTex   Texture2D properties  BoundMin, BoundMax, Frames, Fps, Hdr
//   ClipStart     clip time of frame 0 (the sidecar's `start_s`)
//   EngineSpace   1 when the sidecar's `space` is "unity" (`frond lod --vat-space unity` or
//                 `--preset unity`): data and pivot already in Unity's space, as Houdini bakes
//                 for Unity; 0 for "gltf" (converted here)
// outputs Position -> Vertex Position (Object), Normal -> Vertex Normal (Object).
// Import both textures with sRGB off, Non-Power of 2 = None, no mipmaps, Filter Point, Wrap
// Clamp, Compression None (PNG16: format RGBA 64 bit, or RGBA Half for EXR). The mesh's UV1-3
// must stay 32-bit floats.

#ifndef FROND_VAT_RIGID_UNITY_INCLUDED
#define FROND_VAT_RIGID_UNITY_INCLUDED

// Rotates v by the unit quaternion q = (x, y, z, w).
float3 FrondVatRotate(float4 q, float3 v)
{
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// Rebuilds (x, y, z, w) from the three stored components; position alpha * 4 names the dropped,
// largest, positive component (0 = w, 1 = x, 2 = y, 3 = z) whose slot holds w.
float4 FrondVatDecodeRotation(float3 stored, float positionAlpha)
{
    float largest = sqrt(max(0.0, 1.0 - dot(stored, stored)));
    int dropped = (int)floor(positionAlpha * 4.0 + 0.5);
    if (dropped == 1)
    {
        return float4(largest, stored.y, stored.z, stored.x);
    }
    if (dropped == 2)
    {
        return float4(stored.x, largest, stored.z, stored.y);
    }
    if (dropped == 3)
    {
        return float4(stored.x, stored.y, largest, stored.z);
    }
    return float4(stored, largest);
}

// Shortest-path slerp; normalized lerp when the rotations are within ~1.8 degrees.
float4 FrondVatSlerp(float4 a, float4 b, float t)
{
    float d = dot(a, b);
    if (d < 0.0)
    {
        b = -b;
        d = -d;
    }
    if (d > 0.9995)
    {
        return normalize(lerp(a, b, t));
    }
    float angle = acos(d);
    return normalize(a * sin((1.0 - t) * angle) + b * sin(t * angle));
}

// The pose of the piece at pieceUv (Unity's flipped UV1) at integer frame, in Unity's space.
void FrondVatLoad(UnityTexture2D positionTex, UnityTexture2D rotationTex, float2 pieceUv, int frame,
                  float frames, float3 boundMin, float3 boundMax, float hdr, float engineSpace,
                  out float3 position, out float4 rotation)
{
    int2 size = int2(positionTex.texelSize.zw);
    int rowsPerFrame = size.y / max((int)frames, 1);
    int x = clamp((int)floor(pieceUv.x * (float)size.x), 0, size.x - 1);
    // v flipped and images bottom row first: frame f lies f * rowsPerFrame rows up.
    int row = (int)floor(pieceUv.y * (float)size.y) - frame * rowsPerFrame;
    int y = clamp(row, 0, size.y - 1);
    float4 p = LOAD_TEXTURE2D_LOD(positionTex.tex, int2(x, y), 0);
    float4 r = LOAD_TEXTURE2D_LOD(rotationTex.tex, int2(x, y), 0);
    float3 glPosition = p.xyz;
    float3 stored = r.xyz;
    if (hdr < 0.5)
    {
        glPosition = lerp(boundMin, boundMax, p.xyz);
        stored = r.xyz * 2.0 - 1.0;
    }
    float4 glRotation = FrondVatDecodeRotation(stored, p.w);
    // glTF space -> Unity space (x mirrored), unless baked in it.
    position = float3(-glPosition.x, glPosition.y, glPosition.z);
    rotation = float4(glRotation.x, -glRotation.y, -glRotation.z, glRotation.w);
    if (engineSpace > 0.5)
    {
        position = glPosition;
        rotation = glRotation;
    }
}

// Animated object-space position and normal of a rest-pose vertex at clip time Time.
void FrondVatRigid_float(float3 RestPosition, float3 RestNormal, float2 PieceUV, float2 PivotXY,
                         float2 PivotYZ, float Time, UnityTexture2D PositionTex,
                         UnityTexture2D RotationTex, float3 BoundMin, float3 BoundMax,
                         float Frames, float Fps, float Hdr, float ClipStart, float EngineSpace,
                         out float3 Position, out float3 Normal)
{
    // Unity-space pivot channels were written with v pre-flipped: they read as the pivot.
    float3 pivot = EngineSpace > 0.5 ? float3(PivotXY.x, PivotYZ.x, PivotYZ.y)
                                     : float3(-PivotXY.x, PivotYZ.x, 1.0 - PivotYZ.y);
    float frames = max(Frames, 1.0);
    float frame = (Time - ClipStart) * Fps;
    float wrapped = frame - frames * floor(frame / frames);
    float f0 = min(floor(wrapped), frames - 1.0);
    float t = wrapped - f0;
    int i0 = (int)f0;
    int i1 = (i0 + 1) % (int)frames;
    float3 positionA, positionB;
    float4 rotationA, rotationB;
    FrondVatLoad(PositionTex, RotationTex, PieceUV, i0, frames, BoundMin, BoundMax, Hdr,
                 EngineSpace, positionA, rotationA);
    FrondVatLoad(PositionTex, RotationTex, PieceUV, i1, frames, BoundMin, BoundMax, Hdr,
                 EngineSpace, positionB, rotationB);
    float3 position = lerp(positionA, positionB, t);
    float4 rotation = FrondVatSlerp(rotationA, rotationB, t);
    Position = FrondVatRotate(rotation, RestPosition - pivot) + position;
    Normal = FrondVatRotate(rotation, RestNormal);
}

// Half-precision graphs: computed in float, but the inputs arrive as half (no texel past 2048,
// positions to ~8 mm at 10 m, time in 2 s steps after 2048 s): set this node to Float precision.
void FrondVatRigid_half(half3 RestPosition, half3 RestNormal, half2 PieceUV, half2 PivotXY,
                        half2 PivotYZ, half Time, UnityTexture2D PositionTex,
                        UnityTexture2D RotationTex, half3 BoundMin, half3 BoundMax,
                        half Frames, half Fps, half Hdr, half ClipStart, half EngineSpace,
                        out half3 Position, out half3 Normal)
{
    float3 position, normal;
    FrondVatRigid_float((float3)RestPosition, (float3)RestNormal, (float2)PieceUV,
                        (float2)PivotXY, (float2)PivotYZ, (float)Time, PositionTex, RotationTex,
                        (float3)BoundMin, (float3)BoundMax, (float)Frames, (float)Fps,
                        (float)Hdr, (float)ClipStart, (float)EngineSpace, position, normal);
    Position = (half3)position;
    Normal = (half3)normal;
}

#endif // FROND_VAT_RIGID_UNITY_INCLUDED
