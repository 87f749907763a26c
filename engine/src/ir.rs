//! The RON schema of frame graphs and pass catalogs, as written by people.
//!
//! A graph file (`graphs/*.ron`) is a [`GraphFile`]: the WGSL library it needs, its passes
//! (taken from a catalog with `Use("name")` or declared inline with `Pass(...)`), its
//! resources, streams, counters, constants and layouts. A graph file that starts from another
//! and changes a few things is an [`ExtendingFile`]. A pass catalog (`passes/*.ron`), and a
//! file a graph `include`s, is a [`CatalogFile`].
//!
//! Unknown fields are errors. Two RON extensions are on: a field that may be left out is
//! written as its value, without `Some(...)` (`enabled: "MERGE"`), and a variant that holds a
//! struct takes the struct's fields in its parentheses (`Pass(name: "trace", ...)`). Names of
//! resources, streams, counters, constants and parameters are WGSL identifiers that do not
//! start with `lg_`, and a name cannot be both a constant and a parameter. Count expressions
//! (`count`, `over`, `per_call`, `first`, ...) and conditions (`enabled`, `when`, `checks`) are
//! written over numbers and the constants' names (docs/graphs.md, "Resources").
//!
//! The reference, docs/reference/graph-file.md, is generated from these doc comments by
//! `cargo xtask docs`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A frame graph: one estimator, with the layouts it can be run in.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraphFile {
    /// Short name, used in messages and in `explain`'s file names, e.g. `pt`.
    pub name: String,
    /// One line on what the estimator computes.
    #[serde(default)]
    pub description: String,
    /// Declaration files (virtual paths, in the [`CatalogFile`] format) whose library,
    /// resources, counters and constants all join the graph, and whose passes `Use` can name;
    /// `passes/scene.ron` holds the scene's.
    #[serde(default)]
    pub include: Vec<String>,
    /// WGSL library files (virtual paths), included in every kernel.
    #[serde(default)]
    pub library: Vec<String>,
    /// Pass catalog files (virtual paths) that `Use` entries are looked up in (the later
    /// catalog's pass where two declare one name); a used pass brings what it needs from its
    /// catalog (see [`CatalogFile`]).
    #[serde(default)]
    pub catalogs: Vec<String>,
    /// The passes and operators, in order: item chains follow this order, and phases and
    /// operators run in the order of their start passes and their own. A name is listed once.
    pub passes: Vec<PassEntry>,
    /// Buffers the passes and operators read and write, by name.
    #[serde(default)]
    pub resources: BTreeMap<String, ResourceDecl>,
    /// Typed edges from producing passes to a consuming pass, by name.
    #[serde(default)]
    pub streams: BTreeMap<String, StreamDecl>,
    /// Statistics the passes count with `count(COUNTER_<NAME>, n)`, summed on the GPU.
    #[serde(default)]
    pub counters: Vec<String>,
    /// WGSL `const`s with their default values (`U32(10)`, `I32(-1)`, `F32(1.0)`,
    /// `Bool(true)`); the host, the scene and `--set` may give others.
    #[serde(default)]
    pub constants: BTreeMap<String, ConstValue>,
    /// Per-frame parameters with their default values (as `constants`): set by the host before
    /// any frame without recompiling, read in WGSL by name like constants.
    #[serde(default)]
    pub parameters: BTreeMap<String, ConstValue>,
    /// `u32` constants computed from the others once all are known (the host's, the measured
    /// ones, `--set`): name → count expression, e.g.
    /// `"PM_CAPACITY": "PM_LIGHT_PATHS * PM_AVERAGE_LENGTH * 1.1 + 256"`. They may use each
    /// other, are read like constants, and `--set` may give one directly.
    #[serde(default)]
    pub derived: BTreeMap<String, String>,
    /// Conditions over the constants that must hold once the constants are known: condition →
    /// what the constants may be, e.g. `"PM_STRUCTURE <= 3": "PM_STRUCTURE is 0, 1, 2 or 3"`.
    /// One that fails stops the run with an error at the condition's line, naming the
    /// constants' values and the message.
    #[serde(default)]
    pub checks: BTreeMap<String, String>,
    /// Resources the host reads after frames; passes and operators that contribute to none
    /// are culled.
    #[serde(default)]
    pub outputs: Vec<String>,
    /// `f32` constants the host measures before rendering (unless `--set` gives them), by a
    /// frame of the graph itself; count expressions may use them (`bpt-lvc` sizes its vertex
    /// cache by the measured vertices per light sub-path).
    #[serde(default)]
    pub measured: BTreeMap<String, MeasuredDecl>,
    /// The most loop iterations an item runs, by item type: a count expression over the
    /// constants, e.g. `{"CameraPath": "MAX_PATH_LENGTH"}` (path tracing's paths trace one
    /// segment an iteration). A host-driven loop whose items all start in its first iteration
    /// (no thread pool, or one that holds the chunk) then runs exactly that many iterations
    /// with no read-back in between; an item still alive after them is an error when the batch
    /// is read back (`items of 'T' still alive after N loop iterations`). An item type no pass
    /// runs over is an error. Without a bound the host reads back whether items are alive.
    #[serde(default)]
    pub loop_bounds: BTreeMap<String, String>,
    /// Named kernel layouts: how the passes become kernels.
    pub layouts: BTreeMap<String, LayoutWritten>,
    /// The layout used when none is asked for.
    pub default_layout: String,
    /// What the graph estimates and what it cannot sample, as the application states them:
    /// the engine keeps them for the application's checks (`lightgraph verify`,
    /// docs/verify.md).
    #[serde(default)]
    pub coverage: Coverage,
    /// Fields added to item structs: item → `(name, WGSL type)` in order; the engine adds them
    /// to the struct and packs them in every layout like the struct's own.
    #[serde(default)]
    pub item_fields: BTreeMap<String, Vec<(String, String)>>,
    /// Named hooks replaced: hook (a WGSL function a source declares with `// Hook:`) → the
    /// WGSL file (virtual path) that defines the replacement, of the same signature.
    #[serde(default)]
    pub hooks: BTreeMap<String, String>,
}

