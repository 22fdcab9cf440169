//! GPU state shared by every render: shader, bind group layouts, the pipelines (back-face
//! culled and double-sided, for colour and for normal output), the sampler and a white
//! fallback texture.

use crate::batch::Vertex;
use crate::scene::DrawAlpha;
use crate::srgb::{SRGB_LINEAR, linear_to_srgb};
use frond_scene::Wrap;
use rayon::prelude::*;

/// Colour target format; readback bytes are therefore sRGB-encoded.
pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Normal target format: linear, so `n * 0.5 + 0.5` is stored without sRGB encoding.
pub(crate) const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Coverage target format: 255 where a fragment survived, 0 elsewhere.
pub(crate) const COVERAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// Depth buffer format.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Direction toward the fixed world-space light, normalize(0.4, 1.0, 0.3): from above,
/// slightly right and front.
/// Lit surfaces get `0.6 + 0.4 * |dot(normal, LIGHT_DIRECTION)|`.
pub const LIGHT_DIRECTION: [f32; 3] = [0.357_771, 0.894_427, 0.268_328];

/// Uniform block of bind group 0.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Globals {
    pub view_proj: [[f32; 4]; 4],
    pub light_dir: [f32; 4],
}

/// Uniform block of bind group 1.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct MaterialUniform {
    pub base_color: [f32; 4],
    /// x: alpha cutoff, negative for opaque and blended; y: 1 for blended (glTF BLEND).
    pub params: [f32; 4],
}

/// Pipelines and layouts created once per [`crate::Renderer`].
pub(crate) struct Pipelines {
    pub globals_layout: wgpu::BindGroupLayout,
    pub material_layout: wgpu::BindGroupLayout,
    pub culled: wgpu::RenderPipeline,
    pub double_sided: wgpu::RenderPipeline,
    /// Normal output ([`crate::Output::Normal`]), back faces culled.
    pub normal_culled: wgpu::RenderPipeline,
    /// Normal output, both faces drawn.
    pub normal_double_sided: wgpu::RenderPipeline,
    /// Colour output of blended materials ([`crate::DrawAlpha::Blend`]), back faces culled:
    /// colour blended over what is behind, coverage composed as `1 − Π(1 − α)`, no depth
    /// written (as engines draw transparent surfaces).
    pub blend_culled: wgpu::RenderPipeline,
    /// Colour output of blended materials, both faces drawn.
    pub blend_double_sided: wgpu::RenderPipeline,
    /// One sampler per pair of wrap modes (u, v), indexed by [`wrap_index`]; linear filtering
    /// with mipmaps.
    pub samplers: Vec<wgpu::Sampler>,
    pub white: wgpu::TextureView,
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Pipelines {
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Pipelines {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("frond-render shader"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frond-render globals"),
            entries: &[uniform_entry(0)],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frond-render material"),
            entries: &[
                uniform_entry(0),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("frond-render layout"),
            bind_group_layouts: &[Some(&globals_layout), Some(&material_layout)],
            immediate_size: 0,
        });

        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4, 2 => Float32x2];
        let vertex_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<Vertex>() as wgpu::BufferAddress,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        })];
        // A blended fragment's coverage α composes over the target's: α + c·(1 − α).
        let composed = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let targets = |format: wgpu::TextureFormat, blended: bool| {
            [
                Some(wgpu::ColorTargetState {
                    format,
                    blend: blended.then_some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                }),
                Some(wgpu::ColorTargetState {
                    format: COVERAGE_FORMAT,
                    blend: blended.then_some(wgpu::BlendState {
                        color: composed,
                        alpha: composed,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                }),
            ]
        };
        let make = |label: &str,
                    cull_mode: Option<wgpu::Face>,
                    fragment_entry: &str,
                    (format, blended): (wgpu::TextureFormat, bool)| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &vertex_buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(!blended),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fragment_entry),
                    compilation_options: Default::default(),
                    targets: &targets(format, blended),
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let back = Some(wgpu::Face::Back);
        let (colour, normal, blend) = (
            (COLOR_FORMAT, false),
            (NORMAL_FORMAT, false),
            (COLOR_FORMAT, true),
        );
        let culled = make("frond-render culled", back, "fs_main", colour);
        let double_sided = make("frond-render double-sided", None, "fs_main", colour);
        let normal_culled = make("frond-render normal culled", back, "fs_normal", normal);
        let normal_double_sided = make("frond-render normal double", None, "fs_normal", normal);
        let blend_culled = make("frond-render blend culled", back, "fs_main", blend);
        let blend_double_sided = make("frond-render blend double", None, "fs_main", blend);

        let samplers = WRAPS
            .iter()
            .flat_map(|&u| WRAPS.map(|v| (u, v)))
            .map(|(u, v)| {
                device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("frond-render sampler"),
                    address_mode_u: address_mode(u),
                    address_mode_v: address_mode(v),
                    address_mode_w: wgpu::AddressMode::Repeat,
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                })
            })
            .collect();
        let white = upload_texture(device, queue, "frond-render white", 1, 1, &[255; 4], None);

        Pipelines {
            globals_layout,
            material_layout,
            culled,
            double_sided,
            normal_culled,
            normal_double_sided,
            blend_culled,
            blend_double_sided,
            samplers,
            white,
        }
    }
}

