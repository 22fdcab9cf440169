//! A compute pass for running reference shaders in tests: one float texture, one storage
//! buffer of queries in, one of answers out. Any adapter with compute shaders will do
//! (llvmpipe and lavapipe qualify); without one the caller skips with a message.

use wgpu::util::DeviceExt;

/// A device and queue that can run compute shaders.
pub struct Compute {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

/// Opens any adapter with compute shaders, or None (printing why).
pub fn open_compute(label: &str) -> Option<Compute> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = match pollster::block_on(instance.request_adapter(&Default::default())) {
        Ok(a) => a,
        Err(e) => {
            println!("SKIPPED: no graphics adapter to run {label} on ({e})");
            return None;
        }
    };
    if !adapter
        .get_downlevel_capabilities()
        .flags
        .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
    {
        println!(
            "SKIPPED: adapter {} has no compute shaders",
            adapter.get_info().name
        );
        return None;
    }
    println!("running {label} on {}", adapter.get_info().name);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some(label),
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .expect("the adapter opens a device");
    Some(Compute { device, queue })
}

/// Runs `main` of `source` (64 invocations a workgroup, one per query) with an RGBA32F
/// texture at binding 0 (`width`×`height` texels), `queries` at 1 and `answer_bytes` of
/// answers at 2; returns the answers.
#[expect(
    clippy::too_many_arguments,
    reason = "a compute dispatch is defined by that many pieces (shader, bindings, sizes)"
)]
pub fn run_compute(
    gpu: &Compute,
    source: &str,
    texels: &[f32],
    width: u32,
    height: u32,
    queries: &[u8],
    count: u32,
    answer_bytes: u64,
) -> Vec<u8> {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("reference + harness"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("coefficients"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(width * 16),
            rows_per_image: Some(height),
        },
        size,
    );
    let query_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("queries"),
        contents: queries,
        usage: wgpu::BufferUsages::STORAGE,
    });
    let (answers, readback) = answer_buffers(device, answer_bytes);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("reference"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let view = texture.create_view(&Default::default());
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("reference"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: query_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: answers.as_entire_binding(),
            },
        ],
    });
    dispatch_and_read(gpu, &pipeline, &bind_group, count, &answers, &readback)
}

/// A storage buffer for `bytes` of answers and a mappable one to read them back into.
pub fn answer_buffers(device: &wgpu::Device, bytes: u64) -> (wgpu::Buffer, wgpu::Buffer) {
    let answers = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("answers"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    (answers, readback)
}

/// Dispatches `count` invocations (64 a workgroup) of `pipeline` with `bind_group`, copies
/// `answers` into `readback` and returns its bytes.
pub fn dispatch_and_read(
    gpu: &Compute,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    count: u32,
    answers: &wgpu::Buffer,
    readback: &wgpu::Buffer,
) -> Vec<u8> {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(count.div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(answers, 0, readback, 0, answers.size());
    gpu.queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    readback.map_async(wgpu::MapMode::Read, .., move |result| {
        let _ = sender.send(result);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("the device finishes");
    receiver
        .recv()
        .expect("map callback ran")
        .expect("readback maps");
    let view = readback.get_mapped_range(..).expect("mapped");
    let out = view.to_vec();
    drop(view);
    readback.unmap();
    out
}

// Each test binary compiles this module on its own and uses only part of it; the unnamed
// constant names every helper once, which rustc's dead-code pass counts as a use (no lint
// exception needed; see tests/common/mod.rs at the workspace root).
const _: () = {
    let _ = (open_compute, run_compute, answer_buffers, dispatch_and_read);
};
