//! Reads and writes derived from the WGSL, once the constants are known and before culling: a
//! pass that leaves out `reads` or `writes` gets the resources its function, and everything it
//! calls, reads or writes in naga's view of every source compiled together, preprocessed with
//! the specialisation's flags (a resource used only under a flag that is off is not used).
//! Listed ones are kept as listed; the reflect stage checks them against the same view. Also
//! the WGSL declarations every source is compiled with (the frame record, constants, counters,
//! resources, the emits that do nothing), which code generation writes too.

use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::ir::{ConstValue, ResourceDecl};
use crate::limits::FRAME_BINDING;
use crate::wgsl::{ModuleSource, preprocess};
use crate::{hooks, item_fields};
use naga::valid::GlobalUse;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;

/// `lg_slot`, which passes may read: the slot the thread's item holds in its chain's state
/// buffer (below `ITEM_SLOTS`, which a resource's count may use) in kernels of a chain stored
/// between kernels; the thread's index in others.
pub const SLOT_DECLARATION: &str = "var<private> lg_slot: u32;\n";

/// The most constants not known yet (host constants, in the default constants' view) that a
/// derivation declares as `u32` placeholders before it gives up.
const MAX_PLACEHOLDERS: usize = 64;

/// The WGSL type a parameter's field of the frame record has (a `bool` is held as `u32`).
fn parameter_field_type(v: &ConstValue) -> &'static str {
    match v {
        ConstValue::Bool(_) => "u32",
        other => other.wgsl_type(),
    }
}

/// The frame record: index, seed, first item and item count of the chunk, then the
/// parameters; each parameter is also a private variable, set by the entry point.
pub fn frame_record(parameters: &[(String, ConstValue)]) -> String {
    let mut s = String::from("struct Frame {\n    index: u32,\n    seed: u32,\n    base: u32,\n    count: u32,\n");
    for (name, v) in parameters {
        let _ = writeln!(s, "    lg_{name}: {},", parameter_field_type(v));
    }
    s.push_str("}\n");
    for (name, v) in parameters {
        let _ = writeln!(s, "var<private> {name}: {};", v.wgsl_type());
    }
    s.push_str("fn lg_parameters() {\n");
    for (name, v) in parameters {
        let read = match v {
            ConstValue::Bool(_) => format!("frame.lg_{name} != 0u"),
            _ => format!("frame.lg_{name}"),
        };
        let _ = writeln!(s, "    {name} = {read};");
    }
    s.push_str("}\n");
    s
}

/// The constants, the counters' numbers and `count`.
pub fn constant_declarations(constants: &BTreeMap<String, ConstValue>, counters: &[String]) -> String {
    let mut s = String::new();
    for (name, v) in constants {
        let _ = writeln!(s, "const {name}: {} = {};", v.wgsl_type(), v.wgsl_literal());
    }
    // Counts add up in workgroup memory (no register per counter held through the kernel:
    // VCMsk 7-9% faster on Sponza on an H100, docs/performance.md); `lg_flush` adds them up.
    for (i, c) in counters.iter().enumerate() {
        let _ = writeln!(s, "const COUNTER_{}: u32 = {i}u;", c.to_uppercase());
    }
    let _ = writeln!(
        s,
        "var<workgroup> lg_wg_counts: array<atomic<u32>, {}>;",
        counters.len().max(1)
    );
    s.push_str("fn count(counter: u32, n: u32) {\n    atomicAdd(&lg_wg_counts[counter], n);\n}\n");
    s
}

/// The declaration of resource `name` at `binding` of group 0.
pub fn resource_declaration(name: &str, r: &ResourceDecl, binding: u32, writable: bool) -> String {
    let access = if writable { "read_write" } else { "read" };
    let ty = if r.count.is_some() {
        format!("array<{}>", r.ty)
    } else {
        r.ty.clone()
    };
    format!("@group(0) @binding({binding}) var<storage, {access}> {name}: {ty};\n")
}

/// Emit functions that do nothing: enough to type-check the passes.
pub fn stub_emits(graph: &Graph) -> String {
    let mut s = String::new();
    for st in &graph.streams {
        let _ = writeln!(s, "fn emit_{}(item: {}) {{}}", st.name, st.decl.item);
    }
    s
}

/// The flags of `#if` lines: the host's, and every `Bool` constant that is true (a graph
/// switches code in its library files with its own constants).
fn flags_with_constants(flags: &BTreeSet<String>, constants: &BTreeMap<String, ConstValue>) -> BTreeSet<String> {
    let on = constants.iter().filter(|(_, v)| matches!(v, ConstValue::Bool(true)));
    flags.iter().cloned().chain(on.map(|(k, _)| k.clone())).collect()
}

