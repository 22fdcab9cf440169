//! The shaders and engine materials shipped next to a chain's animation textures (under
//! `shaders/`): the tested WGSL references, their GLSL and HLSL twins, engine materials (Godot 4
//! `.gdshader`, Godot 3 `.shader`, Unity Shader Graph custom functions, Unreal Custom-node
//! bodies) and the dithered LOD cross-fade. `export/tests/shader_compile.rs` compiles every one
//! it has a compiler for and checks that this module lists every file in `export/shaders/`.

/// A shipped file: (file name, source).
pub type ShaderFile = (&'static str, &'static str);

macro_rules! shader {
    ($name:literal) => {
        ($name, include_str!(concat!("../shaders/", $name)))
    };
}

const VAT_WGSL: ShaderFile = shader!("frond_vat_rigid.wgsl");
const VAT_GLSL: ShaderFile = shader!("frond_vat_rigid.glsl");
const VAT_HLSL: ShaderFile = shader!("frond_vat_rigid.hlsl");
const VAT_GODOT4: ShaderFile = shader!("frond_vat_rigid.gdshader");
const VAT_GODOT3: ShaderFile = shader!("frond_vat_rigid_godot3.shader");
const VAT_UNITY: ShaderFile = shader!("frond_vat_rigid_unity.hlsl");
const VAT_UNREAL: ShaderFile = shader!("frond_vat_rigid_unreal.ush");

const SPECTRAL_WGSL: ShaderFile = shader!("frond_spectral.wgsl");
const SPECTRAL_GLSL: ShaderFile = shader!("frond_spectral.glsl");
const SPECTRAL_HLSL: ShaderFile = shader!("frond_spectral.hlsl");
const SPECTRAL_GODOT4: ShaderFile = shader!("frond_spectral.gdshader");
const SPECTRAL_GODOT3: ShaderFile = shader!("frond_spectral_godot3.shader");
const SPECTRAL_UNITY: ShaderFile = shader!("frond_spectral_unity.hlsl");
const SPECTRAL_UNREAL: ShaderFile = shader!("frond_spectral_unreal.ush");

const DITHER_WGSL: ShaderFile = shader!("frond_lod_dither.wgsl");
const DITHER_GLSL: ShaderFile = shader!("frond_lod_dither.glsl");
const DITHER_HLSL: ShaderFile = shader!("frond_lod_dither.hlsl");
const FADE_GODOT4: ShaderFile = shader!("frond_lod_fade.gdshader");
const FADE_GODOT3: ShaderFile = shader!("frond_lod_fade_godot3.shader");

/// The dithered LOD cross-fade: reference functions (WGSL, GLSL, HLSL, which is also a Unity
/// Shader Graph custom function) and Godot materials for LODs without motion textures. The VAT
/// and spectral sets include these too.
pub const LOD_FADE_SHADERS: &[ShaderFile] = &[
    DITHER_WGSL,
    DITHER_GLSL,
    DITHER_HLSL,
    FADE_GODOT4,
    FADE_GODOT3,
];

/// Everything shipped with VAT output (`--animation vat`): the rigid-VAT references and engine
/// materials, then the LOD cross-fade.
pub const SHADERS: &[ShaderFile] = &[
    VAT_WGSL,
    VAT_GLSL,
    VAT_HLSL,
    VAT_GODOT4,
    VAT_GODOT3,
    VAT_UNITY,
    VAT_UNREAL,
    DITHER_WGSL,
    DITHER_GLSL,
    DITHER_HLSL,
    FADE_GODOT4,
    FADE_GODOT3,
];

/// Everything shipped with spectral textures (`--animation spectral`): the spectral-motion
/// references and engine materials, then the LOD cross-fade.
pub const SPECTRAL_SHADERS: &[ShaderFile] = &[
    SPECTRAL_WGSL,
    SPECTRAL_GLSL,
    SPECTRAL_HLSL,
    SPECTRAL_GODOT4,
    SPECTRAL_GODOT3,
    SPECTRAL_UNITY,
    SPECTRAL_UNREAL,
    DITHER_WGSL,
    DITHER_GLSL,
    DITHER_HLSL,
    FADE_GODOT4,
    FADE_GODOT3,
];

/// Where a Godot material of [`SHADERS`], [`SPECTRAL_SHADERS`] or [`LOD_FADE_SHADERS`] tests its
/// alpha (the glTF `MASK` cutoff), removed from its blended variant.
const ALPHA_SCISSOR_TEST: &str = "\tif (albedo.a < alpha_scissor) {\n\t\tdiscard;\n\t}\n";
/// The cutoff's uniform line's start, removed with it.
const ALPHA_SCISSOR_UNIFORM: &str = "uniform float alpha_scissor";
/// The render modes every shipped Godot material sets.
const RENDER_MODE: &str = "render_mode cull_disabled;";
/// Where the fragment stage writes the albedo.
const ALBEDO_WRITE: &str = "\tALBEDO = albedo.rgb;\n";

/// A Godot material of the shipped sets (`.gdshader` for Godot 4, `_godot3.shader` for Godot 3)
/// turned into its blended variant, for a far end drawn as glTF `BLEND`
/// (docs/engines.md, "Blended far ends"): the texel's alpha, its covered fraction, is written to
/// `ALPHA` instead of being tested (Godot then draws the material in its transparent pass,
/// blending `α·src + (1 − α)·dst`), and no depth is written, so overlapping billboards compose
/// as `1 − Π(1 − αᵢ)` in any order. The dithered cross-fade stays as it is. Named as the file
/// with `_blend` before the dialect's suffix (`frond_lod_fade_blend.gdshader`,
/// `frond_lod_fade_blend_godot3.shader`); `None` for any other file, or a Godot file whose
/// alpha test is not written as the shipped ones write it.
pub fn blended_variant((name, text): ShaderFile) -> Option<(String, String)> {
    let stem = name
        .strip_suffix("_godot3.shader")
        .map(|s| (s, "_godot3.shader"))
        .or_else(|| name.strip_suffix(".gdshader").map(|s| (s, ".gdshader")));
    let (stem, suffix) = stem?;
    let uniform_start = text.find(ALPHA_SCISSOR_UNIFORM)?;
    let uniform_end = uniform_start + text[uniform_start..].find('\n')? + 1;
    let without_uniform = format!("{}{}", &text[..uniform_start], &text[uniform_end..]);
    if !(without_uniform.contains(ALPHA_SCISSOR_TEST)
        && without_uniform.contains(RENDER_MODE)
        && without_uniform.contains(ALBEDO_WRITE))
    {
        return None;
    }
    let body = without_uniform
        .replacen(ALPHA_SCISSOR_TEST, "", 1)
        .replacen(
            RENDER_MODE,
            "render_mode cull_disabled, depth_draw_never;",
            1,
        )
        .replacen(
            ALBEDO_WRITE,
            "\tALBEDO = albedo.rgb;\n\tALPHA = albedo.a;\n",
            1,
        );
    let header = format!(
        "// Blended variant of {name}, written by frond for a far end drawn as glTF BLEND: each\n\
         // texel's alpha is the covered fraction of the leaves it holds, written to ALPHA (no\n\
         // alpha scissor) with no depth written, so overlapping billboards compose as\n\
         // 1 - prod(1 - alpha) in any order. Everything else is as in {name}.\n"
    );
    Some((format!("{stem}_blend{suffix}"), header + &body))
}

/// The blended variants ([`blended_variant`]) of the Godot materials in `set`, in its order.
pub fn blended_variants(set: &[ShaderFile]) -> Vec<(String, String)> {
    set.iter().filter_map(|&f| blended_variant(f)).collect()
}
