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
