//! Vertex animation textures for rigid billboards (Houdini VAT 3.0 rigid layout).
//!
//! Every billboard is one rigid piece. Two textures hold, per piece (column) and frame (row), where
//! the piece's pivot is and how the piece is rotated relative to the rest pose stored in the mesh;
//! the mesh carries each piece's texture coordinate in `TEXCOORD_1` and its rest pivot in
//! `TEXCOORD_2`/`TEXCOORD_3`. `export/VAT.md` documents the layout texel by texel.

use std::io::Cursor;

use glam::{DQuat, DVec3, Quat, Vec3, Vec4};
use half::f16;
use serde::{Deserialize, Serialize};

/// Largest texture width or height written (a limit every desktop GPU and engine accepts).
pub const MAX_TEXTURE_SIZE: u32 = 8192;
/// Value of [`VatSidecar::layout`]: the only layout this module writes and reads.
pub const LAYOUT: &str = "houdini-vat3-rigid";
/// glTF attribute holding each piece's texture coordinate (the texel centre of its frame-0 texel).
pub const PIECE_UV_CHANNEL: &str = "TEXCOORD_1";
/// glTF attribute components holding the rest pivot's x, y and z.
pub const PIVOT_CHANNELS: [&str; 3] = ["TEXCOORD_2.x", "TEXCOORD_3.x", "TEXCOORD_3.y"];
/// Value of [`VatSidecar::rotation_encoding`].
pub const ROTATION_ENCODING: &str = "smallest_three";
/// Value of [`VatSidecar::rest_pose`].
pub const REST_POSE: &str = "mesh";
/// Value of [`VatSidecar::coordinate_system`] for data in the glTF file's own space.
pub const COORDINATE_SYSTEM: &str = "gltf_y_up_right_handed_metres";
/// Value of [`VatSidecar::version`]: 2 added `version`, `space`, `start_s` and `clips` (a
/// sidecar without `version` is version 1, glTF space).
pub const SIDECAR_VERSION: u32 = 2;

/// The space the texture data and the pivot channels are baked in: the glTF file's, or the one
/// an engine's glTF importer turns the mesh into, so that Houdini VAT 3.0's stock materials,
/// which take the data as the engine's own (Houdini bakes per engine), play it unedited.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VatSpace {
    /// Right-handed, +Y up, metres: the glTF file's space (frond's own shaders).
    #[default]
    Gltf,
    /// Unity as glTFast and UnityGLTF import: x negated (left-handed, +Y up, metres), every
    /// UV set's v flipped (`v' = 1 − v`).
    Unity,
    /// Unreal as its glTF importers convert: y and z swapped (left-handed, +Z up), centimetres
    /// (× 100); UVs unchanged.
    Unreal,
}

impl VatSpace {
    /// [`VatSidecar::coordinate_system`] for this space.
    pub fn coordinate_system(self) -> &'static str {
        match self {
            VatSpace::Gltf => COORDINATE_SYSTEM,
            VatSpace::Unity => "unity_y_up_left_handed_metres",
            VatSpace::Unreal => "unreal_z_up_left_handed_centimetres",
        }
    }

    /// A glTF-space point in this space.
    pub fn point(self, p: Vec3) -> Vec3 {
        match self {
            VatSpace::Gltf => p,
            VatSpace::Unity => Vec3::new(-p.x, p.y, p.z),
            VatSpace::Unreal => Vec3::new(p.x, p.z, p.y) * 100.0,
        }
    }

    /// A point of this space back in glTF space (the inverse of [`VatSpace::point`]).
    pub fn point_to_gltf(self, p: Vec3) -> Vec3 {
        match self {
            VatSpace::Gltf => p,
            VatSpace::Unity => Vec3::new(-p.x, p.y, p.z),
            VatSpace::Unreal => Vec3::new(p.x, p.z, p.y) / 100.0,
        }
    }

    /// A glTF-space rotation in this space: conjugated by the change of axes, which mirrors
    /// (determinant −1), so the axis (a pseudovector) is mapped and negated. Its own inverse.
    pub fn rotation(self, q: Quat) -> Quat {
        match self {
            VatSpace::Gltf => q,
            VatSpace::Unity => Quat::from_xyzw(q.x, -q.y, -q.z, q.w),
            VatSpace::Unreal => Quat::from_xyzw(-q.x, -q.z, -q.y, q.w),
        }
    }

    /// The values of `TEXCOORD_2` and `TEXCOORD_3` that make the engine read the rest pivot,
    /// in its space, as `(uv2.x, uv3.x, uv3.y)` after its importer's UV conversion (Unity
    /// flips v, so v is written as `1 − value`).
    pub fn pivot_channels(self, pivot: Vec3) -> [[f32; 2]; 2] {
        let p = self.point(pivot);
        match self {
            VatSpace::Unity => [[p.x, 1.0], [p.y, 1.0 - p.z]],
            VatSpace::Gltf | VatSpace::Unreal => [[p.x, 0.0], [p.y, p.z]],
        }
    }
}

/// One clip the textures hold: frames `first_frame .. first_frame + frames` are its loop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VatClip {
    /// The input's clip name (None for a tree without clips).
    pub name: Option<String>,
    /// Clip time of frame `first_frame`, seconds (the sampled loop's start).
    pub start_s: f32,
    /// The loop's length, seconds (`frames / fps`).
    pub duration_s: f32,
    /// The texture frame holding the loop's first sample.
    pub first_frame: u32,
    /// Frames of the loop (it wraps from the last back to `first_frame`).
    pub frames: u32,
}
/// Value of [`VatSidecar::row_order`].
pub const ROW_ORDER: &str = "top_row_first";

/// One rigid piece (a billboard): its pivot in the rest pose (world units) and, per frame,
/// where that pivot is and how the piece is rotated relative to its rest orientation.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidPiece {
    /// The pivot in the rest pose the mesh holds (world units, glTF space).
    pub pivot: Vec3,
    /// The pose at each frame (every piece has the same count).
    pub frames: Vec<RigidFrame>,
}

/// A piece's pose at one frame: a rest-pose point `p` of the piece is drawn at
/// `rotation * (p - pivot) + position`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidFrame {
    /// Where the pivot is (world units).
    pub position: Vec3,
    /// The rotation from the rest orientation (need not be normalised; not zero).
    pub rotation: Quat,
}

