//! The engine's own small kernels: committing a queue or a compaction boundary into indirect
//! dispatch arguments, counting a GPU-counted phase's chunk, resetting and moving control
//! words, and folding per-chunk counters into 64-bit totals.

/// The kernel that commits a queue (the items emitted since the last commit become the
/// consumer's count, clamped to the capacity) and turns the count into indirect dispatch
/// arguments.
pub struct ArgsKernel<'a> {
    /// Entry point name.
    pub name: &'a str,
    /// Binding of the control words.
    pub control_binding: u32,
    /// Binding of the indirect arguments.
    pub args_binding: u32,
    /// Control word the consumer reads its count from.
    pub count_word: u32,
    /// Control word the producers append to.
    pub append_word: u32,
    /// Queue capacity.
    pub capacity: u64,
    /// First of the three argument words.
    pub args_offset: u32,
    /// Workgroup size of the consumer kernel.
    pub workgroup: u32,
    /// Most workgroups per dispatch dimension.
    pub max_groups: u32,
}

impl ArgsKernel<'_> {
    /// The WGSL module.
    pub fn wgsl(&self) -> String {
        let ArgsKernel {
            name,
            control_binding,
            args_binding,
            count_word,
            append_word,
            capacity,
            args_offset,
            workgroup,
            max_groups,
        } = self;
        format!(
            "@group(0) @binding({control_binding}) var<storage, read_write> lg_control: array<u32>;
@group(0) @binding({args_binding}) var<storage, read_write> lg_args: array<u32>;
@compute @workgroup_size(1)
fn {name}() {{
    let n = min(lg_control[{append_word}], {capacity}u);
    lg_control[{count_word}] = n;
    lg_control[{append_word}] = 0u;
    let groups = (n + {workgroup}u - 1u) / {workgroup}u;
    let x = min(groups, {max_groups}u);
    lg_args[{args_offset}] = x;
    lg_args[{args_offset} + 1u] = select(1u, (groups + x - 1u) / x, x > 0u);
    lg_args[{args_offset} + 2u] = 1u;
}}
"
        )
    }
}

/// The kernel that commits a compaction boundary (the items appended since its last commit
/// join its count) and turns the count into indirect dispatch arguments.
pub struct CommitKernel<'a> {
    /// Entry point name.
    pub name: &'a str,
    /// Binding of the boundary buffer.
    pub boundary_binding: u32,
    /// Binding of the indirect arguments.
    pub args_binding: u32,
    /// First of the three argument words.
    pub args_offset: u32,
    /// Workgroup size of the consumer kernel.
    pub workgroup: u32,
    /// Most workgroups per dispatch dimension.
    pub max_groups: u32,
    /// Whether the appended items join items still counted (after a regeneration step)
    /// rather than replace a count already consumed.
    pub add: bool,
}

impl CommitKernel<'_> {
    /// The WGSL module.
    pub fn wgsl(&self) -> String {
        let CommitKernel {
            name,
            boundary_binding,
            args_binding,
            args_offset,
            workgroup,
            max_groups,
            add,
        } = self;
        let kept = if *add { "atomicLoad(&lg_in.count) + " } else { "" };
        format!(
            "struct LgBoundary {{ count: atomic<u32>, append: atomic<u32>, pad0: u32, pad1: u32, words: array<u32> }}
@group(0) @binding({boundary_binding}) var<storage, read_write> lg_in: LgBoundary;
@group(0) @binding({args_binding}) var<storage, read_write> lg_args: array<u32>;
@compute @workgroup_size(1)
fn {name}() {{
    let n = {kept}atomicLoad(&lg_in.append);
    atomicStore(&lg_in.count, n);
    atomicStore(&lg_in.append, 0u);
    let groups = (n + {workgroup}u - 1u) / {workgroup}u;
    let x = min(groups, {max_groups}u);
    lg_args[{args_offset}] = x;
    lg_args[{args_offset} + 1u] = select(1u, (groups + x - 1u) / x, x > 0u);
    lg_args[{args_offset} + 2u] = 1u;
}}
"
        )
    }
}

