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

/// What tells a physical GPU apart: its PCI bus id where the backend gives one, else its
/// name and PCI vendor and device ids (identical GPUs without a bus id then look alike).
fn identity(info: &wgpu::AdapterInfo) -> String {
    if info.device_pci_bus_id.is_empty() {
        format!("{} {:04x}:{:04x}", info.name, info.vendor, info.device)
    } else {
        info.device_pci_bus_id.clone()
    }
}

/// Each GPU wgpu can see, once (through its best backend: Vulkan lists a GPU once per
/// driver, and other backends list it again), best first: the order of adapter indices.
fn distinct_adapters() -> Vec<wgpu::Adapter> {
    let inst = instance();
    let mut all = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
    all.sort_by_key(|a| rank(&a.get_info()));
    let mut seen = Vec::new();
    all.retain(|a| {
        let id = identity(&a.get_info());
        let new = !seen.contains(&id);
        seen.push(id);
        new
    });
    all
}

/// Each GPU wgpu can see, once, best first (index `i` is adapter `i` of `--adapter`).
pub fn adapters() -> Vec<wgpu::AdapterInfo> {
    distinct_adapters().iter().map(|a| a.get_info()).collect()
}

/// Picks an adapter of `candidates` (best first) by `selector`: its index, its PCI bus id,
/// or text its name contains (case-insensitive).
fn select(mut candidates: Vec<wgpu::Adapter>, selector: &str) -> Result<wgpu::Adapter> {
    let infos: Vec<wgpu::AdapterInfo> = candidates.iter().map(|a| a.get_info()).collect();
    let lower = selector.to_lowercase();
    let pos = match selector.parse::<usize>() {
        Ok(i) => (i < candidates.len()).then_some(i),
        Err(_) => infos
            .iter()
            .position(|i| !i.device_pci_bus_id.is_empty() && i.device_pci_bus_id.eq_ignore_ascii_case(selector))
            .or_else(|| infos.iter().position(|i| i.name.to_lowercase().contains(&lower))),
    };
    let listed: Vec<String> = infos.iter().enumerate().map(|(k, i)| describe_adapter(k, i)).collect();
    let pos = pos.ok_or_else(|| {
        Error::Gpu(format!(
            "no adapter matches '{selector}' (an index, a PCI bus id or part of a name); available: {}",
            listed.join("; ")
        ))
    })?;
    Ok(candidates.swap_remove(pos))
}

/// One line on adapter `index`: index, name, PCI bus id, backend, type, driver.
pub fn describe_adapter(index: usize, info: &wgpu::AdapterInfo) -> String {
    let bus = if info.device_pci_bus_id.is_empty() {
        String::new()
    } else {
        format!(" [{}]", info.device_pci_bus_id)
    };
    format!(
        "{index}: {}{bus} ({:?}, {:?}, {})",
        info.name, info.backend, info.device_type, info.driver
    )
}

/// Features lightgraph uses when the adapter has them.
pub fn wanted_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::SHADER_FLOAT32_ATOMIC
        | wgpu::Features::SUBGROUP
}

impl Gpu {
    /// Opens the best adapter, or the one `selector` names: its index in [`adapters`], its
    /// PCI bus id, or text its name contains (case-insensitive). Each call opens a device of
    /// its own, also on an adapter already open.
    pub fn new(selector: Option<&str>) -> Result<Gpu> {
        let mut candidates = distinct_adapters();
        if candidates.is_empty() {
            return Err(Error::Gpu(NO_ADAPTER_HELP.to_string()));
        }
        let adapter = match selector {
            Some(s) => select(candidates, s)?,
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
    pub fn target(&self) -> crate::limits::Target {
        crate::limits::Target {
            capabilities: self.capabilities(),
            max_binding_bytes: self.limits.max_storage_buffer_binding_size,
            max_workgroups_per_dimension: self.limits.max_compute_workgroups_per_dimension,
            fair_shares: self.caps_invocation_loops(),
            // Below llvmpipe's cap on an invocation's iterations (an item's loop and the
            // loops inside it count against it), so the engine's own cap is met first.
            max_loop_iterations: if self.caps_invocation_loops() { 1 << 14 } else { 1 << 16 },
            subgroup_min_size: self.info.subgroup_min_size,
            subgroup_max_size: self.info.subgroup_max_size,
            workgroup_bytes: self.limits.max_compute_workgroup_storage_size,
            ..Default::default()
        }
    }

    /// Whether the adapter is a CPU (lavapipe), whose "GPU" work shares the host's cores.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Whether the driver caps the loop iterations of a shader invocation: llvmpipe (lavapipe)
    /// gives each invocation 65535 iterations over all its loops and then ends every loop.
    pub fn caps_invocation_loops(&self) -> bool {
        self.info.driver == "llvmpipe" || self.info.name.starts_with("llvmpipe")
    }

    /// Waits until the queue is idle.
    pub fn wait(&self) -> Result<()> {
        self.poll(wgpu::PollType::wait_indefinitely())
    }

    /// Blocks until `submission` has run (later submissions may still be running) and its
    /// callbacks (buffer maps) have been called.
    pub fn wait_for(&self, submission: wgpu::SubmissionIndex) -> Result<()> {
        self.poll(wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        })
    }

    fn poll(&self, poll: wgpu::PollType) -> Result<()> {
        self.device
            .poll(poll)
            .map(|_| ())
            .map_err(|e| Error::Gpu(format!("device poll failed: {e}")))
    }
}