/// The next mip level: 2×2 box filter, colour averaged in linear light weighted by alpha (so
/// transparent texels lend no colour), alpha averaged — minified alpha-tested textures then
/// cover what their texels cover on average instead of aliasing.
fn downsample(width: u32, height: u32, rgba: &[u8]) -> (u32, u32, Vec<u8>) {
    let (w2, h2) = ((width / 2).max(1), (height / 2).max(1));
    let mut out = vec![0u8; (w2 * h2 * 4) as usize];
    // Both ways by table ([`crate::srgb`]): four texels' three channels decoded and three
    // encoded an output texel made `powf` most of a large texture's chain.
    let linear = &*SRGB_LINEAR;
    // Rows in parallel (a 1024² leaf map's first level was most of a bake's preparation).
    (out.par_chunks_mut(w2 as usize * 4).enumerate()).for_each(|(y, row)| {
        for x in 0..w2 {
            let mut acc = [0.0f32; 3];
            let mut weight = 0.0f32;
            let block = block(width, height, x, y as u32);
            for &(sx, sy) in &block {
                let i = ((sy * width + sx) * 4) as usize;
                let a = rgba[i + 3] as f32 / 255.0;
                for k in 0..3 {
                    acc[k] += linear[rgba[i + k] as usize] * a.max(1e-3);
                }
                weight += a.max(1e-3);
            }
            let o = (x * 4) as usize;
            for k in 0..3 {
                row[o + k] = linear_to_srgb(acc[k] / weight);
            }
            row[o + 3] =
                mean_alpha(block.map(|(sx, sy)| rgba[((sy * width + sx) * 4 + 3) as usize]));
        }
    });
    (w2, h2, out)
}

/// The 2×2 block of texel `(x, y)` of the next level, edge texels repeated.
fn block(width: u32, height: u32, x: u32, y: u32) -> [(u32, u32); 4] {
    [(0, 0), (1, 0), (0, 1), (1, 1)]
        .map(|(dx, dy)| ((2 * x + dx).min(width - 1), (2 * y + dy).min(height - 1)))
}

/// The next level's alpha of a 2×2 block: the mean, rounded.
fn mean_alpha(a: [u8; 4]) -> u8 {
    let sum: f32 = a.iter().map(|&v| v as f32 / 255.0).sum();
    (sum / 4.0 * 255.0 + 0.5) as u8
}

/// [`downsample`] of an image's alpha alone (one byte a texel): the same alpha, without the
/// colour work.
fn downsample_alpha(width: u32, height: u32, alpha: &[u8]) -> (u32, u32, Vec<u8>) {
    let (w2, h2) = ((width / 2).max(1), (height / 2).max(1));
    let out = (0..h2)
        .flat_map(|y| (0..w2).map(move |x| (x, y)))
        .map(|(x, y)| {
            mean_alpha(block(width, height, x, y).map(|(sx, sy)| alpha[(sy * width + sx) as usize]))
        })
        .collect();
    (w2, h2, out)
}

/// Fraction of texels whose alpha passes a 0.5 alpha test; texels of `stride` bytes, alpha
/// last (4: RGBA, 1: alpha alone).
fn alpha_coverage(data: &[u8], stride: usize) -> f32 {
    let n = data.len() / stride;
    if n == 0 {
        return 0.0;
    }
    data.chunks_exact(stride)
        .filter(|p| p[stride - 1] >= 128)
        .count() as f32
        / n as f32
}

