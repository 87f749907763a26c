//! Preparing a run for compilation (the layout's overrides, the specialisation, the scene's
//! buffers checked to fit the GPU) and measuring the graph's measured constants, one frame
//! each with their measuring settings.

use crate::run::options::{SessionOptions, device_flags, kernel_flags, specialization};
use crate::run::scene::LoadedScene;
use anyhow::{Context, Result, anyhow, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Gpu, Graph, Instance, Specialization, compile};
use lightgraph_scenes::{CompiledScene, split};
use std::collections::BTreeMap;

/// What a session is compiled from: the layout (with the options' overrides), the
/// specialization and the scene's resources the graph declares.
pub(crate) struct Prepared {
    pub(crate) decl: LayoutDecl,
    pub(crate) spec: Specialization,
    pub(crate) externals: BTreeMap<String, Vec<u8>>,
}

/// Checks the options and specializes `graph` in the layout `decl` (called `layout`: a named
/// layout as the graph writes it takes the tuning profile's knobs) for `scene`.
pub(crate) fn prepare(
    gpu: &Gpu,
    graph: &Graph,
    (layout, decl): (&str, LayoutDecl),
    scene: &LoadedScene,
    options: &SessionOptions,
) -> Result<Prepared> {
    if options.width == 0 || options.height == 0 || options.samples_per_frame == 0 {
        bail!("resolution and samples per frame must be at least 1");
    }
    let paths = options.width as u64 * options.height as u64 * options.samples_per_frame as u64;
    if paths > u32::MAX as u64 {
        bail!("{paths} paths per frame is more than 2^32; use fewer samples per frame");
    }
    let decl = options.layout.resolve(Some(gpu), graph, layout, decl);
    let mut flags = kernel_flags(device_flags(gpu), scene, options.layout.all_features);
    let camera = CompiledScene::camera(&scene.scene, options.width, options.height);
    // The scene offers every scene resource; a graph takes those it declares, and the
    // candidates its passes may use (the engine leaves aside those they do not).
    let mut externals = scene.compiled.resources(&camera);
    let limit = adapter_binding_limit(gpu);
    let chunk_limit = options.layout.max_binding.map_or(limit, |m| m.min(limit));
    if split::split(&mut externals, chunk_limit).map_err(|e| too_large(gpu, scene, chunk_limit, e))? {
        flags.insert(split::FLAG.to_string());
    }
    externals.retain(|name, _| {
        graph
            .resource(name)
            .map(|r| &r.decl)
            .or_else(|| graph.declared.candidates.get(name))
            .is_some_and(|r| r.scope == lightgraph_engine::ir::Scope::External)
    });
    check_scene_fits(gpu, scene, limit, &externals)?;
    let spec = specialization(graph, &scene.scene, options, flags);
    Ok(Prepared { decl, spec, externals })
}

/// The most bytes of a buffer `gpu` binds at once: what it binds in one storage buffer and
/// holds in one buffer.
fn adapter_binding_limit(gpu: &Gpu) -> u64 {
    gpu.limits
        .max_storage_buffer_binding_size
        .min(gpu.limits.max_buffer_size)
}

/// An error naming the scene's size where one of its buffers is larger than `gpu` binds or
/// holds in one buffer (its BVH nodes, textures...; its geometry split beforehand), before
/// any is made.
fn check_scene_fits(gpu: &Gpu, scene: &LoadedScene, limit: u64, externals: &BTreeMap<String, Vec<u8>>) -> Result<()> {
    if let Some((name, size)) = largest_over(externals, limit) {
        let mib = |bytes: u64| bytes as f64 / 1048576.0;
        return Err(too_large(
            gpu,
            scene,
            limit,
            format!(
                "its '{name}' buffer takes {:.1} MiB, more than the {:.1} MiB bound at once",
                mib(size),
                mib(limit)
            ),
        ));
    }
    Ok(())
}