/// A graph's claims about its estimate, for the application: which quantity it estimates
/// (graphs of one quantity may be compared) and which samples it cannot draw, each under an
/// optional condition over the constants, e.g.
/// `(estimates: "radiance", misses: [(paths: "Ld S X* E", when: "!FLAG", why: "...")])`. The
/// engine checks only that each `when` names constants; `lightgraph verify` reads the rest.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coverage {
    /// The quantity the graph's output estimates (the application's default when absent:
    /// lightgraph's is `"radiance"`).
    #[serde(default)]
    pub estimates: Option<String>,
    /// The classes of light paths the graph cannot sample.
    #[serde(default)]
    pub misses: Vec<MissDecl>,
    /// The classes of samples whose estimate is biased at a finite budget (a consistent
    /// estimator's, e.g. one that blurs by a radius that shrinks), each under an optional
    /// condition; every other class is held to an unbiased estimator's standard.
    #[serde(default)]
    pub biased: Vec<BiasDecl>,
    /// Scene features, in the application's notation, that the graph's estimate accounts for
    /// where the application asks graphs to say so (lightgraph's `"media"`: participating
    /// media); the application refuses a scene with a feature the graph does not handle.
    #[serde(default)]
    pub handles: Vec<String>,
}

/// A graph's claim that its estimate of one class of samples is biased at a finite budget.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiasDecl {
    /// The class, in the application's notation.
    pub paths: String,
    /// Why, for reports.
    pub why: String,
    /// Constant expression: the claim holds only where it is non-zero (always without it).
    #[serde(default)]
    pub when: Option<String>,
}

/// One class of samples a graph cannot draw.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissDecl {
    /// The class, in the application's notation (lightgraph's: Heckbert's, from the light to
    /// the eye, e.g. `"Ld S X* E"`).
    pub paths: String,
    /// Constant expression: the claim holds only where it is non-zero (always without it).
    #[serde(default)]
    pub when: Option<String>,
    /// Why the graph cannot sample them, for reports.
    #[serde(default)]
    pub why: String,
}

/// How the host measures a constant, e.g.
/// `(set: {"FLAG": Bool(true)}, ratio: ("counter_a", "counter_b"))`: it runs one frame of the
/// graph (same layout and scene) with the constants `set`, and the constant becomes the ratio
/// of two counters' totals, `ratio.0 / ratio.1`, or `value` evaluated with that ratio.
/// Constants are measured in name order, each measuring frame with the values measured before
/// it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredDecl {
    /// Constants of the measuring frame, e.g. a flag that makes the passes only count.
    #[serde(default)]
    pub set: BTreeMap<String, ConstValue>,
    /// Numerator and denominator counters.
    pub ratio: (String, String),
    /// The constant's value: an expression of `RATIO` (the counters' ratio; 0 where the
    /// denominator stayed 0) and the graph's constants, e.g. a setting chosen by what the
    /// frame found (`vcm`'s `"1 + 2 * (RATIO < 0.75)"`). Without it, the ratio itself (and a
    /// denominator of 0 is an error).
    #[serde(default)]
    pub value: Option<String>,
}

/// The name a measured constant's `value` expression reads the measured ratio by.
pub const MEASURED_RATIO: &str = "RATIO";

impl MeasuredDecl {
    /// The constant's value from the measuring frame's counter totals `a` (`ratio.0`) and `b`
    /// (`ratio.1`), its `value` read with the frame's `constants`; the error says why none.
    pub fn value_from(&self, a: u64, b: u64, constants: &BTreeMap<String, ConstValue>) -> Result<f64, String> {
        let Some(value) = &self.value else {
            if b == 0 {
                return Err(format!("counter '{}' stayed 0", self.ratio.1));
            }
            return Ok(a as f64 / b as f64);
        };
        let ratio = if b == 0 { 0.0 } else { a as f64 / b as f64 };
        let mut vars: BTreeMap<String, f64> = constants.iter().map(|(k, v)| (k.clone(), v.as_f64())).collect();
        vars.insert(MEASURED_RATIO.to_string(), ratio);
        crate::expr::Expr::parse(value)?.eval(&vars)
    }
}