/// Texture file format: what Houdini calls HDR (EXR, raw half floats) or LDR (PNG, remapped).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VatFormat {
    /// OpenEXR, uncompressed, RGBA half floats holding raw values.
    ExrHalf,
    /// PNG, RGBA 16 bits per channel, positions remapped through the bounds, rotations from [-1, 1].
    Png16,
}

impl VatFormat {
    /// File extension without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            VatFormat::ExrHalf => "exr",
            VatFormat::Png16 => "png",
        }
    }

    /// Whether texels hold raw values (Houdini's "HDR" switch) rather than remapped ones.
    pub fn is_hdr(self) -> bool {
        matches!(self, VatFormat::ExrHalf)
    }
}

/// One encoded texture file.
#[derive(Clone, Debug, PartialEq)]
pub struct VatImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// The encoded file (EXR or PNG bytes).
    pub bytes: Vec<u8>,
    /// File extension without the dot ("exr" or "png").
    pub extension: &'static str,
}

/// File names of the two textures, relative to the sidecar.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct VatTextureFiles {
    /// RGB: pivot position per frame; A: index of the dropped quaternion component / 4.
    pub position: String,
    /// RGB: the three smaller quaternion components; A: rotations (turns) to the next frame.
    pub rotation: String,
    /// RGB: each piece's rest pivot (as the pivot channels give it, in the data's space), one
    /// frame's rows (`rows_per_frame` high), EXR half: for engines that drop `TEXCOORD_2`/`_3`
    /// (Godot 3's importer keeps two UV sets). Version 2 sidecars.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pivot: Option<String>,
}

/// The JSON written beside the textures: everything a material needs to play them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VatSidecar {
    /// Always [`LAYOUT`].
    pub layout: String,
    /// The textures' file format.
    pub format: VatFormat,
    /// True for EXR: texels are raw values, the bounds are not used to decode.
    pub hdr: bool,
    /// Rows of frames (frame f is the pose at time f / fps; the loop wraps from the last to frame 0).
    pub frames: u32,
    /// Frames per second ("Houdini FPS" in the engine materials).
    pub fps: f32,
    /// frames / fps: the loop's duration.
    pub duration_s: f32,
    /// Rigid pieces (billboards), in the mesh's billboard order.
    pub pieces: u32,
    /// Texture width in texels (both textures have the same size).
    pub width: u32,
    /// Texture height in texels: `frames × rows_per_frame`.
    pub height: u32,
    /// Texel rows per frame: pieces wrap onto further rows when there are more than `width`.
    pub rows_per_frame: u32,
    /// Always [`ROW_ORDER`]: image row 0 (top) is frame 0's first row.
    pub row_order: String,
    /// The texture files' names.
    pub textures: VatTextureFiles,
    /// The engine materials' "Bound Min/Max": PNG16 positions decode as min + t * (max - min).
    /// Whole numbers, so the flags Houdini hides in their fractions read as "no padding";
    /// for EXR `bound_max[2]` carries +0.5, Houdini's "raw positions" flag (see VAT.md).
    pub bound_min: [f32; 3],
    /// The engine materials' "Bound Max" (see `bound_min`).
    pub bound_max: [f32; 3],
    /// Tight lower bound of the pivot trajectories (informational).
    pub position_min: [f32; 3],
    /// Tight upper bound of the pivot trajectories (informational).
    pub position_max: [f32; 3],
    /// Always [`PIECE_UV_CHANNEL`].
    pub piece_uv_channel: String,
    /// Always [`PIVOT_CHANNELS`].
    pub pivot_channels: [String; 3],
    /// Always [`ROTATION_ENCODING`].
    pub rotation_encoding: String,
    /// Always [`REST_POSE`]: the mesh holds the rest pose; no texture row is the rest pose.
    pub rest_pose: String,
    /// [`VatSpace::coordinate_system`] of `space`.
    pub coordinate_system: String,
    /// [`SIDECAR_VERSION`] when written; 1 for sidecars without the field.
    #[serde(default = "version_1")]
    pub version: u32,
    /// Where the texture data and pivot channels are baked (glTF space before version 2).
    #[serde(default)]
    pub space: VatSpace,
    /// Clip time of frame 0, seconds: play at `(clip_time − start_s) × fps`.
    #[serde(default)]
    pub start_s: f32,
    /// The clips the rows hold, in order (one sampled loop today).
    #[serde(default)]
    pub clips: Vec<VatClip>,
}

/// The version of a sidecar without `version`.
fn version_1() -> u32 {
    1
}

/// Everything [`encode_rigid`] produces.
#[derive(Clone, Debug, PartialEq)]
pub struct VatTextures {
    /// [`VatTextureFiles::position`].
    pub position: VatImage,
    /// [`VatTextureFiles::rotation`].
    pub rotation: VatImage,
    /// [`VatTextureFiles::pivot`].
    pub pivot: VatImage,
    /// What is written beside the textures as JSON.
    pub sidecar: VatSidecar,
    /// Per piece: the texture coordinate to put in the UV channel named in the sidecar
    /// (same for all corners of that billboard).
    pub piece_uv: Vec<[f32; 2]>,
    /// Per piece: the values for `TEXCOORD_2` and `TEXCOORD_3` holding its rest pivot:
    /// `[[pivot.x, 0], [pivot.y, pivot.z]]` (same for all corners of that billboard).
    pub pivot_uv: Vec<[[f32; 2]; 2]>,
}

/// Knobs of [`encode_rigid_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct VatOptions {
    /// Largest texture width or height (default [`MAX_TEXTURE_SIZE`]).
    pub max_texture_size: u32,
    /// File name stem: textures are `{stem}_pos.{ext}` and `{stem}_rot.{ext}`.
    pub file_stem: String,
    /// The space the data is baked in (the pieces are given in glTF space).
    pub space: VatSpace,
    /// The clip the frames are a loop of (for the sidecar).
    pub clip: Option<String>,
    /// The clip's time at frame 0, seconds (for the sidecar).
    pub start_s: f32,
}

impl Default for VatOptions {
    fn default() -> Self {
        VatOptions {
            max_texture_size: MAX_TEXTURE_SIZE,
            file_stem: "vat".to_string(),
            space: VatSpace::Gltf,
            clip: None,
            start_s: 0.0,
        }
    }
}