/// The error of a scene too large for `gpu`: `why`, the scene's size and the adapter's limits.
fn too_large(gpu: &Gpu, scene: &LoadedScene, limit: u64, why: impl std::fmt::Display) -> anyhow::Error {
    let mib = |bytes: u64| bytes as f64 / 1048576.0;
    anyhow!(
        "the scene is too large for this GPU: {why} ({} primitives, a BVH of {:.1} MiB; at most {:.1} MiB bound at once: max_storage_buffer_binding_size {}, max_buffer_size {})",
        scene.compiled.primitives.len(),
        mib(scene.compiled.bvh.len() as u64),
        mib(limit),
        gpu.limits.max_storage_buffer_binding_size,
        gpu.limits.max_buffer_size,
    )
}

/// The largest of `buffers` (name and bytes) over `limit` bytes, if any.
fn largest_over(buffers: &BTreeMap<String, Vec<u8>>, limit: u64) -> Option<(&str, u64)> {
    buffers
        .iter()
        .map(|(name, bytes)| (name.as_str(), bytes.len() as u64))
        .filter(|&(_, size)| size > limit)
        .max_by_key(|&(_, size)| size)
}

/// Measures the graph's measured constants that `options` does not give (LVC-BPT's average
/// light sub-path length): one frame each with its measuring constants set. Runs that are
/// merged (shards, GPUs, ranks, a resumed reference) must share one measurement, or they
/// render different estimators: measure once and put the values into every run's constants.
pub fn measure_constants(
    gpu: &Gpu,
    graph: &Graph,
    layout: &str,
    decl: LayoutDecl,
    scene: &LoadedScene,
    options: &SessionOptions,
) -> Result<BTreeMap<String, ConstValue>> {
    if graph.measured.keys().all(|name| options.constants.contains_key(name)) {
        return Ok(BTreeMap::new());
    }
    let Prepared { decl, spec, externals } = prepare(gpu, graph, (layout, decl), scene, options)?;
    measure_prepared(gpu, graph, layout, (&decl, &spec, &externals), options)
}

/// [`measure_constants`] on a prepared layout and specialization.
pub(crate) fn measure_prepared(
    gpu: &Gpu,
    graph: &Graph,
    layout: &str,
    (decl, spec, externals): (&LayoutDecl, &Specialization, &BTreeMap<String, Vec<u8>>),
    options: &SessionOptions,
) -> Result<BTreeMap<String, ConstValue>> {
    let mut measured = BTreeMap::new();
    for (name, m) in &graph.measured {
        if options.constants.contains_key(name) {
            continue;
        }
        let mut measuring = spec.clone();
        measuring.constants.extend(measured.clone());
        measuring.constants.extend(m.set.clone());
        let program = compile(graph, layout, decl, &measuring, &options.layout.target(gpu))?;
        let mut instance = Instance::new(gpu, program, externals)
            .with_context(|| format!("measuring '{name}' of graph '{}' in layout '{layout}'", graph.name))?;
        let stats = instance.run_frames(0, 1, options.seed)?;
        let (a, b) = (stats.counters[&m.ratio.0], stats.counters[&m.ratio.1]);
        let value = m.value_from(a, b, &measuring.constants).map_err(|why| {
            let hint = if m.value.is_none() {
                " (no light in the scene?)"
            } else {
                ""
            };
            anyhow!("measuring '{name}' of graph '{}': {why}{hint}", graph.name)
        })?;
        measured.insert(name.clone(), ConstValue::F32(value as f32));
    }
    Ok(measured)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_largest_buffer_over_the_limit_is_named() {
        let buffers: BTreeMap<String, Vec<u8>> = [("bvh", 300), ("primitives", 500), ("lights", 10)]
            .into_iter()
            .map(|(n, size)| (n.to_string(), vec![0u8; size]))
            .collect();
        assert_eq!(largest_over(&buffers, 200), Some(("primitives", 500)));
        assert_eq!(largest_over(&buffers, 500), None);
    }
}
