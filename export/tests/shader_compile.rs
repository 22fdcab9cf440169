//! Compiles every shipped shader (`export/shaders/`, listed in `frond_export::shaders`) with the
//! compilers this machine has. The files hold functions, so each is compiled inside a small
//! entry point written here:
//!
//! - naga (the version wgpu uses) validates the WGSL and, as GLSL 4.50, the GLSL snippets;
//! - `glslangValidator` compiles the GLSL as 3.30 and ES 3.00 and the HLSL to SPIR-V, the Unity
//!   and Unreal files inside stand-ins for what those engines declare around them; without it
//!   those tests print one "skipped: <test>: glslangValidator not installed" line on stderr and
//!   pass;
//! - nothing here compiles Godot's shading language: the Godot materials are checked for their
//!   dialect (hints, built-ins, features Godot 3 lacks) and, translated to GLSL ES 3.00 (hints
//!   and defaults dropped, built-ins as globals), compiled by glslang.
//!
//! The LOD cross-fade's dither is checked on the CPU (its two sides partition every 4x4 tile at
//! any fade) and, where a GPU adapter exists, by running the WGSL itself against that model.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use frond_export::shaders::{
    LOD_FADE_SHADERS, SHADERS, SPECTRAL_SHADERS, ShaderFile, blended_variant, blended_variants,
};
use frond_export::vat::VatSpace;
use glam::{Mat3, Quat, Vec3};

/// Every shipped file once, by name.
fn shipped() -> Vec<ShaderFile> {
    let mut seen = BTreeSet::new();
    SHADERS
        .iter()
        .chain(SPECTRAL_SHADERS)
        .chain(LOD_FADE_SHADERS)
        .filter(|(name, _)| seen.insert(*name))
        .copied()
        .collect()
}

/// The source of shipped file `name`.
fn source(name: &str) -> &'static str {
    shipped()
        .into_iter()
        .find(|(n, _)| *n == name)
        .map(|(_, s)| s)
        .unwrap_or_else(|| panic!("{name} is not shipped"))
}

fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