/// How a graph's replaced hooks join its sources.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Hooks {
    /// In place of the defaults, which are renamed so that nothing calls them.
    Replace,
    /// Beside the defaults, renamed (to compare their signatures).
    Beside,
}

/// The library and the pass sources of every declared pass of `graph` (a live pass may call
/// functions a culled pass's file defines; what no kernel calls is shaken out later),
/// preprocessed with `flags` and the graph's true `Bool` constants, then the files of its
/// replaced hooks, with the fields it adds to items written in.
pub fn sources(graph: &Graph, flags: &BTreeSet<String>) -> Result<Vec<(String, String)>> {
    sources_with(graph, flags, Hooks::Replace)
}

/// [`sources`] with the replaced hooks joining as `mode` says.
pub(crate) fn sources_with(graph: &Graph, flags: &BTreeSet<String>, mode: Hooks) -> Result<Vec<(String, String)>> {
    let flags = &flags_with_constants(flags, &graph.constants);
    let g = graph;
    let hooks = &g.declared.file.hooks;
    let mut files = g.declared.wgsl_files();
    let mut hook_files: Vec<&String> = hooks.values().filter(|f| !files.contains(f)).collect();
    hook_files.sort();
    hook_files.dedup();
    files.extend(hook_files.into_iter().cloned());
    let mut shared = Vec::new();
    for f in &files {
        let mut text = g.vfs.read(f).map_err(|e| g.error_at(f, e.to_string()))?;
        for (name, file) in hooks {
            text = match mode {
                Hooks::Replace if file != f && hooks::declares(f, &text, name) => {
                    hooks::renamed(&text, name, &hooks::default_name(name))
                }
                Hooks::Beside if file == f => hooks::renamed(&text, name, &hooks::candidate_name(name)),
                _ => text,
            };
        }
        shared.push((f.clone(), preprocess(f, &text, flags)?));
    }
    let fields = &g.declared.file.item_fields;
    if !fields.is_empty() {
        for (_, text) in &mut shared {
            *text = item_fields::added(text, fields);
        }
    }
    Ok(shared)
}

/// Checks each hook `graph` replaces against its default, the two compiled beside each other
/// with `flags` (before any compile that calls the replacements): a pass calls it, and the
/// signatures agree ([`hooks::check_compiled`]).
pub(crate) fn check_hooks(graph: &Graph, flags: &BTreeSet<String>) -> Result<()> {
    let hooks = &graph.declared.file.hooks;
    if hooks.is_empty() {
        return Ok(());
    }
    let (module, _) = compile_all(graph, flags, Hooks::Beside)?;
    let mut replaced = Vec::new();
    for (name, file) in hooks {
        let text = graph.vfs.read(file)?;
        replaced.push(hooks::Replaced {
            name: name.clone(),
            file: file.clone(),
            text,
        });
    }
    let known = hooks::declared_hooks(&graph.declared, &graph.vfs, &graph.file)?;
    let passes: Vec<&str> = graph.declared.passes.iter().map(|p| p.function()).collect();
    let unused = |name: &str, message: String| graph.declared.sources.at_key(&graph.file, name, message);
    hooks::check_compiled(&module, &passes, &replaced, &known, unused)
}

/// The constant a naga error says has no definition, when its name is one a constant could
/// have (upper case): a host constant the default constants' view does not know yet.
fn unknown_constant(e: &Error) -> Option<String> {
    let Error::Shader(message) = e else { return None };
    let (_, rest) = message.split_once("no definition in scope for identifier: `")?;
    let name = rest.split('`').next()?;
    let constant_like = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
    constant_like.then(|| name.to_string())
}

