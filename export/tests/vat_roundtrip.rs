//! Rigid vertex animation textures: encode → decode within each format's precision, the sidecar
//! through JSON, the WGSL reference shader evaluated on a real adapter, and errors on bad input.

mod common;

use frond_export::vat::{
    RigidFrame, RigidPiece, VatError, VatFormat, VatOptions, VatSidecar, VatTextures, decode_rigid,
    decode_turns_per_frame, encode_rigid, encode_rigid_with, sample_frame,
};
use glam::{DQuat, Quat, Vec3};

const PIECES: usize = 50;
const FRAMES: usize = 64;
/// Billboard corners relative to their pivot (a 0.8 × 0.6 card, slightly off its plane).
const CORNERS: [Vec3; 4] = [
    Vec3::new(-0.4, -0.3, 0.05),
    Vec3::new(0.4, -0.3, 0.05),
    Vec3::new(0.4, 0.3, -0.05),
    Vec3::new(-0.4, 0.3, -0.05),
];
/// Translation amplitude of the synthetic motion (world units).
const AMPLITUDE: f32 = 0.3;

/// Pieces in a box of about 10 units: pivots spread over [-5, 5] × [0, 10] × [-5, 5], translations
/// of `AMPLITUDE`, rotations about x, y, z and two oblique axes — swinging up to ±1.2 rad, or (every
/// seventh piece) spinning 1–3 full turns per loop so quaternions cross hemispheres.
fn synthetic_pieces(frames: usize) -> Vec<RigidPiece> {
    (0..PIECES)
        .map(|i| {
            let fi = i as f32;
            let pivot = Vec3::new(
                (fi * 0.37).fract() * 10.0 - 5.0,
                (fi * 0.61).fract() * 10.0,
                (fi * 0.73).fract() * 10.0 - 5.0,
            );
            let axis = match i % 5 {
                0 => Vec3::X,
                1 => Vec3::Y,
                2 => Vec3::Z,
                3 => Vec3::new(1.0, 1.0, 0.0).normalize(),
                _ => Vec3::new(-1.0, 2.0, 3.0).normalize(),
            };
            let frames = (0..frames)
                .map(|f| {
                    let phase = std::f32::consts::TAU * f as f32 / frames as f32;
                    let angle = if i % 7 == 0 {
                        phase * (1 + i % 3) as f32
                    } else {
                        1.2 * (phase + fi).sin()
                    };
                    let offset = Vec3::new(
                        (phase + fi).sin(),
                        0.5 * (2.0 * phase + 0.5 * fi).sin(),
                        (phase + 0.3 * fi).cos(),
                    );
                    RigidFrame {
                        position: pivot + AMPLITUDE * offset,
                        rotation: Quat::from_axis_angle(axis, angle),
                    }
                })
                .collect();
            RigidPiece { pivot, frames }
        })
        .collect()
}

