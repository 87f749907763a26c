//! Human-readable reports of a compiled program: what was culled and why, the frame's steps,
//! phases, kernels, the schedule, resources with their lifetimes, which buffers share memory,
//! and peak memory.

use crate::codegen::slot_traffic;
use crate::graph::FrameStep;
use crate::ids::PhaseId;
use crate::ir::Scope;
use crate::plan::{Root, Step};
use crate::program::Program;
use crate::resolve::BufferRef;
use std::fmt::Write;

fn mib(bytes: u64) -> String {
    if bytes >= 1 << 20 {
        format!("{:.1} MiB", bytes as f64 / 1048576.0)
    } else {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    }
}

fn steps_text(program: &Program, steps: &[Step], indent: usize, out: &mut String) {
    let pad = " ".repeat(indent);
    for s in steps {
        match s {
            Step::Run(k) => {
                let _ = writeln!(out, "{pad}run {}", program.plan.kernels[*k].name);
            }
            Step::Drain(q) => {
                let k = program.plan.consumer_kernel(*q);
                let _ = writeln!(
                    out,
                    "{pad}drain queue '{}' -> {} (indirect)",
                    program.plan.graph.streams[*q].name, program.plan.kernels[k].name
                );
            }
            Step::Loop { chain, body } => {
                let _ = writeln!(
                    out,
                    "{pad}while items of '{}' are alive:",
                    program.plan.graph.chains[*chain].item
                );
                steps_text(program, body, indent + 2, out);
            }
        }
    }
}

/// A frame step in words.
fn step_name(program: &Program, s: usize) -> String {
    let g = &program.plan.graph;
    match g.steps[s] {
        FrameStep::Phase(ph) => format!("phase {ph}"),
        FrameStep::Op(o) => format!("operator '{}'", g.ops[o].name),
    }
}

/// The report `lightgraph explain` prints for one layout. `externals` gives the byte size
/// of external resources when a scene is known.
pub fn report(program: &Program, externals: &dyn Fn(&str) -> Option<u64>) -> String {
    let mut out = String::new();
    header(program, &mut out);
    frame(program, &mut out);
    kernels(program, &mut out);
    resources(program, externals, &mut out);
    memory(program, &mut out);
    out
}

fn header(program: &Program, out: &mut String) {
    let plan = &program.plan;
    let g = &plan.graph;
    let l = &plan.layout;
    let _ = writeln!(out, "graph '{}': {}", g.name, g.description);
    let _ = writeln!(out, "layout '{}': {}", plan.layout_name, l.description);
    let _ = writeln!(
        out,
        "  state {:?}, workgroup {}, loops {:?}, max items in flight {}, loop guards {}",
        l.state,
        l.workgroup_size,
        l.loops,
        l.max_items_in_flight.map_or("auto".to_string(), |v| v.to_string()),
        if l.loop_guards { "on" } else { "off" }
    );
    if !g.culled.is_empty() {
        let _ = writeln!(out, "culled:");
        for c in &g.culled {
            let _ = writeln!(out, "  {}: {}", c.name, c.reason);
        }
    }
    let derived: Vec<String> = g
        .passes
        .iter()
        .filter_map(|p| {
            let d = &p.decl;
            let list = |l: &[String]| {
                if l.is_empty() {
                    "nothing".to_string()
                } else {
                    l.join(", ")
                }
            };
            let mut parts = Vec::new();
            if d.listed_reads.is_none() {
                parts.push(format!("reads {}", list(&d.reads)));
            }
            if d.listed_writes.is_none() {
                parts.push(format!("writes {}", list(&d.writes)));
            }
            (!parts.is_empty()).then(|| format!("  {}: {}", d.name, parts.join("; ")))
        })
        .collect();
    if !derived.is_empty() {
        let _ = writeln!(out, "derived from the WGSL (the passes leave them out):");
        for line in derived {
            let _ = writeln!(out, "{line}");
        }
    }
    if !g.parameters.is_empty() {
        let list: Vec<String> = g
            .parameters
            .iter()
            .map(|(k, v)| format!("{k}: {} = {}", v.wgsl_type(), v.wgsl_literal()))
            .collect();
        let _ = writeln!(out, "per-frame parameters: {}", list.join(", "));
    }
}

fn frame(program: &Program, out: &mut String) {
    let g = &program.plan.graph;
    let _ = writeln!(out, "\nframe steps:");
    for (s, step) in g.steps.iter().enumerate() {
        match *step {
            FrameStep::Phase(ph) => {
                let chains: Vec<String> = g.phases[ph]
                    .chains
                    .iter()
                    .map(|&c| {
                        let names: Vec<&str> = g.chains[c]
                            .passes
                            .iter()
                            .map(|&p| g.passes[p].decl.name.as_str())
                            .collect();
                        format!("{} [{}]", g.chains[c].item, names.join(" -> "))
                    })
                    .collect();
                let d = &program.resolved.domains[ph.0];
                let counted = d.counted.map_or(String::new(), |c| {
                    format!(" (counted on the GPU by '{}')", g.resources[c].name)
                });
                let _ = writeln!(
                    out,
                    "  {s}: phase {ph}: {}{counted} items in chunks of {}: {}",
                    if d.counted.is_some() {
                        format!("at most {}", d.default)
                    } else {
                        d.default.to_string()
                    },
                    d.chunk,
                    chains.join("; ")
                );
            }
            FrameStep::Op(o) => {
                let op = &g.ops[o];
                let n = program.resolved.op_elements[&o];
                let counted = op.domain.as_ref().and_then(|d| d.counted).map_or(String::new(), |c| {
                    format!(" (at most; counted on the GPU by '{}')", g.resources[c].name)
                });
                let kernels: Vec<&str> = program.ops[o.0].kernels.iter().map(|(k, _)| k.name.as_str()).collect();
                let _ = writeln!(
                    out,
                    "  {s}: operator '{}': {} over {n} elements{counted}, kernels {}",
                    op.name,
                    op.describe(),
                    kernels.join(", ")
                );
            }
        }
    }
}