/// A mip level whose alpha is rescaled so that as many texels pass the 0.5 alpha test as in
/// level 0 (coverage-preserving mipmaps): averaged alpha alone makes leaves vanish at a
/// distance. The threshold is put halfway between the weakest texel that should pass and the
/// strongest that should not, so neither lands on the test's edge.
fn preserve_coverage(data: &[u8], stride: usize, target: f32) -> Vec<u8> {
    let mut out = data.to_vec();
    let n = data.len() / stride;
    let want = (target * n as f32).round() as usize;
    if n == 0 || want == 0 {
        return out;
    }
    let mut histogram = [0usize; 256];
    for p in data.chunks_exact(stride) {
        histogram[p[stride - 1] as usize] += 1;
    }
    // Walk down from opaque until `want` texels are included.
    let (mut count, mut v_in) = (0usize, 0usize);
    for v in (0..256).rev() {
        count += histogram[v];
        if count >= want {
            v_in = v;
            break;
        }
    }
    let v_out = (0..v_in).rev().find(|&v| histogram[v] > 0).unwrap_or(0);
    let threshold = 0.5 * (v_in + v_out) as f32;
    if threshold <= 0.0 {
        return out;
    }
    let scale = 127.5 / threshold;
    for p in out.chunks_exact_mut(stride) {
        p[stride - 1] = (p[stride - 1] as f32 * scale).round().min(255.0) as u8;
    }
    out
}

/// The full mip chain the renderer samples an RGBA8 sRGB image with, level 0 first, each level
/// `(width, height, rgba)`: box-filtered (`downsample`), alpha rescaled to keep level 0's
/// alpha-tested coverage (`preserve_coverage`). Public so that CPU models of what the
/// renderer shows (card thinning's coverage) sample the same levels.
pub fn mip_chain(width: u32, height: u32, rgba: &[u8]) -> Vec<(u32, u32, Vec<u8>)> {
    chain(width, height, rgba, 4, downsample, true)
}

/// The mip chain of a blended (glTF BLEND) RGBA8 sRGB image: [`mip_chain`]'s box filter with
/// alpha averaged and not rescaled. A blended texel's alpha is the fraction of it covered, so
/// the mean of four is the fraction of the larger texel covered, at every level.
pub fn blend_mip_chain(width: u32, height: u32, rgba: &[u8]) -> Vec<(u32, u32, Vec<u8>)> {
    chain(width, height, rgba, 4, downsample, false)
}

/// The alpha of every level of [`mip_chain`], computed from the image's alpha alone (one byte
/// a texel): the same bytes as the chain's alpha channel, without its colour work (the colour levels of
/// a large leaf map are slow to make, and a coverage render reads none of them).
pub fn alpha_mip_chain(width: u32, height: u32, alpha: &[u8]) -> Vec<(u32, u32, Vec<u8>)> {
    chain(width, height, alpha, 1, downsample_alpha, true)
}

/// The alpha of every level of [`blend_mip_chain`], from the image's alpha alone.
pub fn blend_alpha_mip_chain(width: u32, height: u32, alpha: &[u8]) -> Vec<(u32, u32, Vec<u8>)> {
    chain(width, height, alpha, 1, downsample_alpha, false)
}

/// One mip level: width, height, texels.
type Level = (u32, u32, Vec<u8>);

/// The chain of texels of `stride` bytes (alpha last), each level from the previous one's
/// plain `down`sample: alpha rescaled to keep level 0's alpha-tested coverage where
/// `preserve`, averaged as it is otherwise (blended alpha).
fn chain(
    width: u32,
    height: u32,
    data: &[u8],
    stride: usize,
    down: fn(u32, u32, &[u8]) -> Level,
    preserve: bool,
) -> Vec<Level> {
    let levels = 32 - width.max(height).max(1).leading_zeros();
    let coverage0 = alpha_coverage(data, stride);
    let mut out = vec![(width, height, data.to_vec())];
    let (mut w, mut h, mut level) = (width, height, data.to_vec());
    for _ in 1..levels {
        (w, h, level) = down(w, h, &level);
        let kept = if preserve {
            preserve_coverage(&level, stride, coverage0)
        } else {
            level.clone()
        };
        out.push((w, h, kept));
    }
    out
}

/// The full chain of 2×2 box-filtered levels (edge texels repeated, rounded up), for linear
/// data such as normal maps, whose texels are no colour to average in linear light nor alpha to
/// keep coverage of. Shared by the CPU rasteriser's normal maps and the KTX2 writer's.
pub fn linear_mip_chain(width: u32, height: u32, rgba: Vec<u8>) -> Vec<Level> {
    let mut out = vec![(width, height, rgba)];
    while let Some((w, h, data)) = out.last().filter(|l| l.0 > 1 || l.1 > 1) {
        let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
        let mut next = vec![0u8; (w2 * h2 * 4) as usize];
        for y in 0..h2 {
            for x in 0..w2 {
                for k in 0..4 {
                    let sum: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .map(|&(dx, dy)| {
                            let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                            u32::from(data[((sy * w + sx) * 4 + k) as usize])
                        })
                        .sum();
                    next[((y * w2 + x) * 4 + k) as usize] = sum.div_ceil(4).min(255) as u8;
                }
            }
        }
        out.push((w2, h2, next));
    }
    out
}

