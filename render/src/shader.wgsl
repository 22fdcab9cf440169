// frond-render: textured, alpha-tested, simply lit triangles plus a coverage mask, or
// (fs_normal) the world-space normal facing the viewer for normal-map baking.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: unit direction toward the light (world space).
    light_dir: vec4<f32>,
};

struct Material {
    base_color: vec4<f32>,
    // x: alpha cutoff, negative for opaque and blended materials; y: 1 for blended ones.
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_texture: texture_2d<f32>;
@group(1) @binding(2) var base_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    // w = 1 for lit meshes, 0 for meshes without normals.
    @location(1) normal: vec4<f32>,
    @location(2) uv: vec2<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec4<f32>,
    @location(1) uv: vec2<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(in.position, 1.0);
    out.normal = in.normal;
    out.uv = in.uv;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) coverage: vec4<f32>,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let texel = textureSample(base_texture, base_sampler, in.uv);
    let color = texel * material.base_color;
    let cutoff = material.params.x;
    if (cutoff >= 0.0 && color.a < cutoff) {
        discard;
    }
    var shade = 1.0;
    let n = in.normal.xyz;
    if (in.normal.w > 0.5 && dot(n, n) > 1e-12) {
        shade = 0.6 + 0.4 * abs(dot(normalize(n), globals.light_dir.xyz));
    }
    var out: FragmentOut;
    if (material.params.y > 0.5) {
        // Blended (glTF BLEND): the pipeline composes colour and coverage over the target's,
        // coverage as a + c * (1 - a).
        let a = clamp(color.a, 0.0, 1.0);
        out.color = vec4<f32>(color.rgb * shade, a);
        out.coverage = vec4<f32>(a, 0.0, 0.0, a);
        return out;
    }
    // Opaque and alpha-tested surfaces are written fully opaque (glTF MASK semantics).
    out.color = vec4<f32>(color.rgb * shade, 1.0);
    out.coverage = vec4<f32>(1.0, 0.0, 0.0, 1.0);
    return out;
}

// Normal output: same alpha test and coverage, but the colour target (linear Rgba8Unorm)
// receives the unit world-space normal of the side facing the viewer, encoded n * 0.5 + 0.5.
// Meshes without normals arrive with per-triangle face normals (computed on the CPU).
@fragment
fn fs_normal(in: VertexOut, @builtin(front_facing) front: bool) -> FragmentOut {
    let texel = textureSample(base_texture, base_sampler, in.uv);
    let color = texel * material.base_color;
    let cutoff = material.params.x;
    if (cutoff >= 0.0 && color.a < cutoff) {
        discard;
    }
    var n = vec3<f32>(0.0, 0.0, 0.0);
    if (dot(in.normal.xyz, in.normal.xyz) > 1e-12) {
        n = normalize(in.normal.xyz);
    }
    // Back faces (only drawn for double-sided materials) show their other side.
    if (!front) {
        n = -n;
    }
    var out: FragmentOut;
    out.color = vec4<f32>(n * 0.5 + 0.5, 1.0);
    out.coverage = vec4<f32>(1.0, 0.0, 0.0, 1.0);
    return out;
}