#[test]
fn the_shipped_lists_hold_every_file_of_the_shaders_folder() {
    let on_disk: BTreeSet<String> = std::fs::read_dir(shaders_dir())
        .expect("export/shaders exists")
        .map(|e| {
            e.expect("readable entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let listed: BTreeSet<String> = shipped().iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(
        on_disk, listed,
        "export/shaders/ and frond_export::shaders differ"
    );
    // Each mode ships its own motion files and the whole cross-fade set.
    for set in [SHADERS, SPECTRAL_SHADERS] {
        for fade in LOD_FADE_SHADERS {
            assert!(set.contains(fade), "{} missing from a mode's set", fade.0);
        }
    }
    assert!(SHADERS.iter().all(|(n, _)| !n.contains("spectral")));
    assert!(SPECTRAL_SHADERS.iter().all(|(n, _)| !n.contains("vat")));
}

/// The leading comment lines of a file.
fn header(text: &str) -> String {
    text.lines()
        .take_while(|l| l.starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The engine materials and cross-fade files (the six WGSL/GLSL/HLSL references predate the
/// header convention and name their layout in prose).
fn is_engine_or_fade_file(name: &str) -> bool {
    name.ends_with(".gdshader")
        || name.ends_with(".shader")
        || name.ends_with(".ush")
        || name.ends_with("_unity.hlsl")
        || name.starts_with("frond_lod_")
}

#[test]
fn engine_files_start_with_the_layout_they_read_and_where_the_sidecar_gives_it() {
    let spectral_layout = frond_export::spectral::SPECTRAL_LAYOUT
        .split(':')
        .next()
        .expect("a layout id");
    for (name, text) in shipped()
        .into_iter()
        .filter(|(n, _)| is_engine_or_fade_file(n))
    {
        let head = header(text);
        assert!(!head.is_empty(), "{name} starts without a comment");
        if name.contains("vat") {
            assert!(
                head.contains(&format!("\"{}\"", frond_export::vat::LAYOUT)),
                "{name}"
            );
            assert!(
                head.contains("_vat.json"),
                "{name} does not name the sidecar"
            );
            for key in ["`frames`", "`fps`", "`bound_min`", "`bound_max`", "`hdr`"] {
                assert!(head.contains(key), "{name} does not say where {key} goes");
            }
        } else if name.contains("spectral") {
            assert!(head.contains(&format!("\"{spectral_layout}\"")), "{name}");
            assert!(
                head.contains("_spectral.json"),
                "{name} does not name the sidecar"
            );
            for key in ["`terms`", "`per_row`", "`start_s`", "`period_s`"] {
                assert!(head.contains(key), "{name} does not say where {key} goes");
            }
        } else {
            assert!(head.contains("no texture layout"), "{name}");
            assert!(head.contains("frond LOD cross-fade"), "{name}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// naga

/// Entry points around the WGSL references: (file, harness appended to it).
const WGSL_HARNESSES: &[(&str, &str)] = &[
    (
        "frond_vat_rigid.wgsl",
        r#"
@group(0) @binding(0) var position_tex: texture_2d<f32>;
@group(0) @binding(1) var rotation_tex: texture_2d<f32>;
struct Uniforms { params: VatRigidParams, frame: f32 }
@group(0) @binding(2) var<uniform> u: Uniforms;
struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) piece_uv: vec2<f32>,
    @location(3) pivot_xy: vec2<f32>,
    @location(4) pivot_yz: vec2<f32>,
}
@vertex
fn vs_main(v: VertexIn) -> @builtin(position) vec4<f32> {
    let pivot = vec3<f32>(v.pivot_xy.x, v.pivot_yz.x, v.pivot_yz.y);
    let out = vat_rigid(v.position, v.normal, v.piece_uv, pivot, u.frame, position_tex,
                        rotation_tex, u.params);
    return vec4<f32>(out.position + out.normal, 1.0);
}
"#,
    ),
    (
        "frond_spectral.wgsl",
        r#"
@group(0) @binding(0) var coefficients: texture_2d<f32>;
struct Uniforms { terms: i32, per_row: i32, start_s: f32, period_s: f32, time: f32 }
@group(0) @binding(1) var<uniform> u: Uniforms;
@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv1: vec2<f32>)
    -> @builtin(position) vec4<f32> {
    let i = frond_spectral_index(uv1.x);
    let phase = frond_spectral_phase(u.time, u.start_s, u.period_s);
    let offset = frond_spectral_offset(coefficients, i, u.terms, u.per_row, phase);
    return vec4<f32>(position + offset, 1.0);
}
"#,
    ),
    (
        "frond_lod_dither.wgsl",
        r#"
struct Fade { fade: f32, incoming: u32 }
@group(0) @binding(0) var<uniform> lod: Fade;
@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    frond_lod_dither_discard(lod.fade, frag.xy, lod.incoming != 0u);
    let kept = frond_lod_dither_keep(lod.fade, frag.xy, lod.incoming != 0u);
    return vec4<f32>(frond_lod_dither_threshold(frag.xy), select(0.0, 1.0, kept), 0.0, 1.0);
}
"#,
    ),
];

fn naga_validate(name: &str, module: &naga::Module, text: &str) {
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(module)
    .unwrap_or_else(|e| {
        panic!(
            "{name}: naga validation failed:\n{}",
            e.emit_to_string(text)
        )
    });
}

#[test]
fn wgsl_validates_with_naga() {
    let wgsl: Vec<&str> = shipped()
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    for name in &wgsl {
        assert!(
            WGSL_HARNESSES.iter().any(|(n, _)| n == name),
            "{name} has no harness in this test"
        );
    }
    for (name, harness) in WGSL_HARNESSES {
        let text = format!("{}\n{harness}", source(name));
        let module = naga::front::wgsl::parse_str(&text)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&text)));
        naga_validate(name, &module, &text);
        eprintln!("{name}: naga (WGSL) ok");
    }
}

/// Entry points around the GLSL snippets: (file, stage, declarations and main). The snippets
/// take combined `sampler2D`s, which naga's GLSL front end lacks; `texelFetch` and
/// `textureSize` take the image alone there, so for naga `sampler2D` is defined as
/// `texture2D` and the harness binds images.
const GLSL_HARNESSES: &[(&str, naga::ShaderStage, &str, &str)] = &[
    (
        "frond_vat_rigid.glsl",
        naga::ShaderStage::Vertex,
        // naga (GLSL 4.50, Vulkan style)
        r#"
layout(set = 0, binding = 0) uniform texture2D uPosition;
layout(set = 0, binding = 1) uniform texture2D uRotation;
layout(set = 0, binding = 2) uniform Block { VatRigidParams params; float frame; };
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aPieceUv;
layout(location = 3) in vec2 aPivotXY;
layout(location = 4) in vec2 aPivotYZ;
void main() {
    vec3 p;
    vec3 n;
    vatRigid(aPosition, aNormal, aPieceUv, vec3(aPivotXY.x, aPivotYZ.x, aPivotYZ.y), frame,
             uPosition, uRotation, params, p, n);
    gl_Position = vec4(p + n, 1.0);
}
"#,
        // glslang (GLSL 3.30 / ES 3.00)
        r#"
uniform sampler2D uPosition;
uniform sampler2D uRotation;
uniform VatRigidParams params;
uniform float frame;
in vec3 aPosition;
in vec3 aNormal;
in vec2 aPieceUv;
in vec2 aPivotXY;
in vec2 aPivotYZ;
void main() {
    vec3 p;
    vec3 n;
    vatRigid(aPosition, aNormal, aPieceUv, vec3(aPivotXY.x, aPivotYZ.x, aPivotYZ.y), frame,
             uPosition, uRotation, params, p, n);
    gl_Position = vec4(p + n, 1.0);
}
"#,
    ),
    (
        "frond_spectral.glsl",
        naga::ShaderStage::Vertex,
        r#"
layout(set = 0, binding = 0) uniform texture2D uCoefficients;
layout(set = 0, binding = 1) uniform Block {
    int terms; int perRow; float startS; float periodS; float time;
};
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec2 aUv1;
void main() {
    int i = frond_spectral_index(aUv1.x);
    float u = frond_spectral_phase(time, startS, periodS);
    gl_Position = vec4(aPosition + frond_spectral_offset(uCoefficients, i, terms, perRow, u), 1.0);
}
"#,
        r#"
uniform sampler2D uCoefficients;
uniform int terms;
uniform int perRow;
uniform float startS;
uniform float periodS;
uniform float time;
in vec3 aPosition;
in vec2 aUv1;
void main() {
    int i = frond_spectral_index(aUv1.x);
    float u = frond_spectral_phase(time, startS, periodS);
    gl_Position = vec4(aPosition + frond_spectral_offset(uCoefficients, i, terms, perRow, u), 1.0);
}
"#,
    ),
    (
        "frond_lod_dither.glsl",
        naga::ShaderStage::Fragment,
        r#"
layout(set = 0, binding = 0) uniform Block { float fade; uint incoming; };
layout(location = 0) out vec4 color;
void main() {
    frondLodDitherDiscard(fade, gl_FragCoord.xy, incoming != 0u);
    bool kept = frondLodDitherKeep(fade, gl_FragCoord.xy, incoming != 0u);
    color = vec4(frondLodDitherThreshold(gl_FragCoord.xy), kept ? 1.0 : 0.0, 0.0, 1.0);
}
"#,
        r#"
uniform float fade;
uniform bool incoming;
out vec4 color;
void main() {
    frondLodDitherDiscard(fade, gl_FragCoord.xy, incoming);
    bool kept = frondLodDitherKeep(fade, gl_FragCoord.xy, incoming);
    color = vec4(frondLodDitherThreshold(gl_FragCoord.xy), kept ? 1.0 : 0.0, 0.0, 1.0);
}
"#,
    ),
];

#[test]
fn glsl_validates_with_naga() {
    for (name, _) in shipped().iter().filter(|(n, _)| n.ends_with(".glsl")) {
        assert!(
            GLSL_HARNESSES.iter().any(|(n, ..)| n == name),
            "{name} has no harness in this test"
        );
    }
    for (name, stage, harness, _) in GLSL_HARNESSES {
        let text = format!(
            "#version 450\n#define sampler2D texture2D\n{}\n{harness}",
            source(name)
        );
        let module = naga::front::glsl::Frontend::default()
            .parse(&naga::front::glsl::Options::from(*stage), &text)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&text)));
        naga_validate(name, &module, &text);
        eprintln!("{name}: naga (GLSL 4.50) ok");
    }
}