/// A one-thread kernel that sets control word `word` to zero (a reset that needs no break
/// in the compute pass).
pub fn zero_kernel(name: &str, control_binding: u32, word: u32) -> String {
    format!(
        "@group(0) @binding({control_binding}) var<storage, read_write> lg_control: array<u32>;
@compute @workgroup_size(1)
fn {name}() {{
    lg_control[{word}] = 0u;
}}
"
    )
}

/// A kernel that moves control word `from` into `to` and clears `from`.
pub fn roll_kernel(name: &str, control_binding: u32, from: u32, to: u32) -> String {
    format!(
        "@group(0) @binding({control_binding}) var<storage, read_write> lg_control: array<u32>;
@compute @workgroup_size(1)
fn {name}() {{
    lg_control[{to}] = lg_control[{from}];
    lg_control[{from}] = 0u;
}}
"
    )
}

/// The kernel that adds the per-chunk counters into 64-bit totals and clears them.
pub fn fold_kernel(counters_binding: u32, totals_binding: u32, n: usize) -> String {
    format!(
        "@group(0) @binding({counters_binding}) var<storage, read_write> lg_counters: array<u32>;
@group(0) @binding({totals_binding}) var<storage, read_write> lg_totals: array<u32>;
@compute @workgroup_size(1)
fn lg_fold() {{
    for (var c = 0u; c < {n}u; c += 1u) {{
        let v = lg_counters[c];
        let lo = lg_totals[2u * c] + v;
        lg_totals[2u * c + 1u] += select(0u, 1u, lo < v);
        lg_totals[2u * c] = lo;
        lg_counters[c] = 0u;
    }}
}}
"
    )
}

/// The kernel that counts the items of the current chunk of a phase counted on the GPU: the
/// counter (at most the phase's `over`, which the record's base and count split into chunks)
/// minus the chunk's first item, clamped to the chunk, into the phase's control word and the
/// indirect arguments of its start kernel.
pub struct DomainKernel<'a> {
    /// Entry point name.
    pub name: &'a str,
    /// Binding of the counter resource.
    pub counter_binding: u32,
    /// Binding of the control words.
    pub control_binding: u32,
    /// Binding of the indirect arguments.
    pub args_binding: u32,
    /// Control word receiving the chunk's items.
    pub word: u32,
    /// First of the three argument words.
    pub args_offset: u32,
    /// Workgroup size of the start kernel.
    pub workgroup: u32,
    /// Most workgroups per dispatch dimension.
    pub max_groups: u32,
}

impl DomainKernel<'_> {
    /// The WGSL module.
    pub fn wgsl(&self) -> String {
        let DomainKernel {
            name,
            counter_binding,
            control_binding,
            args_binding,
            word,
            args_offset,
            workgroup,
            max_groups,
        } = self;
        format!(
            "struct Frame {{ index: u32, seed: u32, base: u32, count: u32 }}
{frame}
@group(0) @binding({counter_binding}) var<storage, read_write> lg_counter: array<u32>;
@group(0) @binding({control_binding}) var<storage, read_write> lg_control: array<u32>;
@group(0) @binding({args_binding}) var<storage, read_write> lg_args: array<u32>;
@compute @workgroup_size(1)
fn {name}() {{
    let n = min(max(lg_counter[0], frame.base) - frame.base, frame.count);
    lg_control[{word}] = n;
    let groups = (n + {workgroup}u - 1u) / {workgroup}u;
    let x = min(groups, {max_groups}u);
    lg_args[{args_offset}] = x;
    lg_args[{args_offset} + 1u] = select(1u, (groups + x - 1u) / x, x > 0u);
    lg_args[{args_offset} + 2u] = 1u;
}}
",
            frame = crate::limits::FRAME_BINDING
        )
    }
}