/// Why textures could not be encoded or decoded.
#[derive(Debug, thiserror::Error)]
pub enum VatError {
    /// There is nothing to encode.
    #[error("no pieces to encode")]
    NoPieces,
    /// The first piece has no frames.
    #[error("the pieces have no frames")]
    NoFrames,
    /// Pieces disagree on the frame count.
    #[error(
        "piece {piece} has {found} frames, piece 0 has {expected}; all pieces need the same count"
    )]
    FrameCountMismatch {
        /// The first piece whose count differs.
        piece: usize,
        /// Piece 0's frame count.
        expected: usize,
        /// That piece's frame count.
        found: usize,
    },
    /// The frame rate is zero, negative or not finite.
    #[error("frames per second must be finite and positive, got {0}")]
    InvalidFps(f32),
    /// A pivot, position or rotation is NaN or infinite.
    #[error("piece {piece}: {what} is not finite")]
    NonFinite {
        /// The piece.
        piece: usize,
        /// Which value ("the rest pivot", "the position at frame 3", ...).
        what: String,
    },
    /// A rotation quaternion cannot be normalised.
    #[error("piece {piece} frame {frame}: the rotation quaternion has (near) zero length")]
    ZeroRotation {
        /// The piece.
        piece: usize,
        /// The frame.
        frame: usize,
    },
    /// A value to be stored as a half float is beyond its range (or not finite).
    #[error(
        "piece {piece} frame {frame}: position {value} is beyond the half-float range (±65504)"
    )]
    OutOfHalfRange {
        /// The piece (the billboard, for spectral textures).
        piece: usize,
        /// The frame (the term, for spectral textures).
        frame: usize,
        /// The value.
        value: f32,
    },
    /// The texture would exceed the largest size allowed.
    #[error(
        "{pieces} pieces × {frames} frames need a {width}×{height} texture, more than the maximum {max}"
    )]
    TooLarge {
        /// Pieces (billboards) to store.
        pieces: usize,
        /// Frames (terms per billboard, for spectral textures).
        frames: usize,
        /// The width needed, texels.
        width: u64,
        /// The height needed, texels.
        height: u64,
        /// The largest side allowed, texels.
        max: u32,
    },
    /// A spectral term's frequency is too high for a half float to hold exactly.
    #[error(
        "billboard {piece}: frequency {frequency} is above 2048 cycles per loop, which half \
         floats cannot hold exactly (sample the loop with at most 4096 samples)"
    )]
    FrequencyTooHigh {
        /// The billboard.
        piece: usize,
        /// The frequency, cycles per loop.
        frequency: f32,
    },
    /// The position bounds' extent overflows f32.
    #[error("the positions span more than f32 can hold")]
    RangeOverflow,
    /// The largest texture size allowed is 0.
    #[error("invalid maximum texture size {0}")]
    InvalidMaxSize(u32),
    /// A texture file could not be encoded.
    #[error("encoding the {role} texture failed: {message}")]
    Encode {
        /// Which texture (`position`, `rotation`).
        role: &'static str,
        /// The encoder's reason.
        message: String,
    },
    /// A texture file could not be decoded.
    #[error("decoding the {role} texture failed: {message}")]
    Decode {
        /// Which texture (`position`, `rotation`, `pivot`).
        role: &'static str,
        /// The decoder's reason.
        message: String,
    },
    /// A sidecar read back is inconsistent (the reason).
    #[error("sidecar does not describe a valid layout: {0}")]
    BadSidecar(String),
}

/// Encodes rigid pieces into position and rotation textures plus sidecar, with default options.
pub fn encode_rigid(
    pieces: &[RigidPiece],
    fps: f32,
    format: VatFormat,
) -> Result<VatTextures, VatError> {
    encode_rigid_with(pieces, fps, format, &VatOptions::default())
}

/// Texture geometry shared by the encoder and decoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Grid {
    width: u32,
    rows_per_frame: u32,
    height: u32,
}

impl Grid {
    /// Pieces fill a row left to right, then further rows; frames stack these blocks top down.
    fn new(pieces: usize, frames: usize, max: u32) -> Result<Grid, VatError> {
        let too_large = |width: u64, height: u64| VatError::TooLarge {
            pieces,
            frames,
            width,
            height,
            max,
        };
        let width = (pieces as u64).min(u64::from(max)).max(1);
        let rows = (pieces as u64).div_ceil(width);
        let height = rows.saturating_mul(frames as u64);
        if height > u64::from(max) {
            return Err(too_large(width, height));
        }
        // All three fit in u32: each is at most `max`.
        Ok(Grid {
            width: width as u32,
            rows_per_frame: rows as u32,
            height: height as u32,
        })
    }

    /// Column and frame-0 row of a piece.
    fn cell(&self, piece: usize) -> (u32, u32) {
        let width = self.width as usize;
        ((piece % width) as u32, (piece / width) as u32)
    }

    /// Index of a piece's texel at a frame, in texels from the top-left corner.
    fn texel(&self, piece: usize, frame: usize) -> usize {
        let (x, row) = self.cell(piece);
        let y = frame * self.rows_per_frame as usize + row as usize;
        y * self.width as usize + x as usize
    }
}

/// A quaternion in "smallest three" form: the three components kept (the dropped largest
/// one's slot replaced by w) and which component was dropped (0 = w, 1 = x, 2 = y, 3 = z).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SmallestThree {
    kept: [f32; 3],
    dropped: u8,
}

/// Drops the largest-magnitude component of a unit quaternion after flipping its sign so that
/// component is positive (the decoder rebuilds it as +sqrt(1 - |kept|²)). Ties prefer w, x, y, z.
fn smallest_three(q: Quat) -> SmallestThree {
    let components = [q.w, q.x, q.y, q.z];
    let mut dropped = 0usize;
    for (i, c) in components.iter().enumerate().skip(1) {
        if c.abs() > components[dropped].abs() {
            dropped = i;
        }
    }
    let q = if components[dropped] < 0.0 { -q } else { q };
    let kept = match dropped {
        0 => [q.x, q.y, q.z],
        1 => [q.w, q.y, q.z],
        2 => [q.x, q.w, q.z],
        _ => [q.x, q.y, q.w],
    };
    SmallestThree {
        kept,
        dropped: dropped as u8,
    }
}