/// An entry of a graph's `passes`: a catalog pass, a pass declared inline, or one of the
/// engine's collective operators. Operators are written once in the engine for any element
/// type and length and are not listed in layouts; each is a barrier (it runs after every phase
/// and operator before it and before every one after it), and works on resources the engine
/// allocates (not `External` ones).
#[derive(Debug, Clone, Deserialize)]
pub enum PassEntry {
    /// A pass from one of the graph's catalogs, by name.
    Use(String),
    /// A pass from one of the graph's catalogs that also reads or writes what this graph's
    /// library functions, which it calls, use (a Markov chain's path evaluator, say).
    UseWith(UseWithDecl),
    /// A pass declared in the graph itself.
    Pass(PassDecl),
    /// Fills a buffer (or a range of it) with a value.
    Clear(ClearDecl),
    /// Exclusive prefix sum of `u32`s (or `f32`s).
    Scan(ScanDecl),
    /// The count step of a counting sort: each element's key bumps its bucket's counter,
    /// and the element keeps the counter's old value as its slot in the bucket.
    Count(CountDecl),
    /// The scatter step of a counting sort: each element to `offsets[key] + slot`.
    Scatter(ScatterDecl),
    /// Each element from the place its index names: `output[i] = input[indices[i]]`.
    Gather(GatherDecl),
    /// Stable radix sort of `u32` keys, with `u32` values permuted alongside.
    Sort(SortDecl),
}

impl PassEntry {
    /// The name of the pass or operator the entry declares.
    pub fn name(&self) -> &str {
        match self {
            PassEntry::Use(name) => name,
            PassEntry::UseWith(d) => &d.name,
            PassEntry::Pass(d) => &d.name,
            PassEntry::Clear(d) => &d.name,
            PassEntry::Scan(d) => &d.name,
            PassEntry::Count(d) => &d.name,
            PassEntry::Scatter(d) => &d.name,
            PassEntry::Gather(d) => &d.name,
            PassEntry::Sort(d) => &d.name,
        }
    }
}

/// A graph file that extends another (`extends: "graphs/ppm.ron"`): the base's declaration
/// with this file's overrides. Maps merge by key (this file's value wins), `passes` and
/// `layouts` are edits of the base's, and every other field given replaces the base's.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtendingFile {
    /// The base graph file (a virtual path, as `include` and `catalogs`).
    pub extends: String,
    /// Replaces the base's name.
    #[serde(default)]
    pub name: Option<String>,
    /// Replaces the base's description.
    #[serde(default)]
    pub description: Option<String>,
    /// Replaces the base's included files.
    #[serde(default)]
    pub include: Option<Vec<String>>,
    /// Replaces the base's library.
    #[serde(default)]
    pub library: Option<Vec<String>>,
    /// Replaces the base's catalogs.
    #[serde(default)]
    pub catalogs: Option<Vec<String>>,
    /// Edits of the base's `passes`, applied in order.
    #[serde(default)]
    pub passes: Vec<PassEdit>,
    /// Merged into the base's resources.
    #[serde(default)]
    pub resources: BTreeMap<String, ResourceDecl>,
    /// Merged into the base's streams.
    #[serde(default)]
    pub streams: BTreeMap<String, StreamDecl>,
    /// Replaces the base's counters.
    #[serde(default)]
    pub counters: Option<Vec<String>>,
    /// Merged into the base's constants.
    #[serde(default)]
    pub constants: BTreeMap<String, ConstValue>,
    /// Merged into the base's parameters.
    #[serde(default)]
    pub parameters: BTreeMap<String, ConstValue>,
    /// Merged into the base's derived constants.
    #[serde(default)]
    pub derived: BTreeMap<String, String>,
    /// Merged into the base's checks.
    #[serde(default)]
    pub checks: BTreeMap<String, String>,
    /// Replaces the base's outputs.
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
    /// Merged into the base's measured constants.
    #[serde(default)]
    pub measured: BTreeMap<String, MeasuredDecl>,
    /// Replaces the base's loop bounds (they follow the passes, which the edits may change).
    #[serde(default)]
    pub loop_bounds: Option<BTreeMap<String, String>>,
    /// Edits of the base's layouts, by name.
    #[serde(default)]
    pub layouts: BTreeMap<String, LayoutEdit>,
    /// Replaces the base's default layout.
    #[serde(default)]
    pub default_layout: Option<String>,
    /// Replaces the base's coverage.
    #[serde(default)]
    pub coverage: Option<Coverage>,
    /// Fields added to item structs, after the base's.
    #[serde(default)]
    pub item_fields: BTreeMap<String, Vec<(String, String)>>,
    /// Hooks replaced, merged into the base's by hook name.
    #[serde(default)]
    pub hooks: BTreeMap<String, String>,
}