// ---------------------------------------------------------------------------------------------
// glslang

/// `glslangValidator` on `text` with `args`; None when the tool is not installed, after one
/// `skipped:` line for the running test ([`skip_without_glslang`]): the caller returns.
fn glslang(label: &str, args: &[&str], text: &str) -> Option<()> {
    let stem: String = label
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let stem = format!("frond_shader_compile_{}_{stem}", std::process::id());
    let input = std::env::temp_dir().join(format!("{stem}.src"));
    let spirv = std::env::temp_dir().join(format!("{stem}.spv"));
    std::fs::write(&input, text).expect("the shader written");
    let run = Command::new("glslangValidator")
        .args(args)
        .arg(&input)
        .args(if args.contains(&"-V") {
            vec!["-o".to_string(), spirv.display().to_string()]
        } else {
            Vec::new()
        })
        .output();
    let _ = std::fs::remove_file(&input);
    let _ = std::fs::remove_file(&spirv);
    let output = match run {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            skip_without_glslang();
            return None;
        }
        Err(e) => panic!("{label}: running glslangValidator: {e}"),
    };
    assert!(
        output.status.success(),
        "{label}: glslangValidator {} failed:\n{}{}\n--- source ---\n{}",
        args.join(" "),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
        numbered(text)
    );
    eprintln!("{label}: glslangValidator {} ok", args.join(" "));
    Some(())
}