/// Rebuilds a quaternion from the kept components and the dropped index (as the shaders do).
fn from_smallest_three(kept: [f32; 3], dropped: u8) -> Quat {
    let k = Vec3::from(kept);
    let largest = (1.0 - k.length_squared()).max(0.0).sqrt();
    let q = match dropped {
        1 => Quat::from_xyzw(largest, k.y, k.z, k.x),
        2 => Quat::from_xyzw(k.x, largest, k.z, k.y),
        3 => Quat::from_xyzw(k.x, k.y, largest, k.z),
        _ => Quat::from_xyzw(k.x, k.y, k.z, largest),
    };
    let length = q.length();
    if length > 1e-6 && length.is_finite() {
        q / length
    } else {
        Quat::IDENTITY
    }
}

/// Rotation from `a` to `b` in turns (rotation angle / 2π) along the shortest path: Houdini's
/// "rotations per frame", which its shader needs to interpolate rotations at all.
fn turns_between(a: Quat, b: Quat) -> f32 {
    // In f64 and through atan2: acos of a dot product near 1 loses the small angles.
    let to_f64 = |q: Quat| DQuat::from_xyzw(q.x.into(), q.y.into(), q.z.into(), q.w.into());
    let relative = to_f64(a).conjugate() * to_f64(b);
    let half_angle = DVec3::new(relative.x, relative.y, relative.z)
        .length()
        .atan2(relative.w.abs());
    (half_angle / std::f64::consts::PI) as f32
}

/// Checks the input and returns the unit rotations per piece and frame.
fn validate(pieces: &[RigidPiece], fps: f32) -> Result<Vec<Vec<Quat>>, VatError> {
    let first = pieces.first().ok_or(VatError::NoPieces)?;
    let frames = first.frames.len();
    if frames == 0 {
        return Err(VatError::NoFrames);
    }
    if !fps.is_finite() || fps <= 0.0 {
        return Err(VatError::InvalidFps(fps));
    }
    let mut rotations = Vec::with_capacity(pieces.len());
    for (p, piece) in pieces.iter().enumerate() {
        if piece.frames.len() != frames {
            return Err(VatError::FrameCountMismatch {
                piece: p,
                expected: frames,
                found: piece.frames.len(),
            });
        }
        if !piece.pivot.is_finite() {
            return Err(VatError::NonFinite {
                piece: p,
                what: "the rest pivot".into(),
            });
        }
        let mut unit = Vec::with_capacity(frames);
        for (f, frame) in piece.frames.iter().enumerate() {
            if !frame.position.is_finite() {
                return Err(VatError::NonFinite {
                    piece: p,
                    what: format!("the position at frame {f}"),
                });
            }
            if !frame.rotation.is_finite() {
                return Err(VatError::NonFinite {
                    piece: p,
                    what: format!("the rotation at frame {f}"),
                });
            }
            let length = frame.rotation.length();
            if !length.is_finite() || length <= 1e-6 {
                return Err(VatError::ZeroRotation { piece: p, frame: f });
            }
            unit.push(frame.rotation / length);
        }
        rotations.push(unit);
    }
    Ok(rotations)
}

/// Encodes rigid pieces into position and rotation textures plus sidecar.
///
/// Deterministic: the same input gives the same bytes.
pub fn encode_rigid_with(
    pieces: &[RigidPiece],
    fps: f32,
    format: VatFormat,
    options: &VatOptions,
) -> Result<VatTextures, VatError> {
    if options.max_texture_size == 0 {
        return Err(VatError::InvalidMaxSize(options.max_texture_size));
    }
    let space = options.space;
    let rest_pivots: Vec<Vec3> = pieces.iter().map(|p| p.pivot).collect();
    let converted: Vec<RigidPiece>;
    let pieces = if space == VatSpace::Gltf {
        pieces
    } else {
        converted = pieces_in_space(pieces, space);
        &converted
    };
    let rotations = validate(pieces, fps)?;
    let frames = rotations[0].len();
    let grid = Grid::new(pieces.len(), frames, options.max_texture_size)?;
    let (piece_count, frame_count) = texture_counts(pieces.len(), frames, &grid, options)?;
    let bounds = PositionBounds::of(pieces, format)?;
    let (position_texels, rotation_texels) = texels(pieces, &rotations, &grid, &bounds, format);
    let (position_bytes, rotation_bytes) =
        encode_textures(format, &grid, &position_texels, &rotation_texels)?;

    let extension = format.extension();
    let image = |bytes| VatImage {
        width: grid.width,
        height: grid.height,
        bytes,
        extension,
    };
    let piece_uv = (0..pieces.len())
        .map(|p| {
            let (x, row) = grid.cell(p);
            [
                (x as f32 + 0.5) / grid.width as f32,
                (row as f32 + 0.5) / grid.height as f32,
            ]
        })
        .collect();
    let pivot_uv = rest_pivots
        .iter()
        .map(|&pivot| space.pivot_channels(pivot))
        .collect();
    let sidecar = sidecar(
        format,
        fps,
        &grid,
        (piece_count, frame_count),
        &bounds,
        options,
    );
    tracing::debug!(
        "VAT rigid: {} pieces × {} frames → {}×{} {:?}",
        pieces.len(),
        frames,
        grid.width,
        grid.height,
        format
    );
    Ok(VatTextures {
        position: image(position_bytes),
        rotation: image(rotation_bytes),
        pivot: pivot_image(&grid, &rest_pivots, space),
        sidecar,
        piece_uv,
        pivot_uv,
    })
}

/// `pieces` (in glTF space) in `space`: pivots, positions and rotations converted.
fn pieces_in_space(pieces: &[RigidPiece], space: VatSpace) -> Vec<RigidPiece> {
    pieces
        .iter()
        .map(|p| RigidPiece {
            pivot: space.point(p.pivot),
            frames: p
                .frames
                .iter()
                .map(|f| RigidFrame {
                    position: space.point(f.position),
                    rotation: space.rotation(f.rotation),
                })
                .collect(),
        })
        .collect()
}

/// The piece and frame counts as the sidecar's `u32`s. Counts beyond u32 only arise with
/// absurd maxima; they are refused rather than truncated.
fn texture_counts(
    pieces: usize,
    frames: usize,
    grid: &Grid,
    options: &VatOptions,
) -> Result<(u32, u32), VatError> {
    match (u32::try_from(pieces), u32::try_from(frames)) {
        (Ok(p), Ok(f)) => Ok((p, f)),
        _ => Err(VatError::TooLarge {
            pieces,
            frames,
            width: u64::from(grid.width),
            height: u64::from(grid.height),
            max: options.max_texture_size,
        }),
    }
}

