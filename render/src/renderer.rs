//! The renderer: owns the device and pipelines and turns a [`DrawScene`] into a [`Frame`].

use std::collections::BTreeMap;

use wgpu::util::DeviceExt;

use crate::adapter::{self, Gpu};
use crate::batch::{self, Batch};
use crate::camera::Camera;
use crate::error::RenderError;
use crate::frame::Frame;
use crate::pipeline::{
    self, COLOR_FORMAT, COVERAGE_FORMAT, DEPTH_FORMAT, Globals, LIGHT_DIRECTION, MaterialUniform,
    Mips, NORMAL_FORMAT, Pipelines,
};
use crate::readback::{self, Readback};
use crate::scene::{DrawAlpha, DrawMaterial, DrawScene};

/// Where and how one render draws: matrix, image size, clear colour and output kind.
struct Target {
    view_proj: glam::Mat4,
    width: u32,
    height: u32,
    background: [f32; 4],
    output: Output,
}

/// Largest single vertex or index buffer we create, even where the device allows
/// more: keeps allocations moderate (about 7M vertices per buffer).
const BUFFER_CAP: u64 = 256 << 20;

/// What the colour image of a render holds.
///
/// Baking billboards needs both the look of the geometry and its normals
/// (improved-billboard-cloud §4 items 4 and 8: diffuse texture and normal map).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Output {
    /// Shaded colour, sRGB-encoded RGBA8 (what [`Renderer::render`] produces).
    #[default]
    Color,
    /// The unit world-space normal of the side facing the viewer (flipped on back faces of
    /// double-sided materials), stored linearly as `rgb = n * 0.5 + 0.5`, alpha 255. Meshes
    /// without normals use their triangles' face normals. Alpha test and coverage are the
    /// same as for [`Output::Color`].
    Normal,
}

/// An offscreen renderer, reusable for many renders and shareable across threads.
///
/// Creating one opens a device (slow on CPU adapters); keep it around.
pub struct Renderer {
    gpu: Gpu,
    pipelines: Pipelines,
    info: String,
    /// Uploaded textures by (content hash, mip-mapped): baking draws the same source textures
    /// in hundreds of tiles, and building a mip chain each time dominated its cost.
    texture_cache:
        std::sync::Mutex<std::collections::HashMap<(u64, Option<Mips>), wgpu::TextureView>>,
}