/// Says that the running test skips for want of glslang, in the form of the workspace's other
/// skip lines (`skipped: <test binary>::<test>: <tool> not installed (<how>)`; libtest names each
/// test's thread after the test), straight to stderr past libtest's output capture so that a
/// plain `cargo test` shows it.
fn skip_without_glslang() {
    use std::io::Write;
    let line = format!(
        "skipped: {}::{}: glslangValidator not installed (apt-get install glslang-tools, as bash \
         .ci/run does)\n",
        env!("CARGO_CRATE_NAME"),
        std::thread::current().name().unwrap_or("main")
    );
    // Nothing sensible to do when stderr is gone; the test still skips.
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

/// `text` with line numbers, for compiler messages.
fn numbered(text: &str) -> String {
    text.lines()
        .enumerate()
        .map(|(i, l)| format!("{:4} {l}\n", i + 1))
        .collect()
}

/// The GLSL ES 3.00 preamble (default precisions a vertex or fragment shader needs).
const ES_PREAMBLE: &str =
    "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\n";

#[test]
fn glsl_compiles_with_glslang_as_330_and_es_300() {
    for (name, stage, _, harness) in GLSL_HARNESSES {
        let stage = match stage {
            naga::ShaderStage::Vertex => "vert",
            _ => "frag",
        };
        let body = format!("{}\n{harness}", source(name));
        for (version, preamble) in [("330", "#version 330\n"), ("300es", ES_PREAMBLE)] {
            let text = format!("{preamble}{body}");
            if glslang(&format!("{name} {version}"), &["-S", stage], &text).is_none() {
                return;
            }
        }
    }
}

/// Entry points around the HLSL files: (file, stage, texts before it, text after it).
const HLSL_HARNESSES: &[(&str, &str, &[&str], &str)] = &[
    (
        "frond_vat_rigid.hlsl",
        "vert",
        &[],
        r#"
Texture2D<float4> gPosition : register(t0);
Texture2D<float4> gRotation : register(t1);
cbuffer Params : register(b0) { VatRigidParams gParams; float gFrame; };
struct VertexIn {
    float3 position : POSITION; float3 normal : NORMAL;
    float2 pieceUv : TEXCOORD1; float2 pivotXY : TEXCOORD2; float2 pivotYZ : TEXCOORD3;
};
float4 main(VertexIn v) : SV_Position {
    float3 p, n;
    VatRigid(v.position, v.normal, v.pieceUv, float3(v.pivotXY.x, v.pivotYZ.x, v.pivotYZ.y),
             gFrame, gPosition, gRotation, gParams, p, n);
    return float4(p + n, 1.0);
}
"#,
    ),
    (
        "frond_spectral.hlsl",
        "vert",
        &[],
        r#"
Texture2D<float4> gCoefficients : register(t0);
cbuffer Params : register(b0) {
    int gTerms; int gPerRow; float gStart; float gPeriod; float gTime;
};
float4 main(float3 position : POSITION, float2 uv1 : TEXCOORD1) : SV_Position {
    int i = frond_spectral_index(uv1.x);
    float u = frond_spectral_phase(gTime, gStart, gPeriod);
    return float4(position + frond_spectral_offset(gCoefficients, i, gTerms, gPerRow, u), 1.0);
}
"#,
    ),
    (
        "frond_lod_dither.hlsl",
        "frag",
        &[],
        r#"
cbuffer Fade : register(b0) { float gFade; float gIncoming; };
float4 main(float4 position : SV_Position) : SV_Target {
    FrondLodDitherClip(gFade, position.xy, gIncoming > 0.5);
    float keep;
    FrondLodDither_float(gFade, position.xy, gIncoming, keep);
    half keepHalf;
    FrondLodDither_half((half)gFade, (half2)position.xy, (half)gIncoming, keepHalf);
    return float4(keep, keepHalf, FrondLodDitherThreshold(position.xy), 1.0);
}
"#,
    ),
    (
        "frond_vat_rigid_unity.hlsl",
        "vert",
        &[UNITY_STAND_IN],
        r#"
Texture2D<float4> gPosition : register(t0);
Texture2D<float4> gRotation : register(t1);
SamplerState gSampler : register(s0);
cbuffer Params : register(b0) {
    float4 gTexelSize; float3 gBoundMin; float gFrames; float3 gBoundMax; float gFps;
    float gHdr; float gTime; float gClipStart; float gEngineSpace;
};
struct VertexIn {
    float3 position : POSITION; float3 normal : NORMAL;
    float2 uv1 : TEXCOORD1; float2 uv2 : TEXCOORD2; float2 uv3 : TEXCOORD3;
};
float4 main(VertexIn v) : SV_Position {
    UnityTexture2D positionTex = UnityStandIn(gPosition, gSampler, gTexelSize);
    UnityTexture2D rotationTex = UnityStandIn(gRotation, gSampler, gTexelSize);
    float3 p, n;
    FrondVatRigid_float(v.position, v.normal, v.uv1, v.uv2, v.uv3, gTime, positionTex, rotationTex,
                        gBoundMin, gBoundMax, gFrames, gFps, gHdr, gClipStart, gEngineSpace,
                        p, n);
    half3 ph, nh;
    FrondVatRigid_half((half3)v.position, (half3)v.normal, (half2)v.uv1, (half2)v.uv2,
                       (half2)v.uv3, (half)gTime, positionTex, rotationTex, (half3)gBoundMin,
                       (half3)gBoundMax, (half)gFrames, (half)gFps, (half)gHdr, (half)gClipStart,
                       (half)gEngineSpace, ph, nh);
    return float4(p + n + ph + nh, 1.0);
}
"#,
    ),
    (
        "frond_spectral_unity.hlsl",
        "vert",
        &[UNITY_STAND_IN],
        r#"
Texture2D<float4> gCoefficients : register(t0);
SamplerState gSampler : register(s0);
cbuffer Params : register(b0) {
    float4 gTexelSize; float gTerms; float gPerRow; float gStart; float gPeriod; float gTime;
};
float4 main(float3 position : POSITION, float2 uv1 : TEXCOORD1) : SV_Position {
    UnityTexture2D coefficients = UnityStandIn(gCoefficients, gSampler, gTexelSize);
    float3 p;
    FrondSpectral_float(position, uv1, gTime, coefficients, gTerms, gPerRow, gStart, gPeriod, p);
    half3 ph;
    FrondSpectral_half((half3)position, (half2)uv1, (half)gTime, coefficients, (half)gTerms,
                       (half)gPerRow, (half)gStart, (half)gPeriod, ph);
    return float4(p + ph, 1.0);
}
"#,
    ),
    (
        "frond_vat_rigid_unreal.ush",
        "vert",
        &[
            UNREAL_STAND_IN,
            r#"
float3 CustomExpression0(FMaterialVertexParameters Parameters, Texture2D PositionTex,
    SamplerState PositionTexSampler, Texture2D RotationTex, SamplerState RotationTexSampler,
    float2 PieceUV, float2 PivotXY, float2 PivotYZ, float3 LocalPosition, float3 LocalNormal,
    float Time, float ClipStart, float Frames, float Fps, float Hdr, float3 BoundMin,
    float3 BoundMax, float UnitScale, float EngineSpace, inout float3 AnimatedNormal)
{
"#,
        ],
        r#"
}
Texture2D gPosition : register(t0);
Texture2D gRotation : register(t1);
SamplerState gSampler : register(s0);
cbuffer Params : register(b0) {
    float3x3 gLocalToWorld; float3 gBoundMin; float gFrames; float3 gBoundMax; float gFps;
    float gHdr; float gTime; float gEngineSpace;
};
struct VertexIn {
    float3 position : POSITION; float3 normal : NORMAL;
    float2 uv1 : TEXCOORD1; float2 uv2 : TEXCOORD2; float2 uv3 : TEXCOORD3;
};
float4 main(VertexIn v) : SV_Position {
    FMaterialVertexParameters parameters;
    parameters.LocalToWorld = gLocalToWorld;
    float3 normal = v.normal;
    float3 offset = CustomExpression0(parameters, gPosition, gSampler, gRotation, gSampler, v.uv1,
        v.uv2, v.uv3, v.position, v.normal, gTime, 0.0, gFrames, gFps, gHdr, gBoundMin,
        gBoundMax, 100.0, gEngineSpace, normal);
    return float4(v.position + offset + normal, 1.0);
}
"#,
    ),
    (
        "frond_spectral_unreal.ush",
        "vert",
        &[
            UNREAL_STAND_IN,
            r#"
float3 CustomExpression0(FMaterialVertexParameters Parameters, Texture2D Coefficients,
    SamplerState CoefficientsSampler, float2 IndexUV, float Time, float Terms, float PerRow,
    float StartS, float PeriodS, float UnitScale)
{
"#,
        ],
        r#"
}
Texture2D gCoefficients : register(t0);
SamplerState gSampler : register(s0);
cbuffer Params : register(b0) {
    float3x3 gLocalToWorld; float gTerms; float gPerRow; float gStart; float gPeriod; float gTime;
};
float4 main(float3 position : POSITION, float2 uv1 : TEXCOORD1) : SV_Position {
    FMaterialVertexParameters parameters;
    parameters.LocalToWorld = gLocalToWorld;
    return float4(position + CustomExpression0(parameters, gCoefficients, gSampler, uv1, gTime,
        gTerms, gPerRow, gStart, gPeriod, 100.0), 1.0);
}
"#,
    ),
];

/// What Unity's SRP Core declares for a Shader Graph custom function (Texture.hlsl's
/// `UnityTexture2D`, the D3D `LOAD_TEXTURE2D_LOD`), reduced to what the files use.
const UNITY_STAND_IN: &str = r#"
struct UnityTexture2D
{
    Texture2D<float4> tex;
    SamplerState samplerstate;
    float4 texelSize;
    float4 scaleTranslate;
};
#define LOAD_TEXTURE2D_LOD(textureName, unCoord2, lod) textureName.Load(int3(unCoord2, lod))
UnityTexture2D UnityStandIn(Texture2D<float4> tex, SamplerState s, float4 texelSize)
{
    UnityTexture2D result;
    result.tex = tex;
    result.samplerstate = s;
    result.texelSize = texelSize;
    result.scaleTranslate = float4(1.0, 1.0, 0.0, 0.0);
    return result;
}
"#;

/// What Unreal's material template gives a Custom node's code: `Parameters` and
/// `TransformLocalVectorToWorld`, reduced to a local-to-world matrix. The node's code becomes
/// the body of a `CustomExpression` function whose parameters are its inputs (a Texture Object
/// input brings `<Name>Sampler` along) and whose additional outputs are `inout`.
const UNREAL_STAND_IN: &str = r#"
struct FMaterialVertexParameters { float3x3 LocalToWorld; };
float3 TransformLocalVectorToWorld(FMaterialVertexParameters Parameters, float3 InLocalVector)
{
    return mul(Parameters.LocalToWorld, InLocalVector);
}
"#;

#[test]
fn hlsl_unity_and_unreal_files_compile_with_glslang() {
    for (name, _) in shipped()
        .iter()
        .filter(|(n, _)| n.ends_with(".hlsl") || n.ends_with(".ush"))
    {
        assert!(
            HLSL_HARNESSES.iter().any(|(n, ..)| n == name),
            "{name} has no harness in this test"
        );
    }
    for (name, stage, before, after) in HLSL_HARNESSES {
        let text = format!("{}\n{}\n{after}", before.concat(), source(name));
        let args = ["-D", "-e", "main", "-S", stage, "-V"];
        if glslang(name, &args, &text).is_none() {
            return;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Godot

#[derive(Clone, Copy, Debug, PartialEq)]
enum Godot {
    V3,
    V4,
}

/// Every shipped Godot material and its blended variant
/// ([`frond_export::shaders::blended_variant`]), with its dialect.
fn godot_files() -> Vec<((String, String), Godot)> {
    let shipped = shipped();
    let mut files: Vec<(String, String)> = (shipped.iter())
        .map(|&(n, t)| (n.to_string(), t.to_string()))
        .collect();
    files.extend(blended_variants(&shipped));
    files
        .into_iter()
        .filter_map(|f| {
            if f.0.ends_with(".gdshader") {
                Some((f, Godot::V4))
            } else if f.0.ends_with(".shader") {
                Some((f, Godot::V3))
            } else {
                None
            }
        })
        .collect()
}

/// The uniform hints a dialect accepts (of those these materials need).
fn godot_hint_allowed(version: Godot, hint: &str) -> bool {
    let hint = hint.trim();
    if hint.starts_with("hint_range(") {
        return true;
    }
    match version {
        Godot::V3 => matches!(
            hint,
            "hint_albedo" | "hint_color" | "hint_black" | "hint_white"
        ),
        Godot::V4 => matches!(
            hint,
            "source_color"
                | "filter_nearest"
                | "filter_linear"
                | "filter_linear_mipmap"
                | "repeat_disable"
                | "repeat_enable"
                | "hint_default_black"
                | "hint_default_white"
        ),
    }
}

/// The text after `uniform <type> <name>` up to `=` or `;`, when there is a `:`.
fn godot_hints(line: &str) -> Option<&str> {
    let rest = line.split_once(':')?.1;
    Some(rest.split(['=', ';']).next().unwrap_or(""))
}

/// Splits a hint list at the commas outside parentheses.
fn split_hints(hints: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in hints.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&hints[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&hints[start..]);
    out
}

#[test]
fn godot_materials_keep_to_their_dialect() {
    let files = godot_files();
    assert_eq!(
        files.len(),
        12,
        "VAT, spectral and cross-fade, Godot 3 and 4, alpha-tested and blended"
    );
    for ((name, text), version) in files {
        let code: Vec<&str> = text
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect();
        let code_text = code.join("\n");
        assert!(code_text.contains("shader_type spatial;"), "{name}");
        for line in code.iter().map(|l| l.trim()) {
            let uniform = line
                .strip_prefix("instance uniform ")
                .or(line.strip_prefix("uniform "));
            if let (Some(decl), Some(hints)) = (uniform, godot_hints(line)) {
                for hint in split_hints(hints) {
                    assert!(
                        godot_hint_allowed(version, hint),
                        "{name}: hint `{}` is not Godot {version:?}'s ({decl})",
                        hint.trim()
                    );
                }
            }
        }
        if version == Godot::V3 {
            // Godot 3 has no per-instance uniforms, CUSTOM0-3, global constants or includes;
            // the ternary operator is avoided too (not in every 3.x release).
            for absent in ["instance uniform", "CUSTOM0", "#include", " ? "] {
                assert!(!code_text.contains(absent), "{name} uses `{absent}`");
            }
            assert!(
                !code.iter().any(|l| l.starts_with("const ")),
                "{name} declares a global constant"
            );
        }
    }
}

/// A Godot spatial shader as GLSL ES 3.00 for glslang: `shader_type` / `render_mode` dropped,
/// uniform hints and defaults dropped (ES has no uniform initializers), `instance uniform` made
/// plain, `vertex()` / `fragment()` renamed and called from `main`, the built-ins the dialect
/// has declared as globals (TIME read-only).
fn godot_to_glsl_es(text: &str, version: Godot) -> String {
    let mut body = String::new();
    for line in text.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("shader_type") || trimmed.starts_with("render_mode") {
            continue;
        }
        let line = line.strip_prefix("instance ").unwrap_or(line);
        let line = if line.starts_with("uniform ") {
            let decl = line.split([':', '=', ';']).next().unwrap_or(line);
            format!("{};", decl.trim_end())
        } else {
            line.replace("void vertex()", "void godot_vertex()")
                .replace("void fragment()", "void godot_fragment()")
        };
        body.push_str(&line);
        body.push('\n');
    }
    let custom = match version {
        Godot::V4 => "vec4 CUSTOM0;\n",
        Godot::V3 => "",
    };
    let vertex = if body.contains("void godot_vertex()") {
        "    godot_vertex();\n"
    } else {
        ""
    };
    format!(
        "{ES_PREAMBLE}vec3 VERTEX;\nvec3 NORMAL;\nvec3 TANGENT;\nvec3 BINORMAL;\nvec2 UV;\n\
         vec2 UV2;\nvec4 COLOR;\n{custom}vec4 FRAGCOORD;\nvec3 ALBEDO;\nfloat ALPHA;\nfloat METALLIC;\n\
         float ROUGHNESS;\nuniform float TIME;\nout vec4 godot_out;\n{body}\n\
         void main() {{\n    FRAGCOORD = gl_FragCoord;\n{vertex}    godot_fragment();\n    \
         godot_out = vec4(VERTEX + NORMAL + TANGENT + BINORMAL + ALBEDO,\n        \
         METALLIC + ROUGHNESS);\n}}\n"
    )
}

#[test]
fn godot_materials_compile_as_glsl_es_with_glslang() {
    eprintln!("Godot materials: no Godot compiler here; checking a GLSL ES 3.00 translation");
    for ((name, text), version) in godot_files() {
        let glsl = godot_to_glsl_es(&text, version);
        if glslang(&format!("{name} as GLSL ES"), &["-S", "frag"], &glsl).is_none() {
            return;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The LOD cross-fade dither

/// The expression every copy of the dither computes its Bayer index with.
const BAYER_EXPRESSION: &str =
    "8.0 * abs(lo.x - lo.y) + 4.0 * lo.y + 2.0 * abs(hi.x - hi.y) + hi.y";

#[test]
fn every_copy_of_the_dither_is_the_same_function() {
    let godot_copy = |text: &str| -> String {
        let start = text
            .find("float frond_lod_dither_threshold(")
            .expect("the threshold function");
        let end = text[start..]
            .find("\treturn to_incoming == incoming;\n}")
            .expect("the keep function")
            + start;
        text[start..end].to_string()
    };
    let reference = godot_copy(source("frond_lod_fade.gdshader"));
    let mut copies = 0;
    for (name, text) in shipped() {
        let has_dither =
            text.contains("lod_dither_threshold") || text.contains("LodDitherThreshold");
        if !has_dither {
            continue;
        }
        copies += 1;
        assert!(
            text.contains(BAYER_EXPRESSION),
            "{name} computes another index"
        );
        assert!(
            text.contains("(b + 0.5) / 16.0"),
            "{name} uses other thresholds"
        );
        if name.ends_with(".gdshader") || name.ends_with(".shader") {
            assert_eq!(
                godot_copy(text),
                reference,
                "{name}'s dither differs from frond_lod_fade.gdshader's"
            );
        }
    }
    // WGSL, GLSL, HLSL, and six Godot materials.
    assert_eq!(copies, 9);
}

/// The dither threshold as the shaders compute it (f32, same operations).
fn threshold(x: f32, y: f32) -> f32 {
    let fx = x.floor();
    let fy = y.floor();
    let p = [fx - 4.0 * (fx / 4.0).floor(), fy - 4.0 * (fy / 4.0).floor()];
    let lo = [
        p[0] - 2.0 * (p[0] / 2.0).floor(),
        p[1] - 2.0 * (p[1] / 2.0).floor(),
    ];
    let hi = [(p[0] / 2.0).floor(), (p[1] / 2.0).floor()];
    let b = 8.0 * (lo[0] - lo[1]).abs() + 4.0 * lo[1] + 2.0 * (hi[0] - hi[1]).abs() + hi[1];
    (b + 0.5) / 16.0
}

fn keep(fade: f32, x: f32, y: f32, incoming: bool) -> bool {
    (threshold(x, y) < fade) == incoming
}

/// The classic 4x4 Bayer matrix, row y, column x.
const BAYER: [[u32; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

const FADES: [f32; 12] = [
    0.0,
    0.01,
    1.0 / 32.0,
    0.1,
    0.25,
    0.3,
    0.5,
    0.5001,
    0.73,
    0.99,
    1.0,
    1.5,
];

#[test]
fn dither_thresholds_are_the_bayer_matrix() {
    // Pixel centres, other origins and far-off pixels give the same tile.
    for (ox, oy) in [
        (0.5, 0.5),
        (0.0, 0.0),
        (0.99, 0.25),
        (4096.5, 2160.5),
        (16380.5, 8.5),
    ] {
        for (y, row) in BAYER.iter().enumerate() {
            for (x, &b) in row.iter().enumerate() {
                let t = threshold(ox + x as f32, oy + y as f32);
                assert_eq!(
                    t,
                    (b as f32 + 0.5) / 16.0,
                    "pixel ({x}, {y}) at origin ({ox}, {oy})"
                );
            }
        }
    }
}

#[test]
fn dither_sides_partition_every_tile_at_any_fade() {
    let mut previous: Option<Vec<bool>> = None;
    for &fade in &FADES {
        let mut incoming_set = Vec::new();
        for y in 0..16 {
            for x in 0..16 {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let outgoing = keep(fade, px, py, false);
                let incoming = keep(fade, px, py, true);
                assert!(
                    outgoing != incoming,
                    "pixel ({x}, {y}) at fade {fade}: drawn by both or neither"
                );
                incoming_set.push(incoming);
            }
        }
        // Each 4x4 tile gives the incoming LOD the pixels whose (b + 0.5) / 16 < fade.
        let per_tile = (0..16).filter(|&b| (b as f32 + 0.5) / 16.0 < fade).count();
        let total = incoming_set.iter().filter(|&&i| i).count();
        assert_eq!(total, 16 * per_tile, "fade {fade}");
        if fade <= 0.0 {
            assert_eq!(total, 0);
        }
        if fade >= 1.0 {
            assert_eq!(total, 256);
        }
        // Monotone: a pixel the incoming LOD took stays taken as the fade grows.
        if let Some(prev) = &previous {
            for (i, (&was, &is)) in prev.iter().zip(&incoming_set).enumerate() {
                assert!(
                    !was || is,
                    "pixel {i} goes back to the outgoing LOD at fade {fade}"
                );
            }
        }
        previous = Some(incoming_set);
    }
}

/// Runs the WGSL dither on a GPU adapter (llvmpipe qualifies) for every pixel of a 16x16 block
/// at several fades and compares with the CPU model; skipped without an adapter.
#[test]
fn wgsl_dither_matches_the_cpu_model_on_a_gpu() {
    let Some(gpu) = common::open_compute("frond_lod_dither.wgsl") else {
        return;
    };
    // The harness needs a texture at binding 0; the answer adds 0 x a texel so it stays bound.
    let harness = r#"
@group(0) @binding(0) var unused: texture_2d<f32>;
struct Query { xy: vec2<f32>, fade: f32, incoming: f32 }
struct Answer { threshold: f32, keep: f32 }
@group(0) @binding(1) var<storage, read> queries: array<Query>;
@group(0) @binding(2) var<storage, read_write> answers: array<Answer>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    let zero = 0.0 * textureLoad(unused, vec2<i32>(0, 0), 0).x;
    let kept = frond_lod_dither_keep(q.fade, q.xy, q.incoming > 0.5);
    answers[id.x] = Answer(frond_lod_dither_threshold(q.xy) + zero, select(0.0, 1.0, kept));
}
"#;
    let text = format!("{}\n{harness}", source("frond_lod_dither.wgsl"));
    let mut queries: Vec<[f32; 4]> = Vec::new();
    for &fade in &FADES {
        for incoming in [0.0, 1.0] {
            for y in 0..16 {
                for x in 0..16 {
                    queries.push([x as f32 + 0.5, 2160.5 + y as f32, fade, incoming]);
                }
            }
        }
    }
    let answers = common::run_compute(
        &gpu,
        &text,
        &[0.0; 4],
        1,
        1,
        bytemuck::cast_slice(&queries),
        queries.len() as u32,
        (queries.len() * 8) as u64,
    );
    let answers: &[[f32; 2]] = bytemuck::cast_slice(&answers);
    for (q, a) in queries.iter().zip(answers) {
        let want_keep = keep(q[2], q[0], q[1], q[3] > 0.5);
        assert_eq!(a[0], threshold(q[0], q[1]), "threshold at {q:?}");
        assert_eq!(a[1] > 0.5, want_keep, "keep at {q:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// The engine conversions the Unity and Unreal files apply to decoded VAT data

fn rotation(q: Quat) -> Mat3 {
    Mat3::from_quat(q)
}

#[test]
fn engine_axis_conversions_turn_quaternions_like_the_imported_mesh() {
    // Unity (glTFast, UnityGLTF): x negated; the files use q' = (x, -y, -z, w).
    let unity = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
    // Unreal's glTF importer: (x, y, z) -> (x, z, y); the file uses q' = (-x, -z, -y, w).
    let unreal = Mat3::from_cols(Vec3::X, Vec3::Z, Vec3::Y);
    for (i, axis) in [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.3, -0.8, 0.5),
        Vec3::new(-0.2, 0.4, 0.9),
        Vec3::new(0.0, 1.0, -1.0),
    ]
    .into_iter()
    .enumerate()
    {
        let q = Quat::from_axis_angle(axis.normalize(), 0.4 + i as f32);
        // What the files do, and what `--vat-space` bakes (the same conversion).
        let unity_q = Quat::from_xyzw(q.x, -q.y, -q.z, q.w);
        let unreal_q = Quat::from_xyzw(-q.x, -q.z, -q.y, q.w);
        assert_eq!(VatSpace::Unity.rotation(q), unity_q);
        assert_eq!(VatSpace::Unreal.rotation(q), unreal_q);
        for (name, m, converted, space) in [
            ("Unity", unity, unity_q, VatSpace::Unity),
            ("Unreal", unreal, unreal_q, VatSpace::Unreal),
        ] {
            let want = m * rotation(q) * m.inverse();
            let got = rotation(converted);
            assert!(
                want.abs_diff_eq(got, 1e-5),
                "{name}: {want:?} vs {got:?} for {q:?}"
            );
            // And a rest vertex about the pivot lands where the converted pose puts it.
            let (rest, pivot, p) = (
                Vec3::new(0.4, 1.2, -0.3),
                Vec3::new(0.1, 1.0, 0.2),
                Vec3::new(0.5, 1.5, -0.1),
            );
            let gltf = q * (rest - pivot) + p;
            let engine = converted * (m * rest - m * pivot) + m * p;
            assert!((m * gltf).abs_diff_eq(engine, 1e-5), "{name}");
            // The baked data: the same pose, with Unreal's centimetres.
            let scale = if space == VatSpace::Unreal {
                100.0
            } else {
                1.0
            };
            let baked = VatSpace::rotation(space, q) * (space.point(rest) - space.point(pivot))
                + space.point(p);
            assert!((m * gltf * scale).abs_diff_eq(baked, 1e-3), "{name} baked");
            assert!(space.point_to_gltf(baked).abs_diff_eq(gltf, 1e-5));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Blended variants of the Godot materials

#[test]
fn every_godot_material_has_a_blended_variant_that_writes_alpha_and_no_depth() {
    let shipped = shipped();
    for &(name, text) in &shipped {
        let godot = name.ends_with(".gdshader") || name.ends_with(".shader");
        let variant = blended_variant((name, text));
        assert_eq!(variant.is_some(), godot, "{name}");
        let Some((blend_name, blend)) = variant else {
            continue;
        };
        assert!(blend_name.contains("_blend"), "{blend_name}");
        assert!(
            !shipped.iter().any(|(n, _)| *n == blend_name),
            "{blend_name} is a name of its own"
        );
        let code: String = (blend.lines())
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(
            !code.contains("alpha_scissor"),
            "{blend_name} tests no alpha"
        );
        assert!(
            code.contains("ALPHA = albedo.a;"),
            "{blend_name} writes its alpha"
        );
        assert!(
            code.contains("render_mode cull_disabled, depth_draw_never;"),
            "{blend_name} writes no depth"
        );
        // The cross-fade and the motion are the alpha-tested file's, line for line.
        let kept = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| !l.starts_with("//") && !l.contains("alpha_scissor"))
                .filter(|l| !l.contains("render_mode") && !l.contains("ALPHA ="))
                .filter(|l| !matches!(l.trim(), "discard;" | "}"))
                .map(str::to_string)
                .collect()
        };
        assert_eq!(
            kept(text),
            kept(&blend),
            "{blend_name} keeps the rest of {name}"
        );
    }
}