/// The bounds of the pivot trajectories: tight, and the whole-number ones the materials
/// decode PNG16 positions with.
struct PositionBounds {
    /// Smallest pivot position over every piece and frame, per axis.
    position_min: Vec3,
    /// Largest pivot position over every piece and frame, per axis.
    position_max: Vec3,
    /// `position_min` rounded down: the decode's lower bound.
    bound_min: Vec3,
    /// The decode's upper bound as the sidecar gives it: `position_max` rounded up, at least
    /// 1 above `bound_min`, plus 0.5 on z for raw (HDR) positions, Houdini's flag.
    material_bound_max: Vec3,
    /// The decode's range: the upper bound (without the flag) minus `bound_min`.
    range: Vec3,
}

impl PositionBounds {
    /// The bounds of `pieces`' positions; for EXR, refuses a position beyond half floats.
    fn of(pieces: &[RigidPiece], format: VatFormat) -> Result<PositionBounds, VatError> {
        // Tight bounds of the pivot trajectories, then the whole-number material bounds.
        let mut position_min = Vec3::splat(f32::INFINITY);
        let mut position_max = Vec3::splat(f32::NEG_INFINITY);
        for (p, piece) in pieces.iter().enumerate() {
            for (f, frame) in piece.frames.iter().enumerate() {
                position_min = position_min.min(frame.position);
                position_max = position_max.max(frame.position);
                if format == VatFormat::ExrHalf {
                    let largest = frame.position.abs().max_element();
                    if largest > f16::MAX.to_f32() {
                        return Err(VatError::OutOfHalfRange {
                            piece: p,
                            frame: f,
                            value: largest,
                        });
                    }
                }
            }
        }
        let bound_min = position_min.floor();
        let mut bound_max = position_max.ceil();
        for axis in 0..3 {
            if bound_max[axis] <= bound_min[axis] {
                bound_max[axis] = bound_min[axis] + 1.0;
            }
        }
        let range = bound_max - bound_min;
        if !range.is_finite() {
            return Err(VatError::RangeOverflow);
        }
        let mut material_bound_max = bound_max;
        if format.is_hdr() {
            // Houdini's "positions are raw" flag: frac(Bound Max Z) >= 0.5 (not used to decode EXR).
            material_bound_max.z += 0.5;
        }
        Ok(PositionBounds {
            position_min,
            position_max,
            bound_min,
            material_bound_max,
            range,
        })
    }
}

/// The position and rotation textures' texels as f32 RGBA in the texture's final meaning
/// (remapped for PNG16): per piece and frame, the pivot position with the dropped component
/// index, and the smallest-three rotation with the turns to the next frame.
fn texels(
    pieces: &[RigidPiece],
    rotations: &[Vec<Quat>],
    grid: &Grid,
    bounds: &PositionBounds,
    format: VatFormat,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let frames = rotations[0].len();
    let texels = grid.width as usize * grid.height as usize;
    let mut position_texels = vec![[0.0f32; 4]; texels];
    let hdr = format.is_hdr();
    // Unused texels: identity rotation (stored components 0, which PNG16 maps to 0.5).
    let unused = if hdr { 0.0 } else { 0.5 };
    let mut rotation_texels = vec![[unused; 4]; texels];
    for (p, piece) in pieces.iter().enumerate() {
        for (f, frame) in piece.frames.iter().enumerate() {
            let q = rotations[p][f];
            let next = rotations[p][(f + 1) % frames];
            let s3 = smallest_three(q);
            let turns = turns_between(q, next);
            let index = grid.texel(p, f);
            let alpha = f32::from(s3.dropped) / 4.0;
            if hdr {
                let v = frame.position;
                position_texels[index] = [v.x, v.y, v.z, alpha];
                rotation_texels[index] = [s3.kept[0], s3.kept[1], s3.kept[2], turns];
            } else {
                let t = ((frame.position - bounds.bound_min) / bounds.range)
                    .clamp(Vec3::ZERO, Vec3::ONE);
                position_texels[index] = [t.x, t.y, t.z, alpha];
                let k = s3.kept;
                rotation_texels[index] = [
                    k[0] * 0.5 + 0.5,
                    k[1] * 0.5 + 0.5,
                    k[2] * 0.5 + 0.5,
                    turns * 0.5 + 0.5,
                ];
            }
        }
    }
    (position_texels, rotation_texels)
}

/// The position and rotation texture files, in `format`.
fn encode_textures(
    format: VatFormat,
    grid: &Grid,
    position_texels: &[[f32; 4]],
    rotation_texels: &[[f32; 4]],
) -> Result<(Vec<u8>, Vec<u8>), VatError> {
    Ok(match format {
        VatFormat::ExrHalf => (
            write_exr_half(grid.width, grid.height, position_texels),
            write_exr_half(grid.width, grid.height, rotation_texels),
        ),
        VatFormat::Png16 => (
            write_png16(grid.width, grid.height, position_texels, true).map_err(|message| {
                VatError::Encode {
                    role: "position",
                    message,
                }
            })?,
            write_png16(grid.width, grid.height, rotation_texels, false).map_err(|message| {
                VatError::Encode {
                    role: "rotation",
                    message,
                }
            })?,
        ),
    })
}

/// The sidecar of textures of `grid` holding `counts` (pieces, frames) at `fps`.
fn sidecar(
    format: VatFormat,
    fps: f32,
    grid: &Grid,
    counts: (u32, u32),
    bounds: &PositionBounds,
    options: &VatOptions,
) -> VatSidecar {
    let (piece_count, frame_count) = counts;
    let frames = frame_count as usize;
    let extension = format.extension();
    let space = options.space;
    VatSidecar {
        layout: LAYOUT.to_string(),
        format,
        hdr: format.is_hdr(),
        frames: frame_count,
        fps,
        duration_s: frames as f32 / fps,
        pieces: piece_count,
        width: grid.width,
        height: grid.height,
        rows_per_frame: grid.rows_per_frame,
        row_order: ROW_ORDER.to_string(),
        textures: VatTextureFiles {
            position: format!("{}_pos.{extension}", options.file_stem),
            rotation: format!("{}_rot.{extension}", options.file_stem),
            pivot: Some(format!("{}_pivot.exr", options.file_stem)),
        },
        bound_min: bounds.bound_min.to_array(),
        bound_max: bounds.material_bound_max.to_array(),
        position_min: bounds.position_min.to_array(),
        position_max: bounds.position_max.to_array(),
        piece_uv_channel: PIECE_UV_CHANNEL.to_string(),
        pivot_channels: PIVOT_CHANNELS.map(str::to_string),
        rotation_encoding: ROTATION_ENCODING.to_string(),
        rest_pose: REST_POSE.to_string(),
        coordinate_system: space.coordinate_system().to_string(),
        version: SIDECAR_VERSION,
        space,
        start_s: options.start_s,
        clips: vec![VatClip {
            name: options.clip.clone(),
            start_s: options.start_s,
            duration_s: frames as f32 / fps,
            first_frame: 0,
            frames: frame_count,
        }],
    }
}