/// An edit of the base's `passes` in a graph that extends another; each names an entry (a
/// pass or operator) of the list as the edits before it left it.
#[derive(Debug, Clone, Deserialize)]
pub enum PassEdit {
    /// `Replace("name", [entries])`: the entry replaced by the entries (none removes it).
    Replace(String, Vec<PassEntry>),
    /// `Before("name", [entries])`: the entries inserted before the entry.
    Before(String, Vec<PassEntry>),
    /// `After("name", [entries])`: the entries inserted after the entry.
    After(String, Vec<PassEntry>),
    /// `Remove("name")`: the entry removed.
    Remove(String),
}

/// An edit of a layout of the base, by name, in a graph that extends another.
#[derive(Debug, Clone, Deserialize)]
pub enum LayoutEdit {
    /// `Layout(kernels: [...], ...)`: a layout declared here, new or replacing the base's; it
    /// may be `like` one of the base's (`Layout(like: "base_layout", ...)`).
    Layout(LayoutWritten),
    /// `From("name")`: a copy of the base's layout `name`.
    From(String),
    /// The base's layout leaves.
    Remove,
}

/// `UseWith(name: "pass", reads: [...], writes: [...], enabled: "...")`: catalog pass `name`
/// with more resources read and written than its catalog declares, for what the graph's own
/// library functions that it calls use, and a condition of the graph's that it runs under.
/// `reads` and `writes` may be added only to a catalog pass that lists them: where the catalog
/// leaves them to be derived from the WGSL, the derivation already sees the graph's functions,
/// and listing them is an error.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UseWithDecl {
    /// The catalog pass.
    pub name: String,
    /// Resources read besides the catalog's `reads`.
    #[serde(default)]
    pub reads: Vec<String>,
    /// Resources written besides the catalog's `writes`.
    #[serde(default)]
    pub writes: Vec<String>,
    /// Constant condition under which the pass runs, besides the catalog's own `enabled`.
    #[serde(default)]
    pub enabled: Option<String>,
}

/// A pass catalog file (`passes/*.ron`), also the format of included declaration files.
///
/// A graph that uses one of the catalog's passes gets the catalog's `library`, `counters`,
/// `constants`, `derived` and `checks`, those of its `resources` that the pass reads or writes
/// (or that one of the graph's operators names), and the pass's own `library`, `counters` and
/// `constants`; an included file gives all of them at once. For resources and constants the
/// graph's own declaration wins over an include's, which wins over a catalog's, which wins over
/// a pass's; two different declarations at the same level are an error naming both files.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CatalogFile {
    /// WGSL library files the catalog's passes need.
    #[serde(default)]
    pub library: Vec<String>,
    /// Resources the catalog's passes use.
    #[serde(default)]
    pub resources: BTreeMap<String, ResourceDecl>,
    /// Resources that join a graph including this file (or using one of its passes) only
    /// where a pass that derives its reads and writes uses them, with the kernels' flags (data of a feature most inputs lack,
    /// which kernels without the feature then neither declare nor bind).
    #[serde(default)]
    pub candidates: BTreeMap<String, ResourceDecl>,
    /// Counters the catalog's passes count.
    #[serde(default)]
    pub counters: Vec<String>,
    /// Constants the catalog's passes read, with defaults.
    #[serde(default)]
    pub constants: BTreeMap<String, ConstValue>,
    /// `u32` constants computed from the others (as the graph's `derived`).
    #[serde(default)]
    pub derived: BTreeMap<String, String>,
    /// Conditions over the constants that must hold (as the graph's `checks`).
    #[serde(default)]
    pub checks: BTreeMap<String, String>,
    /// The passes this catalog offers.
    #[serde(default)]
    pub passes: Vec<PassDecl>,
}

/// `Clear(name, buffer, value, first, count)`: fills elements `first .. first + count` of a
/// buffer (all of it by default) with `value`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClearDecl {
    /// Operator name.
    pub name: String,
    /// The buffer.
    pub buffer: String,
    /// The value, written into each 32-bit word: any `U32`, `I32` or `F32` for elements of
    /// 4 bytes.
    #[serde(default = "zero")]
    pub value: ConstValue,
    /// Count expression of the first element.
    #[serde(default)]
    pub first: Option<String>,
    /// Count expression of the elements to fill.
    #[serde(default)]
    pub count: Option<String>,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

fn zero() -> ConstValue {
    ConstValue::U32(0)
}

/// `Scan(name, input, output, over, counted)`: `output[i] = input[0] + ... + input[i - 1]`
/// (wrapping `u32` sums, or `f32` sums in the order of the scan's tree); in place when
/// `output` is absent.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanDecl {
    /// Operator name.
    pub name: String,
    /// The elements to sum: `u32` (or `atomic<u32>`) or `f32`, as the output's.
    pub input: String,
    /// Where the sums go (the input itself when absent).
    #[serde(default)]
    pub output: Option<String>,
    /// Elements to scan.
    pub over: String,
    /// A GPU counter of the elements (at most `over`).
    #[serde(default)]
    pub counted: Option<String>,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

