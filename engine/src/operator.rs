//! The engine's collective operators as graph nodes: `Clear`, `Scan` (exclusive prefix sum),
//! the `Count` and `Scatter` steps of a counting sort, and `Sort` (a stable radix sort). Each runs over a whole buffer, so
//! it is a barrier: it never shares a kernel with a pass, and it runs between the phases
//! declared before and after it. Their kernels are written once in the engine
//! ([`crate::collective`]). A declared operator names its resources (`R = String`); the live
//! graph's name them by [`ResourceId`], interned where the live graph is built.

use crate::expr::Expr;
use crate::ids::{OpId, ResourceId, indexes};
use crate::ir::{ConstValue, PassEntry};

/// Where a start pass or an operator runs; `R` names resources (a name, or an id).
#[derive(Debug, Clone, PartialEq)]
pub struct Domain<R = String> {
    /// The elements, or with `counted` the most there can be (evaluated on the host, per
    /// frame when it names parameters).
    pub over: Expr,
    /// A resource whose first `u32` holds the element count, read on the GPU.
    pub counted: Option<R>,
}

/// What an operator does, with the buffers it touches; `R` names resources (a name, or an id).
#[derive(Debug, Clone, PartialEq)]
pub enum OpKind<R = String> {
    /// Fills elements `first .. first + over` of `buffer` with `value`.
    Clear {
        /// The buffer.
        buffer: R,
        /// The 32-bit word written.
        value: ConstValue,
        /// First element.
        first: Option<Expr>,
    },
    /// `output[i] = input[0] + ... + input[i - 1]`, of `u32` words or of `f32`s.
    Scan {
        /// The summed elements.
        input: R,
        /// The sums, of the input's type (may be `input`).
        output: R,
    },
    /// `slots[i] = counts[keys[i]]++`.
    Count {
        /// Buckets.
        keys: R,
        /// Bucket counters.
        counts: R,
        /// Slots in the buckets.
        slots: R,
    },
    /// `output[offsets[keys[i]] + slots[i]] = input[i]`, or `= i` without an input.
    Scatter {
        /// Buckets.
        keys: R,
        /// Slots in the buckets.
        slots: R,
        /// First place of each bucket.
        offsets: R,
        /// Elements; `None` moves each element's index.
        input: Option<R>,
        /// Sorted elements (or their indices).
        output: R,
    },
    /// `output[i] = input[indices[i]]`.
    Gather {
        /// Each element's place in `input`.
        indices: R,
        /// Elements.
        input: R,
        /// The elements in the order of `indices`.
        output: R,
    },
    /// Stable ascending sort of `keys` by their low `bits` bits, `values` (if any) moved
    /// alongside.
    Sort {
        /// The `u32` keys, sorted in place.
        keys: R,
        /// The `u32` values, if any.
        values: Option<R>,
        /// Low bits sorted by, 1 to 32.
        bits: u32,
    },
}

impl<R> OpKind<R> {
    /// The kind with its resources named by `f` of their names here.
    fn map<S>(&self, f: &impl Fn(&R) -> S) -> OpKind<S> {
        match self {
            OpKind::Clear { buffer, value, first } => OpKind::Clear {
                buffer: f(buffer),
                value: *value,
                first: first.clone(),
            },
            OpKind::Scan { input, output } => OpKind::Scan {
                input: f(input),
                output: f(output),
            },
            OpKind::Count { keys, counts, slots } => OpKind::Count {
                keys: f(keys),
                counts: f(counts),
                slots: f(slots),
            },
            OpKind::Scatter {
                keys,
                slots,
                offsets,
                input,
                output,
            } => OpKind::Scatter {
                keys: f(keys),
                slots: f(slots),
                offsets: f(offsets),
                input: input.as_ref().map(f),
                output: f(output),
            },
            OpKind::Gather { indices, input, output } => OpKind::Gather {
                indices: f(indices),
                input: f(input),
                output: f(output),
            },
            OpKind::Sort { keys, values, bits } => OpKind::Sort {
                keys: f(keys),
                values: values.as_ref().map(f),
                bits: *bits,
            },
        }
    }
}

/// A collective operator of a graph; `R` names resources (a name, or an id).
#[derive(Debug, Clone, PartialEq)]
pub struct Operator<R = String> {
    /// Its name (unique among passes and operators).
    pub name: String,
    /// What it does.
    pub kind: OpKind<R>,
    /// Its elements; `None` for a `Clear` of the whole buffer.
    pub domain: Option<Domain<R>>,
    /// Constant condition, as written; culled when it is 0.
    pub enabled: Option<String>,
    /// The file that declares it.
    pub origin: String,
}