/// Textures kept uploaded at most; the cache is emptied when it would grow past this.
const TEXTURE_CACHE_LIMIT: usize = 32;

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("adapter", &self.info)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Opens the best available adapter (GPU first, then CPU rasterisers such as
    /// lavapipe or llvmpipe) and builds the pipelines. Honours `WGPU_BACKEND` and
    /// `WGPU_ADAPTER_NAME`.
    pub fn new() -> Result<Renderer, RenderError> {
        let gpu = adapter::open()?;
        // Errors inside `render` are caught by error scopes; anything else is logged
        // instead of wgpu's default panic.
        gpu.device
            .on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
                tracing::error!("uncaptured wgpu error: {e}");
            }));
        let info = adapter::describe(&gpu.adapter.get_info());
        let pipelines = Pipelines::new(&gpu.device, &gpu.queue);
        Ok(Renderer {
            gpu,
            pipelines,
            info,
            texture_cache: Default::default(),
        })
    }

    /// Short description of the adapter in use, e.g. "llvmpipe (LLVM 15) [Gl, Cpu]".
    pub fn adapter_info(&self) -> String {
        self.info.clone()
    }

    /// Full wgpu adapter information.
    pub fn wgpu_adapter_info(&self) -> wgpu::AdapterInfo {
        self.gpu.adapter.get_info()
    }

    /// Whether rendering happens on a CPU rasteriser (llvmpipe, lavapipe, WARP).
    pub fn is_cpu(&self) -> bool {
        self.gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// Largest image width or height this device can render.
    pub fn max_dimension(&self) -> u32 {
        self.gpu.device.limits().max_texture_dimension_2d
    }

    /// The wgpu instance (e.g. to enumerate adapters for diagnostics).
    pub fn instance(&self) -> &wgpu::Instance {
        &self.gpu.instance
    }

    /// Renders `scene` from `camera` into a `width` x `height` image cleared to
    /// `background` (linear RGBA, stored sRGB-encoded).
    ///
    /// Inputs are validated first; bad indices, sizes or references return an error
    /// without touching the GPU.
    pub fn render(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        width: u32,
        height: u32,
        background: [f32; 4],
    ) -> Result<Frame, RenderError> {
        self.render_with_buffer_cap(scene, camera, width, height, background, BUFFER_CAP, false)
    }

    /// Like [`Renderer::render`], but textures are mip-mapped (averaged alpha rescaled per
    /// level so as many texels pass the alpha test as at full size) and filtered trilinearly,
    /// as engines draw them. The coverage metric uses it so that both the original's minified
    /// leaf textures and a billboard atlas are pre-filtered alike; point-sampling the
    /// original's textures made the metric measure their aliasing. Not the default, so plain renders show exactly the file's texels.
    pub fn render_mipmapped(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        width: u32,
        height: u32,
        background: [f32; 4],
    ) -> Result<Frame, RenderError> {
        self.render_with_buffer_cap(scene, camera, width, height, background, BUFFER_CAP, true)
    }

    fn check_size(&self, width: u32, height: u32) -> Result<(), RenderError> {
        let limits = self.gpu.device.limits();
        let invalid = |reason: String| {
            Err(RenderError::InvalidSize {
                width,
                height,
                reason,
            })
        };
        if width == 0 || height == 0 {
            return invalid("width and height must be at least 1".into());
        }
        let max = limits.max_texture_dimension_2d;
        if width > max || height > max {
            return invalid(format!("the device renders at most {max} pixels per side"));
        }
        let readback = readback::padded_row_bytes(width, 4) * u64::from(height);
        if readback > limits.max_buffer_size {
            return invalid(format!(
                "the readback buffer ({readback} bytes) exceeds the device's max_buffer_size ({})",
                limits.max_buffer_size
            ));
        }
        Ok(())
    }

    /// Renders `scene` through an explicit `view_proj` matrix (world to wgpu clip space:
    /// NDC x and y in [-1, 1] with +y up, z in [0, 1]; keeping the geometry inside the
    /// depth range is the caller's job) into a `width` x `height` image.
    ///
    /// Baking needs cameras the orbit [`Camera`] cannot express, e.g. an orthographic
    /// view whose window is exactly a billboard quad (animated-billboard-clouds §2.4,
    /// texturing steps 3 and 4). With [`Output::Color`] the image is what
    /// [`Renderer::render`] would draw with that matrix and `background` is stored
    /// sRGB-encoded; with [`Output::Normal`] it holds normals (see [`Output`]) and
    /// `background` is stored as is (linear). Textures are mip-mapped as in
    /// [`Renderer::render_mipmapped`]: baking samples source leaf textures several times
    /// smaller than they are, and pre-filtering them keeps the baked alpha from aliasing.
    /// Inputs are validated before any GPU work.
    pub fn render_view(
        &self,
        scene: &DrawScene,
        view_proj: glam::Mat4,
        width: u32,
        height: u32,
        background: [f32; 4],
        output: Output,
    ) -> Result<Frame, RenderError> {
        self.check_size(width, height)?;
        if !view_proj.is_finite() {
            return Err(RenderError::InvalidCamera(
                "the view-projection matrix has a non-finite entry".into(),
            ));
        }
        self.draw(
            scene, view_proj, width, height, background, output, BUFFER_CAP, true,
        )
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "a draw is defined by scene, target, camera and pass options, all needed here"
    )]
    pub(crate) fn render_with_buffer_cap(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        width: u32,
        height: u32,
        background: [f32; 4],
        buffer_cap: u64,
        mipmaps: bool,
    ) -> Result<Frame, RenderError> {
        self.check_size(width, height)?;
        camera.validate()?;
        let aspect = width as f32 / height as f32;
        let view_proj = match scene.bounds() {
            Some((min, max)) => camera.view_proj_for_bounds(aspect, min, max),
            None => camera.view_proj(aspect),
        };
        self.draw(
            scene,
            view_proj,
            width,
            height,
            background,
            Output::Color,
            buffer_cap,
            mipmaps,
        )
    }

    /// Validates the scene, draws it and reads both targets back. The size was checked.
    #[expect(
        clippy::too_many_arguments,
        reason = "a draw is defined by scene, target, camera and pass options, all needed here"
    )]
    fn draw(
        &self,
        scene: &DrawScene,
        view_proj: glam::Mat4,
        width: u32,
        height: u32,
        background: [f32; 4],
        output: Output,
        buffer_cap: u64,
        mipmaps: bool,
    ) -> Result<Frame, RenderError> {
        let limits = self.gpu.device.limits();
        scene.validate(limits.max_texture_dimension_2d)?;
        let batches = batch::build_batches(
            scene,
            buffer_cap.min(limits.max_buffer_size),
            output == Output::Normal,
        );

        let device = &self.gpu.device;
        let oom_scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation_scope = device.push_error_scope(wgpu::ErrorFilter::Validation);

        let target = Target {
            view_proj,
            width,
            height,
            background,
            output,
        };
        let readbacks = self.encode_and_submit(scene, &target, &batches, mipmaps);

        let validation = pollster::block_on(validation_scope.pop());
        let oom = pollster::block_on(oom_scope.pop());
        if let Some(e) = validation.or(oom) {
            return Err(RenderError::Gpu(e.to_string()));
        }

        let mut images = Readback::read_all(device, &readbacks)?.into_iter();
        let (Some(rgba), Some(coverage)) = (images.next(), images.next()) else {
            return Err(RenderError::Readback("missing readback image".into()));
        };
        Ok(Frame {
            width,
            height,
            rgba,
            coverage: coverage.iter().map(|&c| c >= 128).collect(),
            coverage_alpha: coverage,
        })
    }

    /// Records and submits the render pass and the copies of both targets: the targets made,
    /// the globals, materials and batches uploaded, the batches drawn, and the targets copied
    /// out for reading back.
    fn encode_and_submit(
        &self,
        scene: &DrawScene,
        target: &Target,
        batches: &[Batch],
        mipmaps: bool,
    ) -> [Readback; 2] {
        let device = &self.gpu.device;
        let p = &self.pipelines;
        let &Target {
            view_proj,
            width,
            height,
            background,
            output,
        } = target;
        let (color_format, culled, double_sided) = match output {
            Output::Color => (COLOR_FORMAT, &p.culled, &p.double_sided),
            Output::Normal => (NORMAL_FORMAT, &p.normal_culled, &p.normal_double_sided),
        };
        let attachments = Attachments::new(device, width, height, color_format);
        let globals_group = self.globals_group(view_proj);
        let material_groups = self.material_groups(scene, batches, mipmaps, output);
        let gpu_batches = upload_batches(device, batches);

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frond-render"),
        });
        {
            let mut pass = attachments.begin_pass(&mut encoder, background);
            pass.set_bind_group(0, &globals_group, &[]);
            // Blended surfaces after the rest, as engines draw transparent ones; a normal
            // render tests them at ½ with the rest.
            let blended = |m: usize| draws_blended(&scene.materials[m], output);
            for (pipelines, pass_blended) in [
                ([culled, double_sided], false),
                ([&p.blend_culled, &p.blend_double_sided], true),
            ] {
                draw_batches(
                    &mut pass,
                    scene,
                    &gpu_batches,
                    &material_groups,
                    pipelines,
                    |m| blended(m) == pass_blended,
                );
            }
        }
        let readbacks = [
            Readback::record(device, &mut encoder, &attachments.color, 4),
            Readback::record(device, &mut encoder, &attachments.coverage, 1),
        ];
        self.gpu.queue.submit([encoder.finish()]);
        readbacks
    }

    /// The bind group of the render's globals: `view_proj` and the light's direction
    /// ([`LIGHT_DIRECTION`]).
    fn globals_group(&self, view_proj: glam::Mat4) -> wgpu::BindGroup {
        let device = &self.gpu.device;
        let [lx, ly, lz] = LIGHT_DIRECTION;
        let globals = Globals {
            view_proj: view_proj.to_cols_array_2d(),
            light_dir: [lx, ly, lz, 0.0],
        };
        let globals_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frond-render globals"),
            contents: bytemuck::bytes_of(&globals),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frond-render globals"),
            layout: &self.pipelines.globals_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals_buffer.as_entire_binding(),
            }],
        })
    }

    /// The uploaded view of `tex`, from the cache when the same pixels were uploaded before.
    fn cached_texture(
        &self,
        tex: &crate::scene::DrawTexture,
        mips: Option<Mips>,
    ) -> wgpu::TextureView {
        use std::hash::{BuildHasher, Hash, Hasher};
        let mut h = foldhash::quality::FixedState::with_seed(0).build_hasher();
        (tex.width, tex.height).hash(&mut h);
        tex.rgba.hash(&mut h);
        let key = (h.finish(), mips);
        let mut cache = match self.texture_cache.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        };
        if let Some(view) = cache.get(&key) {
            return view.clone();
        }
        let view = pipeline::upload_texture(
            &self.gpu.device,
            &self.gpu.queue,
            "frond-render base color",
            tex.width,
            tex.height,
            &tex.rgba,
            mips,
        );
        if cache.len() >= TEXTURE_CACHE_LIMIT {
            cache.clear();
        }
        cache.insert(key, view.clone());
        view
    }

    /// One bind group per material that some batch draws with; textures are uploaded
    /// once each.
    fn material_groups(
        &self,
        scene: &DrawScene,
        batches: &[Batch],
        mipmaps: bool,
        output: Output,
    ) -> BTreeMap<usize, wgpu::BindGroup> {
        let device = &self.gpu.device;
        let p = &self.pipelines;
        let used: std::collections::BTreeSet<usize> = batches
            .iter()
            .flat_map(|b| b.draws.iter().map(|d| d.material))
            .collect();
        let mut textures: BTreeMap<(usize, Option<Mips>), wgpu::TextureView> = BTreeMap::new();
        let mut groups = BTreeMap::new();
        for m in used {
            let material = &scene.materials[m];
            // A blended material's colour render blends, its mips box-filtered; a normal
            // render tests it at ½ as every renderer that cannot blend does.
            let blended = draws_blended(material, output);
            let mips = mipmaps.then_some(if blended { Mips::Blended } else { Mips::Tested });
            let view = match material.texture {
                Some(t) => textures.entry((t, mips)).or_insert_with(|| {
                    let tex = &scene.textures[t];
                    self.cached_texture(tex, mips)
                }),
                None => &p.white,
            };
            let params = if blended {
                [-1.0, 1.0, 0.0, 0.0]
            } else {
                [material.alpha.test_cutoff().unwrap_or(-1.0), 0.0, 0.0, 0.0]
            };
            let uniform = MaterialUniform {
                base_color: material.base_color,
                params,
            };
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frond-render material"),
                contents: bytemuck::bytes_of(&uniform),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frond-render material"),
                layout: &p.material_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::Sampler(
                            &p.samplers[crate::pipeline::wrap_index(material.wrap)],
                        ),
                    },
                ],
            });
            groups.insert(m, group);
        }
        groups
    }
}

