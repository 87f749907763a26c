//! Explaining a graph (`lightgraph explain`, Python's `explain`): the kernels, schedule and
//! resources of its layouts for a scene, or its outline.

use crate::run::{Run, RunOptions, Scenes, load_graph, named_layout};
use anyhow::{Context, Result};
use lightgraph_engine::Gpu;
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_scenes::bvh::BvhKind;
use std::fmt::Write;
use std::path::PathBuf;

/// What to explain: a graph's layouts on a scene, and the files to write.
pub struct ExplainSpec {
    /// The scene, size, constants and switches the kernels are compiled for.
    pub options: RunOptions,
    /// The graph: a built-in name or a .ron graph file.
    pub graph: String,
    /// The layout to explain (None: all of the graph's layouts).
    pub layout: Option<String>,
    /// Also write the graph as Graphviz DOT to this file.
    pub dot: Option<PathBuf>,
    /// Also write each kernel's generated WGSL into this folder.
    pub wgsl: Option<PathBuf>,
}

/// The outline of the graph `args` names, specialised for its scene, size and constants
/// (passes a constant switches off are listed as left out).
pub fn outline(args: &ExplainSpec) -> Result<String> {
    let c = &args.options;
    let graph = load_graph(&args.graph)?;
    let mut scenes = Scenes::new(c.scene());
    let kind = scenes.load_for(c.bvh, &graph.default_layout, &graph.layouts[&graph.default_layout])?;
    let scene = scenes.get(kind);
    let opts = c.options(scene, &graph, 1)?;
    let spec = crate::run::specialization(&graph, &scene.scene, &opts, Default::default());
    Ok(lightgraph_engine::outline::outline(&graph.specialize(&spec.constants)?))
}

/// The explanation of the layouts `args` names: features, measured constants, each layout's
/// kernels, schedule and memory; writes the WGSL and DOT files it asks for.
pub fn report(args: &ExplainSpec) -> Result<String> {
    let mut out = String::new();
    let c = &args.options;
    let graph = load_graph(&args.graph)?;
    let layouts: Vec<(String, LayoutDecl)> = match &args.layout {
        Some(l) => vec![named_layout(&graph, Some(l))?],
        None => graph.layouts.iter().map(|(n, d)| (n.clone(), d.clone())).collect(),
    };
    let mut scenes = Scenes::new(c.scene());
    let kinds: Vec<BvhKind> = layouts
        .iter()
        .map(|(name, decl)| scenes.load_for(c.bvh, name, decl))
        .collect::<Result<_>>()?;
    let gpu = Gpu::new(c.adapter.as_deref()).ok();
    let device = gpu.as_ref().map(crate::run::device_flags).unwrap_or_default();
    features(
        &mut out,
        &crate::run::kernel_flags(device, scenes.get(kinds[0]), c.overrides.all_features),
    )?;
    writeln!(
        out,
        "layouts of graph '{}': {}\n",
        graph.name,
        graph.layouts.keys().cloned().collect::<Vec<_>>().join(", ")
    )?;
    for ((layout, decl), kind) in layouts.into_iter().zip(kinds) {
        writeln!(out, "layout {layout}: BVH {}", kind.name())?;
        let spec = c.spec(&args.graph, Some(&layout), 1);
        let run = Run::with_scene(&spec, graph.clone(), (layout, decl), scenes.shared(kind))?;
        let (layout, opts) = (&run.layout, &run.options);
        let profile = opts.layout.tuning.profile(gpu.as_ref().map(|g| g.info.name.as_str()));
        if let Some((p, k)) = profile.and_then(|p| Some((p, p.knobs(&graph.name, layout)?))) {
            writeln!(out, "tuning profile {}: {} ({})", p.name, k.summary(), k.why)?;
        }
        let camera = lightgraph_scenes::CompiledScene::camera(&run.scene.scene, opts.width, opts.height);
        let externals = run.scene.compiled.resources(&camera);
        // A graph with measured constants (LVC-BPT's average light sub-path length) is
        // measured by a session first, so that the sizes shown are those a render allocates.
        let session = match &gpu {
            Some(g) if !graph.measured.is_empty() => Some(run.session(g)?),
            _ => None,
        };
        let compiled;
        let program = match &session {
            Some(s) => s.program(),
            None => {
                compiled = run.compile(gpu.as_ref())?;
                &compiled
            }
        };
        for name in graph.measured.keys() {
            match (&session, program.constants().get(name)) {
                (Some(_), Some(v)) => writeln!(out, "measured {name} = {v}")?,
                _ => writeln!(
                    out,
                    "{name} not measured (no GPU): sizes that depend on it are shown for its default"
                )?,
            }
        }
        writeln!(
            out,
            "{}",
            lightgraph_engine::explain::report(program, &|name| externals.get(name).map(|b| b.len() as u64))
        )?;
        if let Some(dir) = &args.wgsl {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            let operator_kernels = program.ops.iter().flat_map(|op| op.kernels.iter().map(|(k, _)| k));
            for k in program.kernels.iter().chain(operator_kernels) {
                let path = dir.join(format!("{}-{}-{}.wgsl", graph.name, layout, k.name));
                std::fs::write(&path, k.source.text()).with_context(|| format!("writing {}", path.display()))?;
            }
        }
    }
    if let Some(dot) = &args.dot {
        std::fs::write(dot, graph.to_dot()).with_context(|| format!("writing {}", dot.display()))?;
        writeln!(out, "wrote {}", dot.display())?;
    }
    Ok(out)
}

/// Lists the scene features compiled into the kernels and those left out.
fn features(out: &mut String, flags: &std::collections::BTreeSet<String>) -> std::fmt::Result {
    let (used, unused): (Vec<_>, Vec<_>) = lightgraph_scenes::features::ALL
        .iter()
        .partition(|(f, _)| flags.contains(*f));
    writeln!(out, "scene features compiled in:")?;
    for (f, what) in used {
        writeln!(out, "  {f:<18} {what}")?;
    }
    let names: Vec<&str> = unused.iter().map(|(f, _)| *f).collect();
    writeln!(
        out,
        "left out: {}\n",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    )
}