/// Which mip chain a texture is drawn with, by the CPU rasteriser and the wgpu path alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Mips {
    /// The coverage-preserving chain an alpha test reads ([`mip_chain`]): what an opaque or
    /// alpha-tested material samples.
    Tested,
    /// The box-filtered chain a blended material reads ([`blend_mip_chain`]), whose alpha
    /// stays each texel's covered fraction.
    Blended,
}

impl Mips {
    /// The chain a material of alpha mode `alpha` reads.
    pub(crate) fn of(alpha: DrawAlpha) -> Mips {
        match alpha {
            DrawAlpha::Blend => Mips::Blended,
            DrawAlpha::Opaque | DrawAlpha::Mask(_) => Mips::Tested,
        }
    }

    /// The chain of a texture that needs `self` once a material of alpha mode `alpha` samples
    /// it too: blended only while every material blends (an alpha test keeps its chain).
    pub(crate) fn with(self, alpha: DrawAlpha) -> Mips {
        if self == Mips::Blended && Mips::of(alpha) == Mips::Blended {
            Mips::Blended
        } else {
            Mips::Tested
        }
    }

    /// This chain of an RGBA8 sRGB image.
    pub(crate) fn rgba(self, width: u32, height: u32, rgba: &[u8]) -> Vec<Level> {
        match self {
            Mips::Tested => mip_chain(width, height, rgba),
            Mips::Blended => blend_mip_chain(width, height, rgba),
        }
    }

    /// This chain of an image's alpha alone (one byte a texel): the chain's alpha channel.
    pub(crate) fn alpha(self, width: u32, height: u32, alpha: &[u8]) -> Vec<Level> {
        match self {
            Mips::Tested => alpha_mip_chain(width, height, alpha),
            Mips::Blended => blend_alpha_mip_chain(width, height, alpha),
        }
    }
}

/// Uploads a validated RGBA8 sRGB image as a sampled texture with the mip chain `mips` (level 0
/// alone when `None`).
pub(crate) fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    width: u32,
    height: u32,
    rgba: &[u8],
    mips: Option<Mips>,
) -> wgpu::TextureView {
    let chain = match mips {
        None => vec![(width, height, rgba.to_vec())],
        Some(mips) => mips.rgba(width, height, rgba),
    };
    let levels = chain.len() as u32;
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (level, (w, h, upload)) in chain.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            upload,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(*h),
            },
            wgpu::Extent3d {
                width: *w,
                height: *h,
                depth_or_array_layers: 1,
            },
        );
    }
    texture.create_view(&Default::default())
}

/// The wrap modes, in the order of [`Pipelines::samplers`] (u major).
const WRAPS: [Wrap; 3] = [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat];

/// The index in [`Pipelines::samplers`] of the sampler wrapping as `wrap` (u, v).
pub(crate) fn wrap_index(wrap: [Wrap; 2]) -> usize {
    let at = |w: Wrap| WRAPS.iter().position(|&x| x == w).unwrap_or(0);
    at(wrap[0]) * WRAPS.len() + at(wrap[1])
}

fn address_mode(wrap: Wrap) -> wgpu::AddressMode {
    match wrap {
        Wrap::Repeat => wgpu::AddressMode::Repeat,
        Wrap::ClampToEdge => wgpu::AddressMode::ClampToEdge,
        Wrap::MirroredRepeat => wgpu::AddressMode::MirrorRepeat,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_alpha_chain_is_the_full_chains_alpha() {
        // An odd-sized image with varied alpha (a hash of the texel), so every level keeps
        // edge texels and rescales its alpha.
        let (w, h) = (37u32, 22u32);
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let v = i.wrapping_mul(2_654_435_761) >> 24;
                [v as u8, (v * 3) as u8, 200, (v % 256) as u8]
            })
            .collect();
        let alpha: Vec<u8> = rgba.chunks_exact(4).map(|p| p[3]).collect();
        let full = mip_chain(w, h, &rgba);
        let alone = alpha_mip_chain(w, h, &alpha);
        assert_eq!(full.len(), 6);
        assert_eq!(full.len(), alone.len());
        for ((fw, fh, f), (aw, ah, a)) in full.iter().zip(&alone) {
            assert_eq!((fw, fh), (aw, ah));
            let f_alpha: Vec<u8> = f.chunks_exact(4).map(|p| p[3]).collect();
            assert_eq!(&f_alpha, a, "level {fw}x{fh}");
        }
    }
}
