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