/// `Count(name, keys, counts, slots, over, counted)`: for each element `i`,
/// `slots[i] = counts[keys[i]]++` (atomically). An element whose key is at or beyond the
/// buckets is skipped, and the frame fails naming how many.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CountDecl {
    /// Operator name.
    pub name: String,
    /// Each element's bucket (`u32`).
    pub keys: String,
    /// The buckets' counters (`u32` or `atomic<u32>`; clear them first).
    pub counts: String,
    /// Each element's slot in its bucket (`u32`).
    pub slots: String,
    /// Elements.
    pub over: String,
    /// A GPU counter of the elements (at most `over`).
    #[serde(default)]
    pub counted: Option<String>,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

/// `Scatter(name, keys, slots, offsets, input, output, over, counted)`: for each element `i`,
/// `output[offsets[keys[i]] + slots[i]] = input[i]`, or `= i` without `input` (the permutation
/// that sorts, for elements too large to move: readers then load `input[output[k]]`). An
/// element whose place is beyond `output` is skipped, and the frame fails naming how many.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScatterDecl {
    /// Operator name.
    pub name: String,
    /// Each element's bucket (`u32`).
    pub keys: String,
    /// Each element's slot in its bucket (`u32`).
    pub slots: String,
    /// Each bucket's first place (`u32`, e.g. the exclusive scan of the counts).
    pub offsets: String,
    /// The elements (any type); omitted, each element's index `i` (`u32`) moves instead.
    #[serde(default)]
    pub input: Option<String>,
    /// Where they go (the input's element type, or `u32` without an input).
    pub output: String,
    /// Elements.
    pub over: String,
    /// A GPU counter of the elements (at most `over`).
    #[serde(default)]
    pub counted: Option<String>,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

/// `Gather(name, indices, input, output, over, counted)`: for each element `i`,
/// `output[i] = input[indices[i]]` (after a `Scatter` of indices, the sorted elements written
/// in order, where a scatter of large elements would write each one to a random place). An
/// index past `input` is counted as skipped.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GatherDecl {
    /// Operator name.
    pub name: String,
    /// Each element's place in `input` (`u32`).
    pub indices: String,
    /// The elements read (any type).
    pub input: String,
    /// Where they go, in the order of `indices` (the same element type).
    pub output: String,
    /// Elements.
    pub over: String,
    /// A GPU counter of the elements (at most `over`).
    #[serde(default)]
    pub counted: Option<String>,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

/// `Sort(name, keys, values, over, counted, bits)`: sorts the `u32` keys ascending in place,
/// stably, by their low `bits` bits, moving each element's `u32` value with its key (values
/// are optional: without them only the keys move).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SortDecl {
    /// Operator name.
    pub name: String,
    /// The `u32` keys, sorted in place.
    pub keys: String,
    /// The `u32` values, permuted with their keys (none: keys only); not the keys' resource.
    #[serde(default)]
    pub values: Option<String>,
    /// Elements.
    pub over: String,
    /// A GPU counter of the elements (at most `over`).
    #[serde(default)]
    pub counted: Option<String>,
    /// The low bits of the keys that are sorted by, 1 to 32 (higher bits are ignored).
    #[serde(default = "all_bits")]
    pub bits: u32,
    /// Constant expression; the operator is culled when it is 0.
    #[serde(default)]
    pub enabled: Option<String>,
}

fn all_bits() -> u32 {
    32
}

/// A pass: one WGSL function over one item,
/// `Pass(name: "shade", item: "Hit", source: "lab/shade.wgsl", role: Step)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassDecl {
    /// The pass name; also the WGSL function name unless `function` is given.
    pub name: String,
    /// The WGSL struct the pass runs over.
    pub item: String,
    /// The WGSL file (a virtual path) that defines the function.
    pub source: String,
    /// The WGSL function, if its name differs from the pass name.
    #[serde(default)]
    pub function: Option<String>,
    /// How the pass takes part in its item's chain.
    pub role: Role,
    /// Resources the pass or anything it calls reads. Left out, they are derived from the
    /// WGSL (with the constants' and the scene's flags of the program compiled); listed, they
    /// are checked against it.
    #[serde(default, rename = "reads")]
    pub listed_reads: Option<Vec<String>>,
    /// Resources the pass or anything it calls writes, left out or listed as `reads` (each
    /// list on its own).
    #[serde(default, rename = "writes")]
    pub listed_writes: Option<Vec<String>>,
    /// Resources the pass reads: the listed ones, or those the specialisation derived from
    /// naga's view of the pass function (empty until then).
    #[serde(skip)]
    pub reads: Vec<String>,
    /// Resources the pass writes: the listed ones, or the derived ones (as `reads`).
    #[serde(skip)]
    pub writes: Vec<String>,
    /// Streams the pass emits items into.
    #[serde(default)]
    pub emits: Vec<String>,
    /// Condition over the constants; the pass is culled when it is 0 (e.g. `"MERGE"`,
    /// `"!LVC_MEASURING"` or `"MAX_PATH_LENGTH > 1"`).
    #[serde(default)]
    pub enabled: Option<String>,
    /// WGSL library files the pass needs besides its source, brought into any graph that
    /// uses it.
    #[serde(default)]
    pub library: Vec<String>,
    /// Counters the pass counts, brought into any graph that uses it.
    #[serde(default)]
    pub counters: Vec<String>,
    /// Constants the pass reads, with defaults, brought into any graph that uses it.
    #[serde(default)]
    pub constants: BTreeMap<String, ConstValue>,
}

