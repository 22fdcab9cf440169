// Rigid vertex animation textures as frond-export writes them (Houdini VAT 3.0 rigid layout;
// export/VAT.md). GLSL 3.30 / GLSL ES 3.00 functions to paste or #include before a vertex shader:
// no #version, no uniforms, no main. Equivalent to frond_vat_rigid.wgsl (the tested reference).
//
// Usage in a vertex shader:
//   in vec2 aPieceUv;   // TEXCOORD_1
//   in vec2 aPivotXY;   // TEXCOORD_2: (pivot.x, 0)
//   in vec2 aPivotYZ;   // TEXCOORD_3: (pivot.y, pivot.z)
//   vec3 pivot = vec3(aPivotXY.x, aPivotYZ.x, aPivotYZ.y);
//   vec3 position, normal;
//   vatRigid(aPosition, aNormal, aPieceUv, pivot, time * fps, uVatPosition, uVatRotation, params,
//            position, normal);
// Bind both textures with NEAREST filtering and no mipmaps (texelFetch ignores the sampler).

// Material constants from the sidecar JSON.
struct VatRigidParams {
    vec3 boundMin;   // bound_min: PNG16 positions decode as mix(boundMin, boundMax, texel)
    float frameCount; // frames
    vec3 boundMax;   // bound_max
    float hdr;       // 1.0 for EXR (raw texels), 0.0 for PNG16 (remapped texels)
    float rowStep;   // +1.0: texel row 0 is the image's top row and v grows downwards (uploaded
                     // as stored in the file); -1.0: images uploaded bottom row first with v
                     // flipped (Unity, three.js flipY = true)
};

// Rotates v by the unit quaternion q = (x, y, z, w).
vec3 vatRotate(vec4 q, vec3 v) {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// Rebuilds (x, y, z, w) from the three stored components; position alpha * 4 names the dropped,
// largest, positive component (0 = w, 1 = x, 2 = y, 3 = z) whose slot holds w.
vec4 vatDecodeRotation(vec3 stored, float positionAlpha) {
    float largest = sqrt(max(0.0, 1.0 - dot(stored, stored)));
    int dropped = int(floor(positionAlpha * 4.0 + 0.5));
    if (dropped == 1) {
        return vec4(largest, stored.y, stored.z, stored.x);
    }
    if (dropped == 2) {
        return vec4(stored.x, largest, stored.z, stored.y);
    }
    if (dropped == 3) {
        return vec4(stored.x, stored.y, largest, stored.z);
    }
    return vec4(stored, largest);
}

// Shortest-path slerp; normalized lerp when the rotations are within ~1.8 degrees.
vec4 vatSlerp(vec4 a, vec4 b, float t) {
    float d = dot(a, b);
    if (d < 0.0) {
        b = -b;
        d = -d;
    }
    if (d > 0.9995) {
        return normalize(mix(a, b, t));
    }
    float angle = acos(d);
    return normalize(a * sin((1.0 - t) * angle) + b * sin(t * angle));
}

// The pose of the piece at pieceUv (TEXCOORD_1) at integer frame: point-sampled texels.
void vatLoad(sampler2D positionTex, sampler2D rotationTex, vec2 pieceUv, int frame,
             VatRigidParams params, out vec3 position, out vec4 rotation) {
    ivec2 size = textureSize(positionTex, 0);
    int rowsPerFrame = size.y / max(int(params.frameCount), 1);
    int x = clamp(int(floor(pieceUv.x * float(size.x))), 0, size.x - 1);
    int rowSign = params.rowStep < 0.0 ? -1 : 1;
    int row = int(floor(pieceUv.y * float(size.y))) + rowSign * frame * rowsPerFrame;
    int y = clamp(row, 0, size.y - 1);
    vec4 p = texelFetch(positionTex, ivec2(x, y), 0);
    vec4 r = texelFetch(rotationTex, ivec2(x, y), 0);
    position = p.xyz;
    vec3 stored = r.xyz;
    if (params.hdr < 0.5) {
        position = mix(params.boundMin, params.boundMax, p.xyz);
        stored = r.xyz * 2.0 - 1.0;
    }
    rotation = vatDecodeRotation(stored, p.w);
}

// Animated position and normal of a rest-pose vertex at a fractional frame (wraps around the
// loop; frame = time * fps). pivot is the rest pivot (TEXCOORD_2.x, TEXCOORD_3.x, TEXCOORD_3.y).
void vatRigid(vec3 restPosition, vec3 restNormal, vec2 pieceUv, vec3 pivot, float frame,
              sampler2D positionTex, sampler2D rotationTex, VatRigidParams params,
              out vec3 outPosition, out vec3 outNormal) {
    float frames = max(params.frameCount, 1.0);
    float wrapped = frame - frames * floor(frame / frames);
    float f0 = min(floor(wrapped), frames - 1.0);
    float t = wrapped - f0;
    int i0 = int(f0);
    int i1 = (i0 + 1) % int(frames);
    vec3 positionA, positionB;
    vec4 rotationA, rotationB;
    vatLoad(positionTex, rotationTex, pieceUv, i0, params, positionA, rotationA);
    vatLoad(positionTex, rotationTex, pieceUv, i1, params, positionB, rotationB);
    vec3 position = mix(positionA, positionB, t);
    vec4 rotation = vatSlerp(rotationA, rotationB, t);
    outPosition = vatRotate(rotation, restPosition - pivot) + position;
    outNormal = vatRotate(rotation, restNormal);
}
