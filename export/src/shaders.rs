//! The reference vertex-animation shaders, shipped next to VAT output.

/// (file name, source) of every reference shader.
pub const SHADERS: &[(&str, &str)] = &[
    (
        "frond_vat_rigid.wgsl",
        include_str!("../shaders/frond_vat_rigid.wgsl"),
    ),
    (
        "frond_vat_rigid.glsl",
        include_str!("../shaders/frond_vat_rigid.glsl"),
    ),
    (
        "frond_vat_rigid.hlsl",
        include_str!("../shaders/frond_vat_rigid.hlsl"),
    ),
];

/// (file name, source) of the spectral-motion reference shaders (`--animation spectral`).
pub const SPECTRAL_SHADERS: &[(&str, &str)] = &[
    (
        "frond_spectral.wgsl",
        include_str!("../shaders/frond_spectral.wgsl"),
    ),
    (
        "frond_spectral.glsl",
        include_str!("../shaders/frond_spectral.glsl"),
    ),
    (
        "frond_spectral.hlsl",
        include_str!("../shaders/frond_spectral.hlsl"),
    ),
];