/// The part a pass plays in its item's chain. A `Start` pass, or a stream's consumer, begins a
/// chain over its item; any other pass joins the most recent chain over the same item type.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub enum Role {
    /// Creates items: `fn f(item: ptr<function, T>, index: u32) -> bool`, called for every
    /// index below the count expression `over`; `false` means no item for that index. With
    /// `counted`, for every index below the `u32` that resource holds when the phase runs, at
    /// most `over`: the domain is counted on the GPU and dispatched indirectly, with no
    /// read-back (`over` then sizes the phase's buffers and chunks).
    Start {
        /// Count expression of the items, e.g. `PATHS`.
        over: String,
        /// A `u32` or `atomic<u32>` resource holding the item count, read on the GPU.
        #[serde(default)]
        counted: Option<String>,
    },
    /// Runs once: `fn f(item: ptr<function, T>) -> bool`; `false` finishes the item, and the
    /// rest of its chain is skipped.
    Step,
    /// `fn f(item: ptr<function, T>) -> bool`: the `Loop` passes at the end of a chain repeat
    /// as a group, in order, while they return `true`; the first `false` finishes the item.
    /// Only `Loop` passes may follow one in its chain.
    Loop,
}

/// A typed GPU buffer.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResourceDecl {
    /// WGSL type: with `count`, the element type (`vec4<f32>`, `atomic<u32>`, a struct);
    /// without, the type of a single value; for an `External` resource, the whole type (e.g.
    /// `array<Primitive>`).
    pub ty: String,
    /// Count expression of elements; without it the resource is a single value. It may not
    /// name a parameter. External resources have none: the host's data sizes them.
    #[serde(default)]
    pub count: Option<String>,
    /// Lifetime and ownership.
    #[serde(default)]
    pub scope: Scope,
    /// `Transient` only: set to zero at the start of its lifetime in every frame.
    #[serde(default)]
    pub clear: bool,
}

/// Who owns a resource and how long it lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum Scope {
    /// Allocated by the engine, zero-filled at creation, kept across frames (film,
    /// accumulation). Outputs are persistent.
    #[default]
    Persistent,
    /// Allocated by the engine, valid from its first to its last use within one frame: its
    /// memory is shared with transient buffers whose lifetimes do not overlap, so it holds
    /// garbage at the start of its lifetime unless it is `clear`.
    Transient,
    /// Supplied by the host at instantiation (scene data); its bytes, a whole number of
    /// elements, decide its size.
    External,
}

/// A stream: items of one type emitted by passes and consumed by one pass, e.g.
/// `(item: "ShadowRay", to: "shadow", per_call: 1)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamDecl {
    /// The WGSL struct carried.
    pub item: String,
    /// The consuming pass (its chain's entry): a `Step` or `Loop` pass over the same item, fed
    /// by no other stream.
    pub to: String,
    /// The most items one call of a producing pass emits, never 0: it sizes the queues of split
    /// layouts, and a queue that overflows is an error of the frame.
    #[serde(default = "one")]
    pub per_call: PerCall,
}

fn one() -> PerCall {
    PerCall::Number(1)
}

/// A stream's `per_call`: a number, or a count expression over the constants (e.g.
/// `"MAX_PATH_LENGTH + 1"`), evaluated when the program is compiled.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum PerCall {
    /// A fixed count.
    Number(u32),
    /// A count expression.
    Expr(String),
}

impl std::fmt::Display for PerCall {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PerCall::Number(n) => write!(f, "{n}"),
            PerCall::Expr(e) => write!(f, "{e}"),
        }
    }
}

/// A constant's value, emitted as a WGSL `const` (or a parameter's value).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum ConstValue {
    /// A `u32`, e.g. `U32(10)`.
    U32(u32),
    /// An `i32`, e.g. `I32(-1)`.
    I32(i32),
    /// An `f32`, e.g. `F32(1.0)`.
    F32(f32),
    /// A `bool`, e.g. `Bool(true)`.
    Bool(bool),
}

/// The value as `--set NAME=VALUE` takes it.
impl std::fmt::Display for ConstValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ConstValue::U32(v) => write!(f, "{v}"),
            ConstValue::I32(v) => write!(f, "{v}"),
            ConstValue::F32(v) => write!(f, "{v}"),
            ConstValue::Bool(v) => write!(f, "{v}"),
        }
    }
}

