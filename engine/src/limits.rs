//! Limits and shapes every stage shares: the target a program compiles for, the most
//! parameters a frame record holds, its WGSL binding, and the operator kernels' workgroup and
//! scan tile.

/// Most parameters a graph may declare (a frame record is 256 bytes, 16 of them taken).
pub const MAX_PARAMETERS: usize = 60;

/// The frame record's declaration: group 1, bound with a dynamic offset per chunk.
pub const FRAME_BINDING: &str = "@group(1) @binding(0) var<uniform> frame: Frame;\n";

/// Threads per workgroup of the operator kernels.
pub const WORKGROUP: u32 = 256;
/// Elements each thread of a scan handles by default (a tile of 4096 elements).
pub const SCAN_ITEMS: u32 = 16;

/// Device properties that shape compilation.
#[derive(Debug, Clone)]
pub struct Target {
    /// naga capabilities of the device.
    pub capabilities: naga::valid::Capabilities,
    /// Largest storage buffer binding, in bytes.
    pub max_binding_bytes: u64,
    /// Largest buffer, in bytes (the most one arena of shared memory may take).
    pub max_buffer_bytes: u64,
    /// Alignment of storage buffer binding offsets.
    pub storage_offset_alignment: u64,
    /// Largest number of workgroups per dispatch dimension.
    pub max_workgroups_per_dimension: u32,
    /// Cap on the iterations of in-kernel loops (a guard against hangs).
    pub max_loop_iterations: u32,
    /// Whether transient buffers whose lifetimes do not overlap share memory.
    pub alias_transients: bool,
    /// Elements each thread of a scan operator handles (a tile is 256 times as many).
    pub scan_items: u32,
    /// Most elements each thread of a sort ranked by subgroup ballots ranks (fewer where the
    /// workgroup memory is short). 8 by default: on an H100, 10^7 keys sort fastest so
    /// (docs/performance.md, "Radix sort ranked by subgroup ballots").
    pub sort_items: u32,
    /// Whether persistent threads take at most their share of the items, ceil(items /
    /// threads), each: for drivers that cap the loop iterations of an invocation (llvmpipe:
    /// 65535, shared by all its loops), where a thread taking items until none is left passes
    /// the cap whenever the others start late (a loaded CPU). Off on GPUs, where threads that
    /// take more items balance the load.
    pub fair_shares: bool,
    /// Fewest invocations a subgroup of the device may have (4 when unknown).
    pub subgroup_min_size: u32,
    /// Most invocations a subgroup of the device may have (128 when unknown).
    pub subgroup_max_size: u32,
    /// Workgroup memory a kernel may declare, in bytes.
    pub workgroup_bytes: u32,
}

impl Default for Target {
    fn default() -> Self {
        Target {
            capabilities: naga::valid::Capabilities::all(),
            max_binding_bytes: 128 << 20,
            max_buffer_bytes: 1 << 31,
            storage_offset_alignment: 256,
            max_workgroups_per_dimension: 65535,
            max_loop_iterations: 1 << 16,
            alias_transients: true,
            scan_items: SCAN_ITEMS,
            sort_items: 8,
            fair_shares: false,
            subgroup_min_size: 4,
            subgroup_max_size: 128,
            workgroup_bytes: 16 << 10,
        }
    }
}

impl Target {
    /// Whether the target has subgroup operations.
    pub fn subgroups(&self) -> bool {
        self.capabilities.contains(naga::valid::Capabilities::SUBGROUP)
    }

    /// The same target without subgroup operations (the portable kernels).
    pub fn without_subgroups(mut self) -> Target {
        self.capabilities.remove(naga::valid::Capabilities::SUBGROUP);
        self
    }
}