/// Rotation angle (radians) taking `a` to `b`, computed in f64.
fn rotation_error(a: Quat, b: Quat) -> f64 {
    let da = DQuat::from_xyzw(a.x.into(), a.y.into(), a.z.into(), a.w.into()).normalize();
    let db = DQuat::from_xyzw(b.x.into(), b.y.into(), b.z.into(), b.w.into()).normalize();
    let d = da.conjugate() * db;
    2.0 * glam::DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

/// Largest error of one stored quaternion component: PNG16 rounds [-1, 1] to steps of 2/65535;
/// half floats round components below 1 in magnitude to steps of at most 2^-11.
fn component_error(format: VatFormat) -> f64 {
    match format {
        VatFormat::Png16 => 1.0 / 65535.0,
        VatFormat::ExrHalf => 2f64.powi(-12),
    }
}

/// Bound on the rotation angle error. With kept-component errors ≤ δ: |Δkept| ≤ √3·δ; the rebuilt
/// largest component L = sqrt(1 − |kept|²) ≥ 1/2 moves by ≤ |kept|·|Δkept|/L ≤ 3δ; so |Δq| ≤ √12·δ
/// and the rotation angle (twice the quaternion angle) by ≤ 2·√12·δ ≈ 6.9δ (10% margin on top).
fn angle_bound(format: VatFormat) -> f64 {
    2.0 * 12f64.sqrt() * component_error(format) * 1.1 + 1e-6
}

/// Per-axis bound on a decoded position's error.
fn position_bound(format: VatFormat, sidecar: &VatSidecar, value: Vec3) -> Vec3 {
    match format {
        // Half the 16-bit step of the bounds' range, plus f32 rounding of min + t·range.
        VatFormat::Png16 => {
            let min = Vec3::from(sidecar.bound_min);
            let max = Vec3::from(sidecar.bound_max);
            let eps = 4.0 * f32::EPSILON * min.abs().max(max.abs());
            (max - min) / 65535.0 / 2.0 + eps
        }
        // Half floats: relative rounding 2^-11 (absolute 2^-25 in the subnormal range).
        VatFormat::ExrHalf => (value.abs() * 2f32.powi(-11)).max(Vec3::splat(2f32.powi(-25))),
    }
}

fn encode(pieces: &[RigidPiece], format: VatFormat) -> VatTextures {
    encode_rigid(pieces, 30.0, format).expect("synthetic pieces encode")
}

fn decode(textures: &VatTextures) -> Vec<Vec<RigidFrame>> {
    decode_rigid(
        &textures.position.bytes,
        &textures.rotation.bytes,
        &textures.sidecar,
    )
    .expect("own textures decode")
}

#[test]
fn decoded_frames_match_the_input_within_format_precision() {
    let pieces = synthetic_pieces(FRAMES);
    for format in [VatFormat::Png16, VatFormat::ExrHalf] {
        let textures = encode(&pieces, format);
        let sidecar = &textures.sidecar;
        assert_eq!(
            (sidecar.width, sidecar.height),
            (PIECES as u32, FRAMES as u32)
        );
        assert_eq!(textures.position.extension, format.extension());
        let decoded = decode(&textures);
        assert_eq!(decoded.len(), PIECES);

        let angle_limit = angle_bound(format);
        let (mut worst_angle, mut worst_corner) = (0.0f64, 0.0f32);
        for (piece, track) in pieces.iter().zip(&decoded) {
            assert_eq!(track.len(), FRAMES);
            for (truth, got) in piece.frames.iter().zip(track) {
                let bound = position_bound(format, sidecar, truth.position);
                let error = (got.position - truth.position).abs();
                assert!(
                    error.cmple(bound).all(),
                    "{format:?}: position {:?} decoded as {:?} (error {error:?} > {bound:?})",
                    truth.position,
                    got.position
                );
                let angle = rotation_error(truth.rotation, got.rotation);
                assert!(
                    angle <= angle_limit,
                    "{format:?}: rotation error {angle} rad > {angle_limit}"
                );
                worst_angle = worst_angle.max(angle);
                // Corners: |Δ| ≤ |Δposition| + angle error × distance from the pivot.
                for corner in CORNERS {
                    let rest = piece.pivot + corner;
                    let want = truth.rotation * (rest - piece.pivot) + truth.position;
                    let have = got.rotation * (rest - piece.pivot) + got.position;
                    let limit = bound.length() + angle_limit as f32 * corner.length() + 1e-5;
                    let miss = (have - want).length();
                    assert!(miss <= limit, "{format:?}: corner off by {miss} > {limit}");
                    worst_corner = worst_corner.max(miss);
                }
            }
        }
        println!(
            "{format:?}: worst rotation error {worst_angle:.2e} rad (bound {angle_limit:.2e}), \
             worst corner error {worst_corner:.2e}"
        );
    }
}

#[test]
fn rotation_alpha_holds_the_turns_to_the_next_frame() {
    let pieces = synthetic_pieces(FRAMES);
    for format in [VatFormat::Png16, VatFormat::ExrHalf] {
        let textures = encode(&pieces, format);
        let turns = decode_turns_per_frame(&textures.rotation.bytes, &textures.sidecar)
            .expect("own texture decodes");
        for (piece, piece_turns) in pieces.iter().zip(&turns) {
            for (f, &stored) in piece_turns.iter().enumerate() {
                let a = piece.frames[f].rotation;
                let b = piece.frames[(f + 1) % FRAMES].rotation;
                let want = rotation_error(a, b) / std::f64::consts::TAU;
                let tolerance = match format {
                    VatFormat::Png16 => 1.0 / 65535.0 + 1e-6,
                    VatFormat::ExrHalf => want * 2f64.powi(-11) + 1e-6,
                };
                assert!(
                    (f64::from(stored) - want).abs() <= tolerance,
                    "{format:?}: stored {stored} turns, want {want}"
                );
            }
        }
    }
}

#[test]
fn encoding_is_deterministic() {
    let pieces = synthetic_pieces(FRAMES);
    for format in [VatFormat::Png16, VatFormat::ExrHalf] {
        assert_eq!(encode(&pieces, format), encode(&pieces, format));
    }
}

#[test]
fn pieces_wrap_onto_more_rows_when_wider_than_the_limit() {
    let pieces = synthetic_pieces(8);
    let options = VatOptions {
        max_texture_size: 32,
        ..VatOptions::default()
    };
    let textures = encode_rigid_with(&pieces, 24.0, VatFormat::Png16, &options).expect("fits");
    let sidecar = &textures.sidecar;
    assert_eq!(
        (sidecar.width, sidecar.rows_per_frame, sidecar.height),
        (32, 2, 16)
    );
    // Piece 33 sits in the second row of each frame block, column 1, at the texel centre.
    assert_eq!(textures.piece_uv[33], [1.5 / 32.0, 1.5 / 16.0]);
    let decoded = decode(&textures);
    for (piece, track) in pieces.iter().zip(&decoded) {
        for (truth, got) in piece.frames.iter().zip(track) {
            let bound = position_bound(VatFormat::Png16, sidecar, truth.position);
            assert!((got.position - truth.position).abs().cmple(bound).all());
            assert!(rotation_error(truth.rotation, got.rotation) <= angle_bound(VatFormat::Png16));
        }
    }
}

#[test]
fn sidecar_round_trips_through_json() {
    let pieces = synthetic_pieces(FRAMES);
    for format in [VatFormat::Png16, VatFormat::ExrHalf] {
        let sidecar = encode(&pieces, format).sidecar;
        let json = serde_json::to_string_pretty(&sidecar).expect("serializes");
        let back: VatSidecar = serde_json::from_str(&json).expect("parses");
        assert_eq!(back, sidecar);
        // The written form, not a read of the sidecar: the keys and spellings engines' importers
        // read (`exr_half`, `png16`), which the typed round trip above cannot see.
        let value: serde_json::Value = serde_json::from_str(&json).expect("parses");
        assert_eq!(value["layout"], "houdini-vat3-rigid");
        assert_eq!(value["piece_uv_channel"], "TEXCOORD_1");
        assert_eq!(value["frames"], FRAMES as u64);
        assert_eq!(value["fps"], 30.0);
        assert_eq!(
            value["format"],
            match format {
                VatFormat::Png16 => "png16",
                VatFormat::ExrHalf => "exr_half",
            }
        );
        assert_eq!(value["hdr"], format == VatFormat::ExrHalf);
        let ext = format.extension();
        assert_eq!(value["textures"]["position"], format!("vat_pos.{ext}"));
        assert_eq!(value["textures"]["rotation"], format!("vat_rot.{ext}"));
    }
}

fn piece_with(frames: Vec<RigidFrame>) -> RigidPiece {
    RigidPiece {
        pivot: Vec3::ZERO,
        frames,
    }
}

fn frame(position: Vec3, rotation: Quat) -> RigidFrame {
    RigidFrame { position, rotation }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let ok = frame(Vec3::ONE, Quat::IDENTITY);
    let png = VatFormat::Png16;
    let err = |pieces: &[RigidPiece]| encode_rigid(pieces, 30.0, png).expect_err("must fail");

    assert!(matches!(err(&[]), VatError::NoPieces));
    assert!(matches!(err(&[piece_with(vec![])]), VatError::NoFrames));
    assert!(matches!(
        err(&[piece_with(vec![ok, ok]), piece_with(vec![ok])]),
        VatError::FrameCountMismatch {
            piece: 1,
            expected: 2,
            found: 1
        }
    ));
    let nan = Vec3::new(f32::NAN, 0.0, 0.0);
    assert!(matches!(
        err(&[piece_with(vec![ok, frame(nan, Quat::IDENTITY)])]),
        VatError::NonFinite { piece: 0, .. }
    ));
    assert!(matches!(
        err(&[RigidPiece {
            pivot: Vec3::splat(f32::INFINITY),
            frames: vec![ok]
        }]),
        VatError::NonFinite { .. }
    ));
    let nan_rotation = Quat::from_xyzw(0.0, f32::NAN, 0.0, 1.0);
    assert!(matches!(
        err(&[piece_with(vec![frame(Vec3::ONE, nan_rotation)])]),
        VatError::NonFinite { .. }
    ));
    let zero_rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    assert!(matches!(
        err(&[piece_with(vec![frame(Vec3::ONE, zero_rotation)])]),
        VatError::ZeroRotation { piece: 0, frame: 0 }
    ));
    for fps in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            encode_rigid(&[piece_with(vec![ok])], fps, png),
            Err(VatError::InvalidFps(_))
        ));
    }
    let far = frame(Vec3::new(1e6, 0.0, 0.0), Quat::IDENTITY);
    assert!(matches!(
        encode_rigid(&[piece_with(vec![far])], 30.0, VatFormat::ExrHalf),
        Err(VatError::OutOfHalfRange { .. })
    ));
    let huge = [
        piece_with(vec![frame(Vec3::splat(-3e38), Quat::IDENTITY)]),
        piece_with(vec![frame(Vec3::splat(3e38), Quat::IDENTITY)]),
    ];
    assert!(matches!(
        encode_rigid(&huge, 30.0, png),
        Err(VatError::RangeOverflow)
    ));
    let small = VatOptions {
        max_texture_size: 16,
        ..VatOptions::default()
    };
    assert!(matches!(
        encode_rigid_with(&synthetic_pieces(8), 30.0, png, &small),
        Err(VatError::TooLarge { .. })
    ));
    let zero = VatOptions {
        max_texture_size: 0,
        ..VatOptions::default()
    };
    assert!(encode_rigid_with(&[piece_with(vec![ok])], 30.0, png, &zero).is_err());
}