/// The targets one render draws into: colour (or normals), coverage and depth, with their
/// views.
struct Attachments {
    /// The colour (or normal) image, copied out after the pass.
    color: wgpu::Texture,
    /// The coverage mask, copied out after the pass.
    coverage: wgpu::Texture,
    /// The depth buffer, held until the render is submitted.
    _depth: wgpu::Texture,
    /// View of `color`.
    color_view: wgpu::TextureView,
    /// View of `coverage`.
    coverage_view: wgpu::TextureView,
    /// View of the depth buffer (discarded after the pass).
    depth_view: wgpu::TextureView,
}

impl Attachments {
    /// The targets of a `width`×`height` render whose colour image has `color_format`.
    fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        color_format: wgpu::TextureFormat,
    ) -> Attachments {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let target = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let color = target("frond-render color", color_format, attach);
        let coverage = target("frond-render coverage", COVERAGE_FORMAT, attach);
        let depth = target(
            "frond-render depth",
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let color_view = color.create_view(&Default::default());
        let coverage_view = coverage.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        Attachments {
            color,
            coverage,
            _depth: depth,
            color_view,
            coverage_view,
            depth_view,
        }
    }

    /// The render pass over these targets, colour cleared to `background`, coverage to
    /// transparent and depth to 1.
    fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        background: [f32; 4],
    ) -> wgpu::RenderPass<'e> {
        let [r, g, b, a] = background.map(f64::from);
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("frond-render pass"),
            color_attachments: &[
                Some(wgpu::RenderPassColorAttachment {
                    view: &self.color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                        store: wgpu::StoreOp::Store,
                    },
                }),
                Some(wgpu::RenderPassColorAttachment {
                    view: &self.coverage_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                }),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// Each batch's vertices and indices uploaded, beside the batch.
