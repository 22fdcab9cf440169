//! `frond render`: one frame of a tree at a time of its clip, from an orbit camera, as PNG.

use anyhow::{Context, Result, bail};
use frond_render::{Camera, Frame, Projection, Renderer, TreeParts, tree_scene};
use frond_scene::Tree;
use glam::Vec3;

/// What to render.
#[derive(Clone, Debug)]
pub struct RenderRequest {
    /// Clip to pose the tree with (None: the first clip; the rest pose without clips).
    pub clip: Option<String>,
    /// Time in seconds on the clip's keys, at which the tree is posed.
    pub time: f32,
    /// Camera azimuth in degrees around the vertical axis: 0 looks from +Z, 90 from +X.
    pub azimuth_deg: f32,
    /// Camera elevation in degrees above the horizon (negative looks from below).
    pub elevation_deg: f32,
    /// Camera distance in multiples of the framing distance (1 = the tree fills the view).
    pub zoom: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Orthographic projection instead of the 40° vertical field of view perspective.
    pub orthographic: bool,
    /// Which triangles to draw: all, wood only or foliage only.
    pub parts: TreeParts,
}

impl Default for RenderRequest {
    /// The first clip at t = 0, seen from +Z slightly above, perspective, 256×256, all parts.
    fn default() -> Self {
        RenderRequest {
            clip: None,
            time: 0.0,
            azimuth_deg: 0.0,
            elevation_deg: 10.0,
            zoom: 1.0,
            width: 256,
            height: 256,
            orthographic: false,
            parts: TreeParts::All,
        }
    }
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("size '{s}' is not WxH"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("size '{s}': bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("size '{s}': bad height"))?;
    if w == 0 || h == 0 {
        bail!("size '{s}' must be at least 1x1");
    }
    Ok((w, h))
}

/// Renders the tree as requested. The camera frames the rest-pose bounds so frames at
/// different times line up.
pub fn render_tree(renderer: &Renderer, tree: &Tree, req: &RenderRequest) -> Result<Frame> {
    let clip = match &req.clip {
        Some(name) => Some(
            tree.clip_index(Some(name))
                .with_context(|| format!("{}: no clip named '{name}'", tree.source.display()))?,
        ),
        None => tree.clip_index(None),
    };
    let scene = tree_scene(tree, clip, req.time, req.parts);
    let projection = if req.orthographic {
        Projection::Orthographic { half_height: 1.0 }
    } else {
        Projection::Perspective { fov_y_deg: 40.0 }
    };
    let mut camera = Camera::framing(
        Vec3::from(tree.bounds.min),
        Vec3::from(tree.bounds.max),
        req.azimuth_deg,
        req.elevation_deg,
        projection,
    );
    camera.distance *= req.zoom;
    if let Projection::Orthographic { half_height } = &mut camera.projection {
        *half_height *= req.zoom;
    }
    Ok(renderer.render(&scene, &camera, req.width, req.height, [0.0, 0.0, 0.0, 0.0])?)
}

/// Encodes a frame as PNG bytes.
pub fn frame_png(frame: &Frame) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(
            &frame.rgba,
            frame.width,
            frame.height,
            image::ExtendedColorType::Rgba8,
        )
        .context("encoding PNG")?;
    Ok(out)
}