#[test]
fn bad_textures_and_sidecars_are_errors_not_panics() {
    let pieces = synthetic_pieces(4);
    let textures = encode(&pieces, VatFormat::Png16);
    let (pos, rot, sidecar) = (
        &textures.position.bytes,
        &textures.rotation.bytes,
        &textures.sidecar,
    );
    assert!(decode_rigid(pos, rot, sidecar).is_ok());

    assert!(matches!(
        decode_rigid(b"not an image", rot, sidecar),
        Err(VatError::Decode {
            role: "position",
            ..
        })
    ));
    assert!(decode_rigid(pos, &rot[..rot.len() / 2], sidecar).is_err());
    // A PNG read as EXR.
    let mut as_exr = sidecar.clone();
    as_exr.format = VatFormat::ExrHalf;
    as_exr.hdr = true;
    assert!(matches!(
        decode_rigid(pos, rot, &as_exr),
        Err(VatError::Decode { .. })
    ));
    // Sidecars that contradict themselves or the images.
    let mutations: Vec<fn(&mut VatSidecar)> = vec![
        |s| s.layout = "houdini-vat3-soft".into(),
        |s| s.hdr = true,
        |s| s.frames = 0,
        |s| s.frames = u32::MAX,
        |s| s.pieces = u32::MAX,
        |s| s.width = 0,
        |s| s.width = u32::MAX,
        |s| s.rows_per_frame = u32::MAX,
        |s| s.height += 1,
        |s| s.bound_max[1] = f32::NAN,
        |s| s.bound_max[0] = s.bound_min[0] - 1.0,
    ];
    for mutate in mutations {
        let mut bad = sidecar.clone();
        mutate(&mut bad);
        assert!(decode_rigid(pos, rot, &bad).is_err(), "{bad:?}");
    }
    // EXR with the wrong sidecar size.
    let exr = encode(&pieces, VatFormat::ExrHalf);
    let mut wrong = exr.sidecar.clone();
    wrong.pieces -= 1;
    wrong.width -= 1;
    assert!(decode_rigid(&exr.position.bytes, &exr.rotation.bytes, &wrong).is_err());
}