fn upload_batches<'b>(
    device: &wgpu::Device,
    batches: &'b [Batch],
) -> Vec<(wgpu::Buffer, wgpu::Buffer, &'b Batch)> {
    batches
        .iter()
        .map(|b| {
            let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frond-render vertices"),
                contents: bytemuck::cast_slice(&b.vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
            let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("frond-render indices"),
                contents: bytemuck::cast_slice(&b.indices),
                usage: wgpu::BufferUsages::INDEX,
            });
            (vertices, indices, b)
        })
        .collect()
}

/// Whether a render of `output` draws `material` blended: colour renders of BLEND materials
/// (normal renders test them at ½, [`DrawAlpha::test_cutoff`]).
fn draws_blended(material: &DrawMaterial, output: Output) -> bool {
    output == Output::Color && material.alpha == DrawAlpha::Blend
}

/// Every draw of the uploaded `batches` whose material `drawn` accepts recorded into `pass`,
/// each with its material's bind group (`material_groups`) and the pipeline of its sidedness
/// (`[culled, double_sided]`); a draw whose material has no group is skipped.
fn draw_batches(
    pass: &mut wgpu::RenderPass<'_>,
    scene: &DrawScene,
    batches: &[(wgpu::Buffer, wgpu::Buffer, &Batch)],
    material_groups: &BTreeMap<usize, wgpu::BindGroup>,
    [culled, double_sided]: [&wgpu::RenderPipeline; 2],
    drawn: impl Fn(usize) -> bool,
) {
    for (vertices, indices, batch) in batches {
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        for draw in batch.draws.iter().filter(|d| drawn(d.material)) {
            let Some(group) = material_groups.get(&draw.material) else {
                continue;
            };
            pass.set_pipeline(if scene.materials[draw.material].double_sided {
                double_sided
            } else {
                culled
            });
            pass.set_bind_group(1, group, &[]);
            pass.draw_indexed(
                draw.first_index..draw.first_index + draw.index_count,
                0,
                0..1,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DrawMaterial, DrawMesh, Projection};
    use glam::Vec3;

    /// Splitting meshes across many small buffers must not change the image.
    #[test]
    fn split_buffers_render_identically() {
        let r = Renderer::new().unwrap_or_else(|e| panic!("no renderer: {e}"));
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for k in 0..40u32 {
            let (s, c) = (k as f32 * 0.157).sin_cos();
            positions.extend([
                [0.0, 0.0, 0.0],
                [c, s, 0.1],
                [c * 0.9 - s * 0.2, s * 0.9 + c * 0.2, -0.1],
            ]);
            indices.extend([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        let scene = DrawScene {
            meshes: vec![DrawMesh {
                positions,
                indices,
                ..Default::default()
            }],
            materials: vec![DrawMaterial {
                double_sided: true,
                ..DrawMaterial::opaque([0.2, 0.7, 0.3, 1.0])
            }],
            textures: vec![],
        };
        let camera = Camera::framing(
            Vec3::splat(-1.0),
            Vec3::splat(1.0),
            10.0,
            10.0,
            Projection::Perspective { fov_y_deg: 50.0 },
        );
        let whole = r.render(&scene, &camera, 48, 48, [0.0; 4]).expect("render");
        let cap = 10 * size_of::<crate::batch::Vertex>() as u64;
        let split = r
            .render_with_buffer_cap(&scene, &camera, 48, 48, [0.0; 4], cap, false)
            .expect("render");
        assert!(whole.covered_count() > 100);
        assert_eq!(whole, split);
    }
}