/// The pivot texture: the rest pivots (glTF space), as the pivot channels carry them (in
/// the data's `space`), at each piece's frame-0 texel; one frame's rows, EXR half.
fn pivot_image(grid: &Grid, rest_pivots: &[Vec3], space: VatSpace) -> VatImage {
    let mut pivot_texels =
        vec![[0.0f32, 0.0, 0.0, 1.0]; grid.width as usize * grid.rows_per_frame as usize];
    for (p, &pivot) in rest_pivots.iter().enumerate() {
        let q = space.point(pivot);
        pivot_texels[grid.texel(p, 0)] = [q.x, q.y, q.z, 1.0];
    }
    VatImage {
        width: grid.width,
        height: grid.rows_per_frame,
        bytes: write_exr_half(grid.width, grid.rows_per_frame, &pivot_texels),
        extension: "exr",
    }
}

/// 16-bit code of a [0, 1] value. The position alpha (dropped index / 4) rounds up so that
/// Houdini's `floor(alpha * 4)` recovers the index exactly.
fn unorm16(value: f32, round_up: bool) -> u16 {
    let scaled = value.clamp(0.0, 1.0) * 65535.0;
    let code = if round_up {
        scaled.ceil()
    } else {
        scaled.round()
    };
    code as u16
}

/// Writes RGBA texels ([0, 1]) as a 16-bit RGBA PNG.
fn write_png16(
    width: u32,
    height: u32,
    texels: &[[f32; 4]],
    alpha_is_index: bool,
) -> Result<Vec<u8>, String> {
    let mut samples = Vec::with_capacity(texels.len() * 4);
    for texel in texels {
        samples.push(unorm16(texel[0], false));
        samples.push(unorm16(texel[1], false));
        samples.push(unorm16(texel[2], false));
        samples.push(unorm16(texel[3], alpha_is_index));
    }
    let buffer = image::ImageBuffer::<image::Rgba<u16>, Vec<u16>>::from_raw(width, height, samples)
        .ok_or_else(|| "texel count does not match the size".to_string())?;
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        Cursor::new(&mut bytes),
        image::codecs::png::CompressionType::Default,
        image::codecs::png::FilterType::Adaptive,
    );
    image::DynamicImage::ImageRgba16(buffer)
        .write_with_encoder(encoder)
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Appends one EXR header attribute.
fn exr_attribute(out: &mut Vec<u8>, name: &str, kind: &str, value: &[u8]) {
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.extend_from_slice(kind.as_bytes());
    out.push(0);
    out.extend_from_slice(&(value.len() as i32).to_le_bytes());
    out.extend_from_slice(value);
}

/// Writes RGBA texels as an uncompressed single-part scanline OpenEXR of half floats
/// (channels A, B, G, R as the format requires them sorted; top row first).
pub(crate) fn write_exr_half(width: u32, height: u32, texels: &[[f32; 4]]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&20000630u32.to_le_bytes());
    out.extend_from_slice(&2u32.to_le_bytes()); // version 2, single-part scanline

    let mut channels = Vec::new();
    for name in ["A", "B", "G", "R"] {
        channels.extend_from_slice(name.as_bytes());
        channels.push(0);
        channels.extend_from_slice(&1i32.to_le_bytes()); // HALF
        channels.extend_from_slice(&[0, 0, 0, 0]); // pLinear + reserved
        channels.extend_from_slice(&1i32.to_le_bytes()); // x sampling
        channels.extend_from_slice(&1i32.to_le_bytes()); // y sampling
    }
    channels.push(0);
    let mut window = Vec::new();
    for v in [0i32, 0, width as i32 - 1, height as i32 - 1] {
        window.extend_from_slice(&v.to_le_bytes());
    }
    exr_attribute(&mut out, "channels", "chlist", &channels);
    exr_attribute(&mut out, "compression", "compression", &[0]);
    exr_attribute(&mut out, "dataWindow", "box2i", &window);
    exr_attribute(&mut out, "displayWindow", "box2i", &window);
    exr_attribute(&mut out, "lineOrder", "lineOrder", &[0]);
    exr_attribute(&mut out, "pixelAspectRatio", "float", &1.0f32.to_le_bytes());
    let mut center = Vec::new();
    center.extend_from_slice(&0.0f32.to_le_bytes());
    center.extend_from_slice(&0.0f32.to_le_bytes());
    exr_attribute(&mut out, "screenWindowCenter", "v2f", &center);
    exr_attribute(
        &mut out,
        "screenWindowWidth",
        "float",
        &1.0f32.to_le_bytes(),
    );
    out.push(0);

    let row_bytes = width as usize * 4 * 2;
    let chunk_bytes = 8 + row_bytes;
    let table_start = out.len();
    let first_chunk = table_start + 8 * height as usize;
    for y in 0..height as usize {
        out.extend_from_slice(&((first_chunk + y * chunk_bytes) as u64).to_le_bytes());
    }
    for y in 0..height as usize {
        out.extend_from_slice(&(y as i32).to_le_bytes());
        out.extend_from_slice(&(row_bytes as i32).to_le_bytes());
        let row = &texels[y * width as usize..(y + 1) * width as usize];
        for channel in [3usize, 2, 1, 0] {
            for texel in row {
                out.extend_from_slice(&f16::from_f32(texel[channel]).to_le_bytes());
            }
        }
    }
    out
}

