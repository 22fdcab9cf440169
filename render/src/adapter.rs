//! Picks a graphics adapter (real GPU first, CPU rasterisers as fallback) and opens
//! a device on it.

use std::cmp::Reverse;

use wgpu::{Backend, DeviceType};

use crate::error::RenderError;

/// An opened device with the instance and adapter it came from.
pub(crate) struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

/// Lower is better: discrete GPUs first, CPU rasterisers last.
fn device_rank(device_type: DeviceType) -> u8 {
    match device_type {
        DeviceType::DiscreteGpu => 0,
        DeviceType::IntegratedGpu => 1,
        DeviceType::VirtualGpu => 2,
        DeviceType::Other => 3,
        DeviceType::Cpu => 4,
    }
}

/// Lower is better: native modern APIs before GL (lavapipe beats llvmpipe-on-GL).
fn backend_rank(backend: Backend) -> u8 {
    match backend {
        Backend::Vulkan | Backend::Metal | Backend::Dx12 => 0,
        Backend::Gl => 1,
        _ => 2,
    }
}

/// "Vulkan, Metal, Dx12, GL" style list of the backends in `backends`.
fn backend_names(backends: wgpu::Backends) -> String {
    let known = [
        (wgpu::Backends::VULKAN, "Vulkan"),
        (wgpu::Backends::METAL, "Metal"),
        (wgpu::Backends::DX12, "Dx12"),
        (wgpu::Backends::GL, "GL"),
        (wgpu::Backends::BROWSER_WEBGPU, "WebGPU"),
    ];
    let names: Vec<&str> = known
        .iter()
        .filter(|(flag, _)| backends.contains(*flag))
        .map(|(_, name)| *name)
        .collect();
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// Short human-readable adapter description, e.g. "llvmpipe (LLVM 15) [Gl, Cpu]".
pub(crate) fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} [{:?}, {:?}]", info.name, info.backend, info.device_type)
}

/// Opens a device on the best adapter. Honours `WGPU_BACKEND` (which backends to
/// search) and `WGPU_ADAPTER_NAME` (prefer adapters whose name contains it).
pub(crate) fn open() -> Result<Gpu, RenderError> {
    let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    let backends = desc.backends;
    let instance = wgpu::Instance::new(desc);
    let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));

    let wanted_name = std::env::var("WGPU_ADAPTER_NAME")
        .ok()
        .map(|n| n.to_lowercase())
        .filter(|n| !n.is_empty());
    adapters.sort_by_key(|a| {
        let info = a.get_info();
        let name_match = wanted_name
            .as_ref()
            .is_some_and(|n| info.name.to_lowercase().contains(n));
        (
            Reverse(name_match),
            device_rank(info.device_type),
            backend_rank(info.backend),
        )
    });
    for adapter in &adapters {
        tracing::debug!("found graphics adapter {}", describe(&adapter.get_info()));
    }

    if adapters.is_empty() {
        let hint = if std::env::var_os("WGPU_BACKEND").is_some() {
            "; WGPU_BACKEND is set and limits the search, unset it to try all backends".to_string()
        } else {
            String::new()
        };
        return Err(RenderError::NoAdapter {
            backends: backend_names(backends),
            hint,
        });
    }

    let mut failures = Vec::new();
    for adapter in adapters {
        let info = adapter.get_info();
        let device_desc = wgpu::DeviceDescriptor {
            label: Some("frond-render"),
            // The adapter's own limits: large textures and buffers where available.
            required_limits: adapter.limits(),
            ..Default::default()
        };
        match pollster::block_on(adapter.request_device(&device_desc)) {
            Ok((device, queue)) => {
                tracing::info!(
                    "frond-render using adapter {} (driver: {} {})",
                    describe(&info),
                    info.driver,
                    info.driver_info
                );
                return Ok(Gpu {
                    instance,
                    adapter,
                    device,
                    queue,
                });
            }
            Err(e) => {
                tracing::warn!("adapter {} refused a device: {e}", describe(&info));
                failures.push(format!("{}: {e}", describe(&info)));
            }
        }
    }
    Err(RenderError::DeviceCreation(failures.join("; ")))
}