impl ConstValue {
    /// The WGSL type name.
    pub fn wgsl_type(&self) -> &'static str {
        match self {
            ConstValue::U32(_) => "u32",
            ConstValue::I32(_) => "i32",
            ConstValue::F32(_) => "f32",
            ConstValue::Bool(_) => "bool",
        }
    }

    /// The WGSL literal.
    pub fn wgsl_literal(&self) -> String {
        match self {
            ConstValue::U32(v) => format!("{v}u"),
            ConstValue::I32(v) => format!("{v}i"),
            ConstValue::F32(v) => {
                let s = format!("{v:?}");
                if s.contains('.') || s.contains('e') {
                    format!("{s}f")
                } else {
                    format!("{s}.0f")
                }
            }
            ConstValue::Bool(v) => v.to_string(),
        }
    }

    /// The value's 32 bits, as a uniform or storage buffer holds it (`bool` as 0 or 1).
    pub fn bits(&self) -> u32 {
        match self {
            ConstValue::U32(v) => *v,
            ConstValue::I32(v) => *v as u32,
            ConstValue::F32(v) => v.to_bits(),
            ConstValue::Bool(v) => *v as u32,
        }
    }

    /// `v` converted to this value's type (rounded towards zero for integers).
    pub fn with_number(&self, v: f64) -> ConstValue {
        match self {
            ConstValue::U32(_) => ConstValue::U32(v as u32),
            ConstValue::I32(_) => ConstValue::I32(v as i32),
            ConstValue::F32(_) => ConstValue::F32(v as f32),
            ConstValue::Bool(_) => ConstValue::Bool(v != 0.0),
        }
    }

    /// The value as a number, for count expressions.
    pub fn as_f64(&self) -> f64 {
        match self {
            ConstValue::U32(v) => *v as f64,
            ConstValue::I32(v) => *v as f64,
            ConstValue::F32(v) => *v as f64,
            ConstValue::Bool(v) => *v as u8 as f64,
        }
    }
}

/// How item state is laid out in buffers between split kernels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum StateStorage {
    /// Structure of arrays: word `w` of item `i` at `w * capacity + i` (coalesced).
    #[default]
    SoA,
    /// Array of structures: word `w` of item `i` at `i * words + w`.
    AoS,
}

/// A layout: how the passes become kernels. A graph file writes a [`LayoutWritten`].
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LayoutDecl {
    /// What the layout is (e.g. the paper's name for it), shown by `explain`.
    #[serde(default)]
    pub description: String,
    /// Fusion groups: each inner list of pass names becomes one kernel (operators are not
    /// listed). Each pass the constants enable is in one kernel; one they disable may be left
    /// out, and when other constants enable it, it joins the kernel of the nearest pass before
    /// it in its chain that a kernel lists (or a kernel of its own where it begins its chain).
    #[serde(default)]
    pub kernels: Vec<Vec<String>>,
    /// Item state layout between split kernels.
    #[serde(default)]
    pub state: StateStorage,
    /// Threads per workgroup, 1 to 1024.
    #[serde(default = "default_workgroup")]
    pub workgroup_size: u32,
    /// Most items a split chain keeps in flight, per chunk of a phase that stores state or
    /// uses queues (larger frames run in chunks); 4194304 when absent.
    #[serde(default)]
    pub max_items_in_flight: Option<u64>,
    /// Where loop passes repeat.
    #[serde(default)]
    pub loops: LoopMode,
    /// How finished items are replaced in a chain with a loop.
    #[serde(default)]
    pub policy: Policy,
    /// Threads (item slots) of a `Regeneration` or `Compaction` pool: 1048576 when absent,
    /// fewer when the frame has fewer items or a queue would not fit one binding.
    #[serde(default)]
    pub threads: Option<u64>,
    /// Host loops with policy Regeneration: idle slots are refilled only once at least this
    /// fraction of the pool was idle after the last iteration (van Antwerpen's streaming
    /// threshold, e.g. 0.6); every iteration when absent.
    #[serde(default)]
    pub regenerate_at: Option<f32>,
    /// Settings for the application that runs the graph, by name; the engine carries them
    /// unread. lightgraph reads `bvh` (`"bvh2"` or `"cwbvh"`): the acceleration structure
    /// `--bvh auto` gives the layout.
    #[serde(default)]
    pub hints: BTreeMap<String, String>,
    /// Constants this layout compiles with unless the program is given them (a variant of the
    /// estimator's code that suits the layout's kernels, the same image to float rounding):
    /// they cull passes and enter the code as the graph's own constants do. Each is a constant
    /// of the graph, of its type; `--set` wins over it.
    #[serde(default)]
    pub constants: BTreeMap<String, ConstValue>,
    /// Whether the pass kernels keep the loop guards wgpu adds to a shader (a counter in every
    /// loop that ends it after 2^64 iterations, so that a loop that never ends cannot hang the
    /// GPU or be miscompiled). `false` for a layout whose loops all end: its kernels run
    /// without the counters, which also frees the driver to unroll and schedule the loops
    /// (faster where a kernel traverses the BVH at one place, slower where it fuses several
    /// traversals; measured per layout, docs/performance.md). `--loop-guards on|off`
    /// overrides it.
    #[serde(default = "default_loop_guards")]
    pub loop_guards: bool,
}

fn default_loop_guards() -> bool {
    true
}