indexes!(OpId => Operator<ResourceId>);

impl Operator {
    /// The operator of a graph entry, or `None` for a pass entry. An error gives the text
    /// that does not parse and why.
    pub fn from_entry(entry: &PassEntry, origin: &str) -> Option<Result<Operator, (String, String)>> {
        if matches!(entry, PassEntry::Use(_) | PassEntry::UseWith(_) | PassEntry::Pass(_)) {
            return None;
        }
        Some(Self::build(entry, origin))
    }

    fn build(entry: &PassEntry, origin: &str) -> Result<Operator, (String, String)> {
        let parse = |text: &str| Expr::parse(text).map_err(|e| (text.to_string(), e));
        let domain = |over: &str, counted: &Option<String>| -> Result<Domain, (String, String)> {
            Ok(Domain {
                over: parse(over)?,
                counted: counted.clone(),
            })
        };
        let (name, kind, domain, enabled) = match entry {
            PassEntry::Use(_) | PassEntry::UseWith(_) | PassEntry::Pass(_) => unreachable!("operators only"),
            PassEntry::Clear(d) => {
                let kind = OpKind::Clear {
                    buffer: d.buffer.clone(),
                    value: d.value,
                    first: d.first.as_deref().map(parse).transpose()?,
                };
                let domain = d.count.as_deref().map(|c| domain(c, &None)).transpose()?;
                (&d.name, kind, domain, &d.enabled)
            }
            PassEntry::Scan(d) => {
                let kind = OpKind::Scan {
                    input: d.input.clone(),
                    output: d.output.clone().unwrap_or_else(|| d.input.clone()),
                };
                (&d.name, kind, Some(domain(&d.over, &d.counted)?), &d.enabled)
            }
            PassEntry::Count(d) => {
                let kind = OpKind::Count {
                    keys: d.keys.clone(),
                    counts: d.counts.clone(),
                    slots: d.slots.clone(),
                };
                (&d.name, kind, Some(domain(&d.over, &d.counted)?), &d.enabled)
            }
            PassEntry::Scatter(d) => {
                let kind = OpKind::Scatter {
                    keys: d.keys.clone(),
                    slots: d.slots.clone(),
                    offsets: d.offsets.clone(),
                    input: d.input.clone(),
                    output: d.output.clone(),
                };
                (&d.name, kind, Some(domain(&d.over, &d.counted)?), &d.enabled)
            }
            PassEntry::Gather(d) => {
                let kind = OpKind::Gather {
                    indices: d.indices.clone(),
                    input: d.input.clone(),
                    output: d.output.clone(),
                };
                (&d.name, kind, Some(domain(&d.over, &d.counted)?), &d.enabled)
            }
            PassEntry::Sort(d) => {
                if !(1..=32).contains(&d.bits) {
                    let why = format!("operator '{}': bits {} is not in 1..=32", d.name, d.bits);
                    return Err((d.name.clone(), why));
                }
                let kind = OpKind::Sort {
                    keys: d.keys.clone(),
                    values: d.values.clone(),
                    bits: d.bits,
                };
                (&d.name, kind, Some(domain(&d.over, &d.counted)?), &d.enabled)
            }
        };
        Ok(Operator {
            name: name.clone(),
            kind,
            domain,
            enabled: enabled.clone(),
            origin: origin.to_string(),
        })
    }
}

impl<R> Operator<R> {
    /// The operator with its resources named by `f` of their names here (the live graph's
    /// ids of a declared operator's names).
    pub fn map<S>(&self, f: &impl Fn(&R) -> S) -> Operator<S> {
        Operator {
            name: self.name.clone(),
            kind: self.kind.map(f),
            domain: self.domain.as_ref().map(|d| Domain {
                over: d.over.clone(),
                counted: d.counted.as_ref().map(f),
            }),
            enabled: self.enabled.clone(),
            origin: self.origin.clone(),
        }
    }

