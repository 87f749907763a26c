//! Human-readable reports of a compiled program: phases, kernels, schedule, resources and
//! memory.

use crate::codegen::BufferRef;
use crate::ir::Scope;
use crate::plan::{Root, Step};
use crate::program::Program;
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
                let k = program.plan.consumer_kernel(q);
                let _ = writeln!(
                    out,
                    "{pad}drain queue '{q}' -> {} (indirect)",
                    program.plan.kernels[k].name
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

/// The report `lightgraph explain` prints for one layout. `externals` gives the byte size
/// of external resources when a scene is known.
pub fn report(program: &Program, externals: &dyn Fn(&str) -> Option<u64>) -> String {
    let plan = &program.plan;
    let g = &plan.graph;
    let l = &plan.layout;
    let mut out = String::new();
    let _ = writeln!(out, "graph '{}': {}", g.name, g.description);
    let _ = writeln!(out, "layout '{}': {}", plan.layout_name, l.description);
    let _ = writeln!(
        out,
        "  state {:?}, workgroup {}, loops {:?}, max items in flight {}",
        l.state,
        l.workgroup_size,
        l.loops,
        l.max_items_in_flight.map_or("auto".to_string(), |v| v.to_string())
    );
    if !g.culled.is_empty() {
        let _ = writeln!(
            out,
            "culled passes (nothing reads their output): {}",
            g.culled
                .iter()
                .map(|p| p.decl.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(out, "\nphases:");
    for (ph, phase) in g.phases.iter().enumerate() {
        let chains: Vec<String> = phase
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
        let _ = writeln!(
            out,
            "  {ph}: {} items in chunks of {}: {}",
            program.domains[ph],
            program.chunks[ph],
            chains.join("; ")
        );
    }
    let _ = writeln!(out, "\nkernels:");
    for (k, kp) in plan.kernels.iter().enumerate() {
        let passes: Vec<&str> = plan
            .kernel_passes(k)
            .iter()
            .map(|&p| g.passes[p].decl.name.as_str())
            .collect();
        let root = match &kp.root {
            Root::Start => "start (one thread per item)".to_string(),
            Root::State => "state buffer (one thread per slot)".to_string(),
            Root::Queue(q) => format!("queue '{q}' (indirect)"),
            Root::Boundary => format!("boundary {} (indirect, compacted)", kp.input.map_or(0, |p| p.boundary)),
        };
        let module = &program.kernels[k];
        let text = module.source.text();
        let bindings: Vec<String> = module
            .uses
            .iter()
            .map(|u| match &u.buffer {
                BufferRef::Resource(r) => r.clone(),
                other => format!("{other:?}").to_lowercase(),
            })
            .collect();
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
            text.lines().count(),
            text.len(),
            bindings.join(", ")
        );
    }
    let _ = writeln!(out, "\nschedule per chunk:");
    for (ph, steps) in plan.schedule.iter().enumerate() {
        let _ = writeln!(out, "  phase {ph}:");
        steps_text(program, steps, 4, &mut out);
    }
    let _ = writeln!(out, "\nresources:");
    let mut total = 0u64;
    for (name, r) in &g.resources {
        let size = &program.sizes[name];
        let (count, bytes) = match size.count {
            Some(c) => (c.to_string(), Some(c * size.element_bytes as u64)),
            None => ("from scene".to_string(), externals(name)),
        };
        if let Some(b) = bytes {
            total += b;
        }
        let scope = match r.scope {
            Scope::Persistent => "persistent",
            Scope::Transient => "transient",
            Scope::External => "external",
        };
        let _ = writeln!(
            out,
            "  {name}: {} x {count} ({} B each) = {}, {scope}",
            r.ty,
            size.element_bytes,
            bytes.map_or("?".into(), mib)
        );
    }
    let allocated = program.allocated_bytes();
    for (name, bytes) in &allocated {
        if !g.resources.contains_key(name) {
            let _ = writeln!(out, "  {name}: {}", mib(*bytes));
            total += bytes;
        }
    }
    let layout_bytes: u64 = allocated
        .iter()
        .filter(|(n, _)| !g.resources.contains_key(*n))
        .map(|(_, b)| b)
        .sum();
    let _ = writeln!(
        out,
        "\nGPU memory: {} in all, of which {} for this layout's item state and queues",
        mib(total),
        mib(layout_bytes)
    );
    out
}