/// How a chain with a loop keeps its threads busy (the paper's regeneration policies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum Policy {
    /// One thread (slot) per item; finished items leave their slot idle.
    #[default]
    Naive,
    /// A fixed pool of threads; an idle thread takes the next item index from a global
    /// counter (persistent threads with in-kernel loops, a regenerate step with host loops).
    Regeneration,
    /// Host loops only: surviving items are compacted into the next kernel's queue through an
    /// atomic counter, and new items fill the pool up behind them (streaming).
    Compaction,
}

/// Where a chain's loop passes repeat.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum LoopMode {
    /// Inside the kernel, with the item in registers.
    #[default]
    InKernel,
    /// One iteration per dispatch, driven by the host while items are alive, with the item
    /// stored between dispatches.
    Host,
}

fn default_workgroup() -> u32 {
    64
}

impl Default for LayoutDecl {
    fn default() -> Self {
        LayoutDecl {
            description: String::new(),
            kernels: Vec::new(),
            state: StateStorage::default(),
            workgroup_size: default_workgroup(),
            max_items_in_flight: None,
            loops: LoopMode::default(),
            policy: Policy::default(),
            threads: None,
            regenerate_at: None,
            hints: BTreeMap::new(),
            constants: BTreeMap::new(),
            loop_guards: default_loop_guards(),
        }
    }
}

/// A layout as a graph file writes it: the fields it gives, and the layout it is `like`, whose
/// fields it takes where it gives none (resolved when the file is read); a field given by
/// neither takes its default. So a layout names only how it differs, e.g.
/// `"StreamingPTmk2": (like: "RegenerationPTmk2", policy: Compaction)`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LayoutWritten {
    /// Another layout of the graph (or of the graph it extends) whose fields this one takes
    /// where it gives none, each field whole (a map given here replaces that layout's); that
    /// layout may itself be `like` a third. A `like` of no layout, or a cycle, is an error.
    pub like: Option<String>,
    /// [`LayoutDecl::description`].
    pub description: Option<String>,
    /// [`LayoutDecl::kernels`].
    pub kernels: Option<Vec<Vec<String>>>,
    /// [`LayoutDecl::state`].
    pub state: Option<StateStorage>,
    /// [`LayoutDecl::workgroup_size`].
    pub workgroup_size: Option<u32>,
    /// [`LayoutDecl::max_items_in_flight`].
    pub max_items_in_flight: Option<u64>,
    /// [`LayoutDecl::loops`].
    pub loops: Option<LoopMode>,
    /// [`LayoutDecl::policy`].
    pub policy: Option<Policy>,
    /// [`LayoutDecl::threads`].
    pub threads: Option<u64>,
    /// [`LayoutDecl::regenerate_at`].
    pub regenerate_at: Option<f32>,
    /// [`LayoutDecl::hints`].
    pub hints: Option<BTreeMap<String, String>>,
    /// [`LayoutDecl::constants`].
    pub constants: Option<BTreeMap<String, ConstValue>>,
    /// [`LayoutDecl::loop_guards`].
    pub loop_guards: Option<bool>,
}

impl LayoutWritten {
    /// This layout with each field it does not give taken from `base` (a whole field: a map
    /// given here replaces the base's), no longer `like` anything.
    pub fn over(self, base: &LayoutWritten) -> LayoutWritten {
        LayoutWritten {
            like: None,
            description: self.description.or_else(|| base.description.clone()),
            kernels: self.kernels.or_else(|| base.kernels.clone()),
            state: self.state.or(base.state),
            workgroup_size: self.workgroup_size.or(base.workgroup_size),
            max_items_in_flight: self.max_items_in_flight.or(base.max_items_in_flight),
            loops: self.loops.or(base.loops),
            policy: self.policy.or(base.policy),
            threads: self.threads.or(base.threads),
            regenerate_at: self.regenerate_at.or(base.regenerate_at),
            hints: self.hints.or_else(|| base.hints.clone()),
            constants: self.constants.or_else(|| base.constants.clone()),
            loop_guards: self.loop_guards.or(base.loop_guards),
        }
    }

    /// The layout, with [`LayoutDecl`]'s defaults for the fields it does not give.
    pub fn decl(&self) -> LayoutDecl {
        let d = LayoutDecl::default();
        LayoutDecl {
            description: self.description.clone().unwrap_or(d.description),
            kernels: self.kernels.clone().unwrap_or(d.kernels),
            state: self.state.unwrap_or(d.state),
            workgroup_size: self.workgroup_size.unwrap_or(d.workgroup_size),
            max_items_in_flight: self.max_items_in_flight.or(d.max_items_in_flight),
            loops: self.loops.unwrap_or(d.loops),
            policy: self.policy.unwrap_or(d.policy),
            threads: self.threads.or(d.threads),
            regenerate_at: self.regenerate_at.or(d.regenerate_at),
            hints: self.hints.clone().unwrap_or(d.hints),
            constants: self.constants.clone().unwrap_or(d.constants),
            loop_guards: self.loop_guards.unwrap_or(d.loop_guards),
        }
    }
}