/// Decoded texels of one texture as f32 RGBA in the texture's meaning (PNG16 → [0, 1]).
fn read_texels(
    bytes: &[u8],
    format: VatFormat,
    role: &'static str,
    width: u32,
    height: u32,
) -> Result<Vec<[f32; 4]>, VatError> {
    let error = |message: String| VatError::Decode { role, message };
    let image_format = match format {
        VatFormat::ExrHalf => image::ImageFormat::OpenExr,
        VatFormat::Png16 => image::ImageFormat::Png,
    };
    let decoded = image::load_from_memory_with_format(bytes, image_format)
        .map_err(|e| error(e.to_string()))?;
    if decoded.width() != width || decoded.height() != height {
        return Err(error(format!(
            "the image is {}×{}, the sidecar says {width}×{height}",
            decoded.width(),
            decoded.height()
        )));
    }
    let texels: Vec<[f32; 4]> = match format {
        VatFormat::Png16 => {
            let image::DynamicImage::ImageRgba16(buffer) = decoded else {
                return Err(error(format!(
                    "expected a 16-bit RGBA PNG, found {:?}",
                    decoded.color()
                )));
            };
            buffer
                .pixels()
                .map(|p| p.0.map(|v| f32::from(v) / 65535.0))
                .collect()
        }
        VatFormat::ExrHalf => decoded.to_rgba32f().pixels().map(|p| p.0).collect(),
    };
    if texels.iter().flatten().any(|v| !v.is_finite()) {
        return Err(error("the texture holds non-finite values".into()));
    }
    Ok(texels)
}

/// Checks the sidecar's own consistency and returns the grid it describes.
fn sidecar_grid(sidecar: &VatSidecar) -> Result<Grid, VatError> {
    let bad = |m: String| VatError::BadSidecar(m);
    if sidecar.layout != LAYOUT {
        return Err(bad(format!(
            "layout is {:?}, expected {LAYOUT:?}",
            sidecar.layout
        )));
    }
    if sidecar.hdr != sidecar.format.is_hdr() {
        return Err(bad(format!(
            "hdr = {} contradicts format {:?}",
            sidecar.hdr, sidecar.format
        )));
    }
    if sidecar.frames == 0 || sidecar.pieces == 0 {
        return Err(bad("frames and pieces must be at least 1".into()));
    }
    if sidecar.width == 0 || sidecar.rows_per_frame == 0 {
        return Err(bad("width and rows_per_frame must be at least 1".into()));
    }
    if u64::from(sidecar.width) * u64::from(sidecar.rows_per_frame) < u64::from(sidecar.pieces) {
        return Err(bad(format!(
            "{} pieces do not fit {} rows of {} texels",
            sidecar.pieces, sidecar.rows_per_frame, sidecar.width
        )));
    }
    if u64::from(sidecar.rows_per_frame) * u64::from(sidecar.frames) != u64::from(sidecar.height) {
        return Err(bad(format!(
            "height {} is not rows_per_frame {} × frames {}",
            sidecar.height, sidecar.rows_per_frame, sidecar.frames
        )));
    }
    if !sidecar.format.is_hdr() {
        for axis in 0..3 {
            let (lo, hi) = (sidecar.bound_min[axis], sidecar.bound_max[axis]);
            if !lo.is_finite() || !hi.is_finite() || hi < lo {
                return Err(bad(format!("bounds on axis {axis} are [{lo}, {hi}]")));
            }
        }
    }
    Ok(Grid {
        width: sidecar.width,
        rows_per_frame: sidecar.rows_per_frame,
        height: sidecar.height,
    })
}

/// Reads the encoded textures back into per-piece frames (for tests and for users' tools).
///
/// Returns `frames[piece][frame]`; rotations are unit quaternions with their largest component
/// positive (the stored sign).
pub fn decode_rigid(
    position: &[u8],
    rotation: &[u8],
    sidecar: &VatSidecar,
) -> Result<Vec<Vec<RigidFrame>>, VatError> {
    let grid = sidecar_grid(sidecar)?;
    let format = sidecar.format;
    let positions = read_texels(position, format, "position", grid.width, grid.height)?;
    let rotations = read_texels(rotation, format, "rotation", grid.width, grid.height)?;
    let bound_min = Vec3::from(sidecar.bound_min);
    let range = Vec3::from(sidecar.bound_max) - bound_min;

    let pieces = sidecar.pieces as usize;
    let frames = sidecar.frames as usize;
    let mut out = Vec::with_capacity(pieces);
    for piece in 0..pieces {
        let mut track = Vec::with_capacity(frames);
        for frame in 0..frames {
            let index = grid.texel(piece, frame);
            let (p, r) = (positions[index], rotations[index]);
            let (position, kept) = if format.is_hdr() {
                (Vec3::new(p[0], p[1], p[2]), [r[0], r[1], r[2]])
            } else {
                (
                    bound_min + Vec3::new(p[0], p[1], p[2]) * range,
                    [r[0], r[1], r[2]].map(|v| v * 2.0 - 1.0),
                )
            };
            let dropped = (p[3] * 4.0 + 0.5).floor().clamp(0.0, 3.0) as u8;
            track.push(RigidFrame {
                position,
                rotation: from_smallest_three(kept, dropped),
            });
        }
        out.push(track);
    }
    Ok(out)
}

/// Reads the pivot texture ([`VatTextureFiles::pivot`]) back: each piece's rest pivot, in the
/// sidecar's space (half-float precision).
pub fn decode_pivots(pivot: &[u8], sidecar: &VatSidecar) -> Result<Vec<Vec3>, VatError> {
    let grid = sidecar_grid(sidecar)?;
    let texels = read_texels(
        pivot,
        VatFormat::ExrHalf,
        "pivot",
        grid.width,
        grid.rows_per_frame,
    )?;
    Ok((0..sidecar.pieces as usize)
        .map(|p| {
            let t = texels[grid.texel(p, 0)];
            Vec3::new(t[0], t[1], t[2])
        })
        .collect())
}

/// Reads the rotation texture's alpha back: per piece and frame, the turns (rotation angle / 2π)
/// from that frame to the next (wrapping) — the value Houdini's shader interpolates with.
pub fn decode_turns_per_frame(
    rotation: &[u8],
    sidecar: &VatSidecar,
) -> Result<Vec<Vec<f32>>, VatError> {
    let grid = sidecar_grid(sidecar)?;
    let rotations = read_texels(
        rotation,
        sidecar.format,
        "rotation",
        grid.width,
        grid.height,
    )?;
    let decode = |a: f32| {
        if sidecar.hdr {
            a
        } else {
            (a * 2.0 - 1.0).abs()
        }
    };
    Ok((0..sidecar.pieces as usize)
        .map(|piece| {
            (0..sidecar.frames as usize)
                .map(|frame| decode(rotations[grid.texel(piece, frame)][3]))
                .collect()
        })
        .collect())
}

