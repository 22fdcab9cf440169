// Rigid vertex animation textures as frond-export writes them (Houdini VAT 3.0 rigid layout;
// export/VAT.md). Core functions only — no bindings, no entry point — so a pipeline can append its
// own declarations and call `vat_rigid` from its vertex (or compute) stage.
//
// Equivalent to frond_vat_rigid.glsl and frond_vat_rigid.hlsl.

// Material constants from the sidecar JSON.
struct VatRigidParams {
    // `bound_min` / `bound_max`: PNG16 positions decode as mix(bound_min, bound_max, texel).
    bound_min: vec3<f32>,
    // `frames`: texel rows per frame = texture height / frame_count.
    frame_count: f32,
    bound_max: vec3<f32>,
    // 1.0 for EXR (raw texels), 0.0 for PNG16 (remapped texels).
    hdr: f32,
    // +1.0 when texture row 0 is the image file's top row and UV v grows downwards (as uploaded:
    // WebGPU, Vulkan, D3D, Metal, Unreal, glTF); -1.0 when the engine stores images bottom row
    // first and flips v on import (Unity, three.js with flipY). Frame f lies f/frames further in v.
    row_step: f32,
}

struct VatRigidOutput {
    position: vec3<f32>,
    normal: vec3<f32>,
}

struct VatRigidPose {
    position: vec3<f32>,
    rotation: vec4<f32>,
}

// Rotates v by the unit quaternion q = (x, y, z, w).
fn vat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// Rebuilds (x, y, z, w) from the three stored components; position alpha × 4 names the dropped,
// largest, positive component (0 = w, 1 = x, 2 = y, 3 = z) whose slot holds w.
fn vat_decode_rotation(stored: vec3<f32>, position_alpha: f32) -> vec4<f32> {
    let largest = sqrt(max(0.0, 1.0 - dot(stored, stored)));
    let dropped = i32(floor(position_alpha * 4.0 + 0.5));
    if dropped == 1 {
        return vec4<f32>(largest, stored.y, stored.z, stored.x);
    }
    if dropped == 2 {
        return vec4<f32>(stored.x, largest, stored.z, stored.y);
    }
    if dropped == 3 {
        return vec4<f32>(stored.x, stored.y, largest, stored.z);
    }
    return vec4<f32>(stored, largest);
}

// Shortest-path slerp; normalized lerp when the rotations are within ~1.8 degrees.
fn vat_slerp(a: vec4<f32>, b_in: vec4<f32>, t: f32) -> vec4<f32> {
    var b = b_in;
    var d = dot(a, b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        return normalize(mix(a, b, t));
    }
    let angle = acos(d);
    return normalize(a * sin((1.0 - t) * angle) + b * sin(t * angle));
}

// The pose of the piece at `piece_uv` (TEXCOORD_1) at integer `frame`: point-sampled texels.
fn vat_load(
    position_tex: texture_2d<f32>,
    rotation_tex: texture_2d<f32>,
    piece_uv: vec2<f32>,
    frame: i32,
    params: VatRigidParams,
) -> VatRigidPose {
    let size = vec2<i32>(textureDimensions(position_tex));
    let rows_per_frame = size.y / max(i32(params.frame_count), 1);
    let x = clamp(i32(floor(piece_uv.x * f32(size.x))), 0, size.x - 1);
    let row_sign = select(1, -1, params.row_step < 0.0);
    let row = i32(floor(piece_uv.y * f32(size.y))) + row_sign * frame * rows_per_frame;
    let y = clamp(row, 0, size.y - 1);
    let p = textureLoad(position_tex, vec2<i32>(x, y), 0);
    let r = textureLoad(rotation_tex, vec2<i32>(x, y), 0);
    var position = p.xyz;
    var stored = r.xyz;
    if params.hdr < 0.5 {
        position = mix(params.bound_min, params.bound_max, p.xyz);
        stored = r.xyz * 2.0 - 1.0;
    }
    return VatRigidPose(position, vat_decode_rotation(stored, p.w));
}

// Animated position and normal of a rest-pose vertex at a fractional frame (wraps around the loop;
// frame = time × fps). `pivot` is the rest pivot (TEXCOORD_2.x, TEXCOORD_3.x, TEXCOORD_3.y).
fn vat_rigid(
    rest_position: vec3<f32>,
    rest_normal: vec3<f32>,
    piece_uv: vec2<f32>,
    pivot: vec3<f32>,
    frame: f32,
    position_tex: texture_2d<f32>,
    rotation_tex: texture_2d<f32>,
    params: VatRigidParams,
) -> VatRigidOutput {
    let frames = max(params.frame_count, 1.0);
    let wrapped = frame - frames * floor(frame / frames);
    let f0 = min(floor(wrapped), frames - 1.0);
    let t = wrapped - f0;
    let i0 = i32(f0);
    let i1 = (i0 + 1) % i32(frames);
    let a = vat_load(position_tex, rotation_tex, piece_uv, i0, params);
    let b = vat_load(position_tex, rotation_tex, piece_uv, i1, params);
    let position = mix(a.position, b.position, t);
    let rotation = vat_slerp(a.rotation, b.rotation, t);
    return VatRigidOutput(
        vat_rotate(rotation, rest_position - pivot) + position,
        vat_rotate(rotation, rest_normal),
    );
}