fn kernels(program: &Program, out: &mut String) {
    let plan = &program.plan;
    let g = &plan.graph;
    let _ = writeln!(out, "\nkernels:");
    for k in plan.kernel_ids() {
        let kp = &plan.kernels[k];
        let passes: Vec<&str> = plan
            .kernel_passes(k)
            .iter()
            .map(|&p| g.passes[p].decl.name.as_str())
            .collect();
        let root = match &kp.root {
            Root::Start if program.domains.contains_key(&kp.phase) => {
                "start (one thread per item, indirect from the GPU count)".to_string()
            }
            Root::Start => "start (one thread per item)".to_string(),
            Root::State => "state buffer (one thread per slot)".to_string(),
            Root::Queue(q) => format!("queue '{}' (indirect)", g.streams[*q].name),
            Root::Boundary => format!(
                "boundary {} (indirect, compacted)",
                kp.input.map_or(0, |p| p.boundary.0)
            ),
        };
        let module = &program.kernels[k.0];
        let text = module.source.text();
        let bindings: Vec<String> = module.uses.iter().map(|u| u.buffer.describe(plan)).collect();
        let _ = writeln!(
            out,
            "  {}: passes [{}], fed by {root}{}, {} WGSL lines ({} bytes)\n    binds: {}",
            kp.name,
            passes.join(", "),
            if kp.loop_in_kernel && g.chains[kp.chain].loop_start.is_some() {
                ", loop in kernel"
            } else {
                ""
            },
            text.lines().filter(|l| !l.trim().is_empty()).count(),
            text.len(),
            bindings.join(", ")
        );
        if let Some(t) = slot_traffic(plan, &program.resolved, k) {
            let _ = writeln!(
                out,
                "    item in its slot: loads {} and stores {} of its {} words",
                t.load.len(),
                t.store.len(),
                t.words
            );
        }
    }
    let _ = writeln!(out, "\nschedule per chunk:");
    for (ph, steps) in plan.schedule.iter().enumerate() {
        let _ = writeln!(out, "  phase {}:", PhaseId(ph));
        steps_text(program, steps, 4, out);
    }
}

fn resources(program: &Program, externals: &dyn Fn(&str) -> Option<u64>, out: &mut String) {
    let plan = &program.plan;
    let g = &plan.graph;
    let r = &program.resolved;
    let _ = writeln!(out, "\nresources:");
    for id in g.resource_ids() {
        let (name, decl) = (&g.resources[id].name, &g.resources[id].decl);
        let size = &r.sizes[id];
        let (count, bytes) = match size.count {
            Some(c) => (c.to_string(), Some(c * size.element_bytes as u64)),
            None => ("from scene".to_string(), externals(name)),
        };
        let scope = match decl.scope {
            Scope::Persistent => "persistent".to_string(),
            Scope::Transient => {
                let life = r
                    .memory
                    .lifetimes
                    .get(&BufferRef::Resource(id))
                    .map_or("unused".to_string(), |l| {
                        format!("{} .. {}", step_name(program, l.first), step_name(program, l.last))
                    });
                format!(
                    "transient, live {life}{}",
                    if decl.clear { ", cleared first" } else { "" }
                )
            }
            Scope::External => "external".to_string(),
        };
        let unused = if r.used.contains(&id) {
            ""
        } else {
            " (unused: not allocated)"
        };
        let _ = writeln!(
            out,
            "  {name}: {} x {count} ({} B each) = {}, {scope}{unused}",
            decl.ty,
            size.element_bytes,
            bytes.map_or("?".into(), mib)
        );
    }
}

fn memory(program: &Program, out: &mut String) {
    let plan = &program.plan;
    let m = &program.resolved.memory;
    let _ = writeln!(out, "\nengine buffers (item state, queues, scratch):");
    for (b, p) in &m.placements {
        if matches!(b, BufferRef::Resource(_)) {
            continue;
        }
        let life = m
            .lifetimes
            .get(b)
            .map_or(String::new(), |l| format!(", live {}", step_name(program, l.first)));
        let _ = writeln!(out, "  {}: {}{life}", b.describe(plan), mib(p.bytes));
    }
    if !m.arenas.is_empty() {
        let _ = writeln!(out, "\nshared memory:");
        for (a, &size) in m.arenas.iter().enumerate() {
            let _ = writeln!(out, "  arena {a}: {}", mib(size));
            let mut members: Vec<(&BufferRef, &crate::memory::Placement)> =
                m.placements.iter().filter(|(_, p)| p.arena == Some(a)).collect();
            members.sort_by_key(|(_, p)| p.offset);
            for (b, p) in members {
                let l = m.lifetimes[b];
                let _ = writeln!(
                    out,
                    "    {}..{}: {} (steps {}..{})",
                    mib(p.offset),
                    mib(p.offset + p.bytes),
                    b.describe(plan),
                    l.first,
                    l.last
                );
            }
        }
        for (a, b) in m.sharing() {
            let _ = writeln!(out, "  {} shares memory with {}", a.describe(plan), b.describe(plan));
        }
    }
    let externals_note = "besides external scene data";
    let _ = writeln!(
        out,
        "\nGPU memory {externals_note}: peak {} (without sharing {})",
        mib(m.peak_bytes()),
        mib(m.unshared_bytes())
    );
}