/// The WGSL reference evaluated by a small compute entry point: one query per vertex.
const HARNESS: &str = r#"
struct Query {
    rest_position: vec3<f32>,
    frame: f32,
    rest_normal: vec3<f32>,
    pad0: f32,
    piece_uv: vec2<f32>,
    pad1: vec2<f32>,
    pivot: vec3<f32>,
    pad2: f32,
}

struct Answer {
    position: vec3<f32>,
    pad0: f32,
    normal: vec3<f32>,
    pad1: f32,
}

@group(0) @binding(0) var position_tex: texture_2d<f32>;
@group(0) @binding(1) var rotation_tex: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: VatRigidParams;
@group(0) @binding(3) var<storage, read> queries: array<Query>;
@group(0) @binding(4) var<storage, read_write> answers: array<Answer>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    let out = vat_rigid(q.rest_position, q.rest_normal, q.piece_uv, q.pivot, q.frame,
                        position_tex, rotation_tex, params);
    answers[id.x] = Answer(out.position, 0.0, out.normal, 0.0);
}
"#;

struct Gpu {
    compute: common::Compute,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

/// Any adapter with compute shaders (llvmpipe and lavapipe qualify), or `None` with a message.
fn open_gpu() -> Option<Gpu> {
    let compute = common::open_compute("the WGSL VAT reference")?;
    let device = &compute.device;
    let source = format!(
        "{}\n{HARNESS}",
        include_str!("../shaders/frond_vat_rigid.wgsl")
    );
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("frond_vat_rigid.wgsl + harness"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let texture_entry = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let buffer_entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("vat test"),
        entries: &[
            texture_entry(0),
            texture_entry(1),
            buffer_entry(2, wgpu::BufferBindingType::Uniform),
            buffer_entry(3, wgpu::BufferBindingType::Storage { read_only: true }),
            buffer_entry(4, wgpu::BufferBindingType::Storage { read_only: false }),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("vat test"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("vat test"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    Some(Gpu {
        compute,
        pipeline,
        layout,
    })
}

/// One vertex to evaluate.
#[derive(Clone, Copy, Debug)]
struct Query {
    piece: usize,
    corner: Vec3,
    normal: Vec3,
    frame: f32,
}

/// Uploads a texture the way an engine would sample it: PNG16 as normalized floats, EXR as
/// half floats; `bottom_up` stores the image's bottom row first, as Unity does.
fn upload(
    gpu: &Gpu,
    image: &frond_export::vat::VatImage,
    format: VatFormat,
    bottom_up: bool,
) -> wgpu::Texture {
    let (texture_format, data, texel_bytes) = match format {
        VatFormat::Png16 => {
            let decoded =
                image::load_from_memory_with_format(&image.bytes, image::ImageFormat::Png)
                    .expect("own PNG")
                    .into_rgba16();
            let floats: Vec<f32> = decoded
                .into_raw()
                .into_iter()
                .map(|v| f32::from(v) / 65535.0)
                .collect();
            (
                wgpu::TextureFormat::Rgba32Float,
                bytemuck::cast_slice::<f32, u8>(&floats).to_vec(),
                16,
            )
        }
        VatFormat::ExrHalf => {
            let decoded =
                image::load_from_memory_with_format(&image.bytes, image::ImageFormat::OpenExr)
                    .expect("own EXR")
                    .into_rgba32f();
            let halves: Vec<u16> = decoded
                .into_raw()
                .into_iter()
                .map(|v| half::f16::from_f32(v).to_bits())
                .collect();
            (
                wgpu::TextureFormat::Rgba16Float,
                bytemuck::cast_slice::<u16, u8>(&halves).to_vec(),
                8,
            )
        }
    };
    let data = if bottom_up {
        let row = (image.width * texel_bytes) as usize;
        data.chunks_exact(row).rev().flatten().copied().collect()
    } else {
        data
    };
    let size = wgpu::Extent3d {
        width: image.width,
        height: image.height,
        depth_or_array_layers: 1,
    };
    let texture = gpu.compute.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("vat texture"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: texture_format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    gpu.compute.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        &data,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(image.width * texel_bytes),
            rows_per_image: Some(image.height),
        },
        size,
    );
    texture
}

/// Runs the queries through the WGSL reference; returns (position, normal) per query.
/// `bottom_up` plays an engine that stores images bottom row first and flips UV v (Unity).
fn run_shader(
    gpu: &Gpu,
    textures: &VatTextures,
    pieces: &[RigidPiece],
    queries: &[Query],
    bottom_up: bool,
) -> Vec<(Vec3, Vec3)> {
    use wgpu::util::DeviceExt;
    let sidecar = &textures.sidecar;
    let position = upload(gpu, &textures.position, sidecar.format, bottom_up);
    let rotation = upload(gpu, &textures.rotation, sidecar.format, bottom_up);

    let min = sidecar.bound_min;
    let max = sidecar.bound_max;
    let params: [f32; 12] = [
        min[0],
        min[1],
        min[2],
        sidecar.frames as f32,
        max[0],
        max[1],
        max[2],
        if sidecar.hdr { 1.0 } else { 0.0 },
        if bottom_up { -1.0 } else { 1.0 },
        0.0,
        0.0,
        0.0,
    ];
    let mut packed: Vec<f32> = Vec::with_capacity(queries.len() * 16);
    for q in queries {
        // What the mesh would carry: the rest vertex, TEXCOORD_1 and the pivot channels.
        let pivot_uv = textures.pivot_uv[q.piece];
        let pivot = Vec3::new(pivot_uv[0][0], pivot_uv[1][0], pivot_uv[1][1]);
        let rest = pieces[q.piece].pivot + q.corner;
        let mut uv = textures.piece_uv[q.piece];
        if bottom_up {
            uv[1] = 1.0 - uv[1];
        }
        packed.extend_from_slice(&[
            rest.x, rest.y, rest.z, q.frame, q.normal.x, q.normal.y, q.normal.z, 0.0, uv[0], uv[1],
            0.0, 0.0, pivot.x, pivot.y, pivot.z, 0.0,
        ]);
    }
    let device = &gpu.compute.device;
    let params_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: bytemuck::cast_slice(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let query_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("queries"),
        contents: bytemuck::cast_slice(&packed),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let answer_size = (queries.len() * 8 * 4) as u64;
    let (answers, readback) = common::answer_buffers(device, answer_size);
    let position_view = position.create_view(&Default::default());
    let rotation_view = rotation.create_view(&Default::default());
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("vat test"),
        layout: &gpu.layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&position_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&rotation_view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: params_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: query_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: answers.as_entire_binding(),
            },
        ],
    });
    let bytes = common::dispatch_and_read(
        &gpu.compute,
        &gpu.pipeline,
        &bind_group,
        queries.len() as u32,
        &answers,
        &readback,
    );
    let floats: &[f32] = bytemuck::cast_slice(&bytes);
    floats
        .chunks_exact(8)
        .map(|a| (Vec3::new(a[0], a[1], a[2]), Vec3::new(a[4], a[5], a[6])))
        .collect()
}

/// Vertices of a few pieces at integer, fractional, wrapping and negative frames.
fn queries_for(frames: usize) -> Vec<Query> {
    let n = frames as f32;
    let frame_list = [
        0.0,
        1.0,
        2.25,
        n * 0.5 + 0.5,
        n - 1.0,
        n - 0.25, // blends the last frame into frame 0
        n,        // = frame 0
        -0.5,
        3.0 * n + 1.75,
    ];
    let normals = [
        Vec3::Z,
        Vec3::new(0.0, 0.6, 0.8),
        Vec3::X,
        Vec3::new(-0.48, 0.6, 0.64),
    ];
    let mut queries = Vec::new();
    for piece in [0usize, 7, 13, 21, 33, 49] {
        for (corner, normal) in CORNERS.into_iter().zip(normals) {
            for frame in frame_list {
                queries.push(Query {
                    piece,
                    corner,
                    normal,
                    frame,
                });
            }
        }
    }
    queries
}

#[test]
fn wgsl_reference_shader_matches_the_cpu_formula() {
    let Some(gpu) = open_gpu() else {
        return;
    };
    let wrapped = VatOptions {
        max_texture_size: 32,
        ..VatOptions::default()
    };
    let cases = [
        (VatFormat::Png16, FRAMES, VatOptions::default(), false),
        (VatFormat::ExrHalf, FRAMES, VatOptions::default(), false),
        (VatFormat::Png16, 8, wrapped.clone(), false),
        (VatFormat::ExrHalf, 8, wrapped.clone(), false),
        (VatFormat::Png16, 8, wrapped.clone(), true),
        (VatFormat::ExrHalf, FRAMES, VatOptions::default(), true),
    ];
    for (format, frames, options, bottom_up) in cases {
        let pieces = synthetic_pieces(frames);
        let textures = encode_rigid_with(&pieces, 30.0, format, &options).expect("encodes");
        let decoded = decode(&textures);
        let queries = queries_for(frames);
        let answers = run_shader(&gpu, &textures, &pieces, &queries, bottom_up);
        assert_eq!(answers.len(), queries.len());

        let mut worst = 0.0f32;
        for (q, (gpu_position, gpu_normal)) in queries.iter().zip(answers) {
            let piece = &pieces[q.piece];
            let rest = piece.pivot + q.corner;
            // CPU formula on the decoded textures.
            let pose = sample_frame(&decoded[q.piece], q.frame).expect("finite frame");
            let want_position = pose.rotation * (rest - piece.pivot) + pose.position;
            let want_normal = pose.rotation * q.normal;
            let miss = (gpu_position - want_position).length();
            let tolerance = 2e-4 * (1.0 + want_position.length());
            assert!(
                miss <= tolerance,
                "{format:?} {q:?}: shader {gpu_position:?}, CPU {want_position:?} (off by {miss})"
            );
            assert!(
                (gpu_normal - want_normal).length() <= 2e-4,
                "{format:?} {q:?}: shader normal {gpu_normal:?}, CPU {want_normal:?}"
            );
            worst = worst.max(miss);

            // At whole frames the shader also reproduces the original motion within the
            // format's precision.
            if q.frame.fract() == 0.0 {
                let index = q.frame.rem_euclid(frames as f32) as usize;
                let truth = piece.frames[index];
                let truth_position = truth.rotation * q.corner + truth.position;
                let limit = position_bound(format, &textures.sidecar, truth.position).length()
                    + angle_bound(format) as f32 * q.corner.length()
                    + tolerance;
                let off = (gpu_position - truth_position).length();
                assert!(
                    off <= limit,
                    "{format:?} {q:?}: {off} from the input > {limit}"
                );
            }
        }
        println!(
            "{format:?} {}×{}{}: {} vertices, worst shader-vs-CPU difference {worst:.2e}",
            textures.sidecar.width,
            textures.sidecar.height,
            if bottom_up { " (bottom row first)" } else { "" },
            queries.len()
        );
    }
}
