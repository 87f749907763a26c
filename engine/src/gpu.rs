//! The headless wgpu context: adapter choice, features and limits.

use crate::error::{Error, Result};

/// How to install a software Vulkan driver when no adapter exists.
pub const NO_ADAPTER_HELP: &str = "no GPU adapter found: lightgraph runs on Vulkan. On a machine without a GPU, install Mesa's \
software Vulkan driver (lavapipe): `sudo apt-get install mesa-vulkan-drivers libvulkan1` (Debian/Ubuntu), \
or run `cargo xtask test`, which installs it when it can";

/// A device and queue, with what the adapter offers.
pub struct Gpu {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// The queue.
    pub queue: wgpu::Queue,
    /// Adapter name, backend and type.
    pub info: wgpu::AdapterInfo,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// Limits of the device.
    pub limits: wgpu::Limits,
}

fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let ty = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    let backend = if info.backend == wgpu::Backend::Vulkan { 0 } else { 1 };
    (backend, ty)
}

fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::GL | wgpu::Backends::METAL | wgpu::Backends::DX12;
    wgpu::Instance::new(desc)
}

/// All adapters wgpu can see, best first.
pub fn adapters() -> Vec<wgpu::AdapterInfo> {
    let inst = instance();
    let mut infos: Vec<wgpu::AdapterInfo> = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| a.get_info())
        .collect();
    infos.sort_by_key(rank);
    infos
}

/// Features lightgraph uses when the adapter has them.
pub fn wanted_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::SHADER_FLOAT32_ATOMIC
        | wgpu::Features::SUBGROUP
}

impl Gpu {
    /// Opens the best adapter, or the first whose name contains `name` (case-insensitive).
    pub fn new(name: Option<&str>) -> Result<Gpu> {
        let inst = instance();
        let mut candidates = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
        if candidates.is_empty() {
            return Err(Error::Gpu(NO_ADAPTER_HELP.to_string()));
        }
        candidates.sort_by_key(|a| rank(&a.get_info()));
        let adapter = match name {
            Some(n) => {
                let lower = n.to_lowercase();
                let names: Vec<String> = candidates.iter().map(|a| a.get_info().name).collect();
                let pos = candidates
                    .iter()
                    .position(|a| a.get_info().name.to_lowercase().contains(&lower))
                    .ok_or_else(|| Error::Gpu(format!("no adapter matches '{n}'; available: {}", names.join(", "))))?;
                candidates.swap_remove(pos)
            }
            None => candidates.remove(0),
        };
        let info = adapter.get_info();
        let features = adapter.features() & wanted_features();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lightgraph"),
            required_features: features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::Gpu(format!("cannot open adapter '{}': {e}", info.name)))?;
        Ok(Gpu {
            adapter,
            device,
            queue,
            info,
            features,
            limits,
        })
    }

    /// naga capabilities matching the device's features.
    pub fn capabilities(&self) -> naga::valid::Capabilities {
        use naga::valid::Capabilities as C;
        let mut caps = C::empty();
        if self.features.contains(wgpu::Features::SHADER_FLOAT32_ATOMIC) {
            caps |= C::SHADER_FLOAT32_ATOMIC;
        }
        if self.features.contains(wgpu::Features::SUBGROUP) {
            caps |= C::SUBGROUP;
        }
        caps
    }

    /// A one-line description: name, backend, type, driver.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name, self.info.backend, self.info.device_type, self.info.driver, self.info.driver_info
        )
    }

    /// Compilation target for this device.
    pub fn target(&self) -> crate::program::Target {
        crate::program::Target {
            capabilities: self.capabilities(),
            max_binding_bytes: self.limits.max_storage_buffer_binding_size,
            max_workgroups_per_dimension: self.limits.max_compute_workgroups_per_dimension,
            ..Default::default()
        }
    }

    /// Waits until the queue is idle.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Gpu(format!("device poll failed: {e}")))
    }
}