/// Shortest-path spherical interpolation exactly as the reference shaders compute it
/// (normalized lerp when the two rotations are within ~1.8°).
pub fn slerp_shortest(a: Quat, b: Quat, t: f32) -> Quat {
    let a4 = Vec4::from(a);
    let mut b4 = Vec4::from(b);
    let mut d = a4.dot(b4);
    if d < 0.0 {
        b4 = -b4;
        d = -d;
    }
    let blended = if d > 0.9995 {
        a4.lerp(b4, t)
    } else {
        let angle = d.acos();
        a4 * ((1.0 - t) * angle).sin() + b4 * (t * angle).sin()
    };
    Quat::from_vec4(blended.normalize())
}

/// The pose at a fractional, looping frame: positions lerp and rotations slerp between the two
/// nearest frames, the last frame blending into frame 0 — what the reference shaders compute.
/// `None` when `frames` is empty or `frame` is not finite.
pub fn sample_frame(frames: &[RigidFrame], frame: f32) -> Option<RigidFrame> {
    if frames.is_empty() || !frame.is_finite() {
        return None;
    }
    let count = frames.len() as f32;
    let wrapped = frame - count * (frame / count).floor();
    let f0 = wrapped.floor().min(count - 1.0);
    let t = wrapped - f0;
    let i0 = f0 as usize;
    let i1 = (i0 + 1) % frames.len();
    let (a, b) = (frames[i0], frames[i1]);
    Some(RigidFrame {
        position: a.position.lerp(b.position, t),
        rotation: slerp_shortest(a.rotation, b.rotation, t),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece(pivot: Vec3, frames: Vec<(Vec3, Quat)>) -> RigidPiece {
        RigidPiece {
            pivot,
            frames: frames
                .into_iter()
                .map(|(position, rotation)| RigidFrame { position, rotation })
                .collect(),
        }
    }

    #[test]
    fn smallest_three_drops_each_component_and_round_trips() {
        let cases = [
            (Quat::from_xyzw(0.1, 0.2, 0.3, 0.9).normalize(), 0),
            (Quat::from_xyzw(-0.9, 0.2, 0.3, 0.1).normalize(), 1),
            (Quat::from_xyzw(0.1, 0.9, -0.3, -0.2).normalize(), 2),
            (Quat::from_xyzw(0.1, 0.2, -0.9, 0.3).normalize(), 3),
        ];
        for (q, expected) in cases {
            let s3 = smallest_three(q);
            assert_eq!(s3.dropped, expected, "{q:?}");
            let back = from_smallest_three(s3.kept, s3.dropped);
            // Same rotation; the sign makes the dropped component positive.
            assert!(back.dot(q).abs() > 1.0 - 1e-6, "{q:?} -> {back:?}");
            let largest = [back.w, back.x, back.y, back.z][expected as usize];
            assert!(largest > 0.0);
        }
    }

    #[test]
    fn position_alpha_codes_floor_back_to_the_index() {
        for index in 0..4u8 {
            let code = unorm16(f32::from(index) / 4.0, true);
            let alpha = f32::from(code) / 65535.0;
            assert_eq!((alpha * 4.0).floor() as u8, index, "Houdini's floor(a * 4)");
            assert_eq!((alpha * 4.0 + 0.5).floor() as u8, index, "our rounding");
        }
    }

    #[test]
    fn grid_wraps_pieces_onto_rows_and_stacks_frames() {
        let grid = Grid::new(6, 2, 4).expect("fits");
        assert_eq!(
            grid,
            Grid {
                width: 4,
                rows_per_frame: 2,
                height: 4
            }
        );
        assert_eq!(grid.cell(5), (1, 1));
        assert_eq!(grid.texel(5, 0), 4 + 1);
        assert_eq!(grid.texel(5, 1), (2 + 1) * 4 + 1);
        assert!(matches!(
            Grid::new(6, 3, 4),
            Err(VatError::TooLarge { height: 6, .. })
        ));
    }

    #[test]
    fn exr_writer_is_read_back_by_the_image_crate() {
        let texels: Vec<[f32; 4]> = (0..6)
            .map(|i| {
                let i = i as f32;
                [i, -i * 0.5, 0.25 + i, 0.75]
            })
            .collect();
        let bytes = write_exr_half(3, 2, &texels);
        let back = read_texels(&bytes, VatFormat::ExrHalf, "test", 3, 2).expect("readable");
        assert_eq!(back, texels, "small values are exact in half floats");
    }

    #[test]
    fn encoding_is_deterministic_and_uvs_hit_texel_centres() {
        let pieces: Vec<RigidPiece> = (0..3)
            .map(|i| {
                let i = i as f32;
                piece(
                    Vec3::new(i, 1.0, 0.0),
                    vec![
                        (Vec3::new(i, 1.0, 0.0), Quat::IDENTITY),
                        (Vec3::new(i, 1.5, 0.2), Quat::from_rotation_y(0.3 * i)),
                    ],
                )
            })
            .collect();
        for format in [VatFormat::ExrHalf, VatFormat::Png16] {
            let a = encode_rigid(&pieces, 30.0, format).expect("encodes");
            let b = encode_rigid(&pieces, 30.0, format).expect("encodes");
            assert_eq!(a, b);
            assert_eq!((a.position.width, a.position.height), (3, 2));
            assert_eq!(a.piece_uv[1], [0.5, 0.25]);
            assert_eq!(a.pivot_uv[2], [[2.0, 0.0], [1.0, 0.0]]);
            assert_eq!(a.sidecar.bound_min, [0.0, 1.0, 0.0]);
        }
    }

    #[test]
    fn sample_frame_wraps_the_loop() {
        let frames = [
            RigidFrame {
                position: Vec3::ZERO,
                rotation: Quat::IDENTITY,
            },
            RigidFrame {
                position: Vec3::X,
                rotation: Quat::from_rotation_z(0.5),
            },
        ];
        let mid = sample_frame(&frames, 1.5).expect("finite");
        assert!((mid.position - Vec3::splat(0.0).lerp(Vec3::X, 0.5)).length() < 1e-6);
        assert!(mid.rotation.angle_between(Quat::from_rotation_z(0.25)) < 1e-4);
        let wrapped = sample_frame(&frames, -0.5).expect("finite");
        assert!((wrapped.position - mid.position).length() < 1e-6);
        assert!(sample_frame(&frames, f32::NAN).is_none());
        assert!(sample_frame(&[], 0.0).is_none());
    }
}