    /// What the operator is, in words.
    pub fn describe(&self) -> &'static str {
        match self.kind {
            OpKind::Clear { .. } => "clear",
            OpKind::Scan { .. } => "exclusive scan",
            OpKind::Count { .. } => "count (counting sort)",
            OpKind::Scatter { .. } => "scatter (counting sort)",
            OpKind::Gather { .. } => "gather",
            OpKind::Sort { .. } => "radix sort",
        }
    }

    /// Resources it reads (its GPU counter included).
    pub fn reads(&self) -> Vec<&R> {
        let mut out: Vec<&R> = match &self.kind {
            OpKind::Clear { .. } => vec![],
            OpKind::Scan { input, .. } => vec![input],
            OpKind::Count { keys, counts, .. } => vec![keys, counts],
            OpKind::Scatter {
                keys,
                slots,
                offsets,
                input,
                ..
            } => [keys, slots, offsets].into_iter().chain(input).collect(),
            OpKind::Gather { indices, input, .. } => vec![indices, input],
            OpKind::Sort { keys, values, .. } => [keys].into_iter().chain(values).collect(),
        };
        if let Some(c) = self.domain.as_ref().and_then(|d| d.counted.as_ref()) {
            out.push(c);
        }
        out
    }

    /// Resources it writes.
    pub fn writes(&self) -> Vec<&R> {
        match &self.kind {
            OpKind::Clear { buffer, .. } => vec![buffer],
            OpKind::Scan { output, .. } => vec![output],
            OpKind::Count { counts, slots, .. } => vec![counts, slots],
            OpKind::Scatter { output, .. } | OpKind::Gather { output, .. } => vec![output],
            OpKind::Sort { keys, values, .. } => [keys].into_iter().chain(values).collect(),
        }
    }

    /// Every resource it touches, with what its elements must be: `u32` words for keys,
    /// slots, counts and sorted values, `u32` words or `f32` for scans (input and output
    /// alike, which the load checks apart).
    pub fn buffers(&self) -> Vec<(&R, Elements)> {
        let mut out: Vec<(&R, Elements)> = match &self.kind {
            OpKind::Clear { buffer, .. } => vec![(buffer, Elements::Any)],
            OpKind::Scan { input, output } => vec![(input, Elements::Summed), (output, Elements::Summed)],
            OpKind::Count { keys, counts, slots } => {
                vec![(keys, Elements::U32), (counts, Elements::U32), (slots, Elements::U32)]
            }
            OpKind::Scatter {
                keys,
                slots,
                offsets,
                input,
                output,
            } => {
                let mut out = vec![(keys, Elements::U32), (slots, Elements::U32), (offsets, Elements::U32)];
                match input {
                    Some(input) => out.extend([(input, Elements::Any), (output, Elements::Any)]),
                    None => out.push((output, Elements::U32)),
                }
                out
            }
            OpKind::Gather { indices, input, output } => {
                vec![
                    (indices, Elements::U32),
                    (input, Elements::Any),
                    (output, Elements::Any),
                ]
            }
            OpKind::Sort { keys, values, .. } => [keys].into_iter().chain(values).map(|r| (r, Elements::U32)).collect(),
        };
        if let Some(c) = self.domain.as_ref().and_then(|d| d.counted.as_ref()) {
            out.push((c, Elements::U32));
        }
        out
    }
}

/// What an operator needs of the elements of a resource it touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Elements {
    /// Any type.
    Any,
    /// 32-bit unsigned words (`u32` or `atomic<u32>`).
    U32,
    /// What a scan sums: `u32` words or `f32`.
    Summed,
}

impl Elements {
    /// Whether a resource of element type `ty` meets the need.
    pub fn accepts(self, ty: &str) -> bool {
        match self {
            Elements::Any => true,
            Elements::U32 => is_u32_word(ty),
            Elements::Summed => summed_type(ty).is_some(),
        }
    }

    /// The need in words, as in "needs u32 elements".
    pub fn describe(self) -> &'static str {
        match self {
            Elements::Any => "any",
            Elements::U32 => "u32",
            Elements::Summed => "u32 or f32",
        }
    }
}

/// Whether a resource's element type `ty` is a 32-bit unsigned word (`u32`, or `atomic<u32>`).
pub fn is_u32_word(ty: &str) -> bool {
    let t: String = ty.chars().filter(|c| !c.is_whitespace()).collect();
    t == "u32" || t == "atomic<u32>"
}

/// The WGSL type a scan sums elements of type `ty` as: `u32` for `u32` words, `f32` for
/// `f32`, `None` for any other type.
pub fn summed_type(ty: &str) -> Option<&'static str> {
    match ty.trim() {
        _ if is_u32_word(ty) => Some("u32"),
        "f32" => Some("f32"),
        _ => None,
    }
}
