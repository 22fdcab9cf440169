// Rigid vertex animation textures as frond-export writes them (Houdini VAT 3.0 rigid layout;
// export/VAT.md). HLSL (shader model 4+) functions to #include in a vertex shader or an engine's
// custom node: no resources declared, no entry point. Equivalent to frond_vat_rigid.wgsl (the
// tested reference).
//
// Usage in a vertex shader:
//   float2 pieceUv : TEXCOORD1;   // TEXCOORD_1
//   float2 pivotXY : TEXCOORD2;   // TEXCOORD_2: (pivot.x, 0)
//   float2 pivotYZ : TEXCOORD3;   // TEXCOORD_3: (pivot.y, pivot.z)
//   float3 pivot = float3(pivotXY.x, pivotYZ.x, pivotYZ.y);
//   float3 position, normal;
//   VatRigid(input.position, input.normal, input.pieceUv, pivot, time * fps, _VatPosition,
//            _VatRotation, params, position, normal);
// Texture2D.Load point-samples; import the textures uncompressed, linear (not sRGB), no mipmaps.

// Material constants from the sidecar JSON.
struct VatRigidParams {
    float3 boundMin;   // bound_min: PNG16 positions decode as lerp(boundMin, boundMax, texel)
    float frameCount;  // frames
    float3 boundMax;   // bound_max
    float hdr;         // 1.0 for EXR (raw texels), 0.0 for PNG16 (remapped texels)
    float rowStep;     // +1.0: texel row 0 is the image's top row and v grows downwards (D3D,
                       // Unreal); -1.0: images stored bottom row first with v flipped (Unity)
};

// Rotates v by the unit quaternion q = (x, y, z, w).
float3 VatRotate(float4 q, float3 v)
{
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// Rebuilds (x, y, z, w) from the three stored components; position alpha * 4 names the dropped,
// largest, positive component (0 = w, 1 = x, 2 = y, 3 = z) whose slot holds w.
float4 VatDecodeRotation(float3 stored, float positionAlpha)
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
float4 VatSlerp(float4 a, float4 b, float t)
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

// The pose of the piece at pieceUv (TEXCOORD_1) at integer frame: point-sampled texels.
void VatLoad(Texture2D<float4> positionTex, Texture2D<float4> rotationTex, float2 pieceUv,
             int frame, VatRigidParams params, out float3 position, out float4 rotation)
{
    uint width, height;
    positionTex.GetDimensions(width, height);
    int2 size = int2((int)width, (int)height);
    int rowsPerFrame = size.y / max((int)params.frameCount, 1);
    int x = clamp((int)floor(pieceUv.x * (float)size.x), 0, size.x - 1);
    int rowStep = params.rowStep < 0.0 ? -1 : 1;
    int row = (int)floor(pieceUv.y * (float)size.y) + rowStep * frame * rowsPerFrame;
    int y = clamp(row, 0, size.y - 1);
    float4 p = positionTex.Load(int3(x, y, 0));
    float4 r = rotationTex.Load(int3(x, y, 0));
    position = p.xyz;
    float3 stored = r.xyz;
    if (params.hdr < 0.5)
    {
        position = lerp(params.boundMin, params.boundMax, p.xyz);
        stored = r.xyz * 2.0 - 1.0;
    }
    rotation = VatDecodeRotation(stored, p.w);
}

// Animated position and normal of a rest-pose vertex at a fractional frame (wraps around the
// loop; frame = time * fps). pivot is the rest pivot (TEXCOORD_2.x, TEXCOORD_3.x, TEXCOORD_3.y).
void VatRigid(float3 restPosition, float3 restNormal, float2 pieceUv, float3 pivot, float frame,
              Texture2D<float4> positionTex, Texture2D<float4> rotationTex, VatRigidParams params,
              out float3 outPosition, out float3 outNormal)
{
    float frames = max(params.frameCount, 1.0);
    float wrapped = frame - frames * floor(frame / frames);
    float f0 = min(floor(wrapped), frames - 1.0);
    float t = wrapped - f0;
    int i0 = (int)f0;
    int i1 = (i0 + 1) % (int)frames;
    float3 positionA, positionB;
    float4 rotationA, rotationB;
    VatLoad(positionTex, rotationTex, pieceUv, i0, params, positionA, rotationA);
    VatLoad(positionTex, rotationTex, pieceUv, i1, params, positionB, rotationB);
    float3 position = lerp(positionA, positionB, t);
    float4 rotation = VatSlerp(rotationA, rotationB, t);
    outPosition = VatRotate(rotation, restPosition - pivot) + position;
    outNormal = VatRotate(rotation, restNormal);
}