/// What `graph`'s WGSL looks like to naga with `flags`: every source compiled together with the
/// declarations (resources and candidates all writable, so that a store the lists do not show
/// yet compiles) and emits that do nothing. A constant not known yet (`PIXELS` before the host
/// gives it, in the default constants' view or a view of some constants only) is declared as a
/// `u32`, as the host's are; where it is not one, the compile fails.
fn compile_all(
    graph: &Graph,
    flags: &BTreeSet<String>,
    hooks: Hooks,
) -> Result<(naga::Module, naga::valid::ModuleInfo)> {
    let shared = sources_with(graph, flags, hooks)?;
    let parameters: Vec<(String, ConstValue)> = graph.parameters.iter().map(|(k, v)| (k.clone(), *v)).collect();
    let mut declarations = frame_record(&parameters);
    declarations.push_str(FRAME_BINDING);
    declarations.push_str(SLOT_DECLARATION);
    declarations.push_str(&constant_declarations(&graph.constants, &graph.counters));
    let candidates = graph
        .declared
        .candidates
        .iter()
        .filter(|(n, _)| !graph.resource_by_name.contains_key(*n));
    let live = graph.resources.iter().map(|r| (&r.name, &r.decl));
    for (i, (name, r)) in live.chain(candidates).enumerate() {
        declarations.push_str(&resource_declaration(name, r, i as u32, true));
    }
    let emits = stub_emits(graph);
    let mut unknown = String::new();
    for _ in 0..=MAX_PLACEHOLDERS {
        let mut src = ModuleSource::default();
        src.push("<generated declarations>", &declarations);
        src.push("<constants not known yet>", &unknown);
        for (f, text) in &shared {
            src.push(f, text);
        }
        src.push("<generated emits>", &emits);
        match src.compile(naga::valid::Capabilities::all()) {
            Ok(compiled) => return Ok(compiled),
            Err(e) => match unknown_constant(&e) {
                Some(name) if !graph.constants.contains_key(&name) => {
                    let _ = writeln!(unknown, "const {name}: u32 = 1u;");
                }
                _ => return Err(e),
            },
        }
    }
    Err(Error::Shader(format!(
        "graph '{}': its WGSL names more than {MAX_PLACEHOLDERS} constants that are neither the graph's nor the host's",
        graph.name
    )))
}

impl Graph {
    /// Fills `reads` and `writes` of every declared pass that leaves them out with the
    /// resources its function uses when compiled with `flags` (a resource in `writes` where
    /// the function stores to it or changes it atomically, in `reads` where it loads from it,
    /// changes it atomically or asks its length). A pass whose function is missing derives
    /// nothing; the reflect stage reports it. A candidate resource (a catalog's that no pass
    /// lists) that a pass uses joins the graph's resources.
    pub(crate) fn derive_access(&mut self, flags: &BTreeSet<String>) -> Result<()> {
        self.intern_resources(self.used_declarations());
        if self
            .declared
            .passes
            .iter()
            .all(|p| p.decl.listed_reads.is_some() && p.decl.listed_writes.is_some())
        {
            return Ok(());
        }
        let key = flags_with_constants(flags, &self.constants);
        let known = self
            .derivations
            .lock()
            .expect("no derivation panicked")
            .get(&key)
            .cloned();
        match known {
            Some(lists) => {
                for (p, (reads, writes)) in self.declared.passes.iter_mut().zip(lists) {
                    (p.decl.reads, p.decl.writes) = (reads, writes);
                }
            }
            None => {
                self.derive_uses(flags)?;
                let lists = self
                    .declared
                    .passes
                    .iter()
                    .map(|p| (p.decl.reads.clone(), p.decl.writes.clone()))
                    .collect();
                self.derivations
                    .lock()
                    .expect("no derivation panicked")
                    .insert(key, lists);
            }
        }
        self.intern_resources(self.used_declarations());
        Ok(())
    }

    /// The declared resources, and the candidates some declared pass reads or writes.
    fn used_declarations(&self) -> BTreeMap<String, ResourceDecl> {
        let mut resources = self.declared.resources.clone();
        for p in &self.declared.passes {
            for r in p.decl.reads.iter().chain(&p.decl.writes) {
                if let Some(decl) = self.declared.candidates.get(r) {
                    resources.insert(r.clone(), decl.clone());
                }
            }
        }
        resources
    }

    /// Fills the lists passes leave out from naga's view of the sources with `flags`.
    fn derive_uses(&mut self, flags: &BTreeSet<String>) -> Result<()> {
        let (module, info) = compile_all(self, flags, Hooks::Replace)?;
        let resources: Vec<(naga::Handle<naga::GlobalVariable>, &str)> = module
            .global_variables
            .iter()
            .filter_map(|(h, v)| v.name.as_deref().map(|n| (h, n)))
            .filter(|(_, n)| self.resource_by_name.contains_key(*n) || self.declared.candidates.contains_key(*n))
            .collect();
        for p in &mut self.declared.passes {
            let Some((h, _)) = module
                .functions
                .iter()
                .find(|(_, f)| f.name.as_deref() == Some(p.function()))
            else {
                continue;
            };
            let uses = &info[h];
            let with = |test: &dyn Fn(GlobalUse) -> bool| -> Vec<String> {
                resources
                    .iter()
                    .filter(|(gh, _)| test(uses[*gh]))
                    .map(|(_, n)| n.to_string())
                    .collect()
            };
            if p.decl.listed_reads.is_none() {
                p.decl.reads = with(&|u| !(u - GlobalUse::WRITE).is_empty());
            }
            if p.decl.listed_writes.is_none() {
                p.decl.writes = with(&|u| u.contains(GlobalUse::WRITE));
            }
        }
        Ok(())
    }
}
