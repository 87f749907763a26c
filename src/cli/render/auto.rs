//! `render --layout auto` and the layout cache: the layout of a one-GPU render, cached,
//! measured now, or the one named.

use super::RenderArgs;
use anyhow::Result;
use lightgraph::layout_cache;
use lightgraph::run::{Run, parse_bvh};
use lightgraph_engine::Gpu;
use lightgraph_scenes::bvh::BvhKind;

/// Puts into `run` the layout of a render where it is not the run's own, and says whether it
/// did: not for a layout named with `--layout`; else the one `--layout auto` measured fastest
/// for this render's key (`lightgraph::layout_cache`) unless `--retune`, with the scene loaded
/// again for the BVH it was measured with; else, without `--layout`, none (the graph's
/// default), and with `--layout auto`, the fastest measured now (and stored).
pub fn choose_layout(gpu: &Gpu, run: &mut Run, args: &RenderArgs) -> Result<bool> {
    if args.film.layout.is_some() && !run.spec.auto_layout() {
        return Ok(false);
    }
    let key = cache_key(gpu, run);
    if let Some(cached) = layout_cache::find(&key).filter(|_| !args.retune) {
        match lightgraph_engine::auto::check(&run.graph, &cached.name, &cached.layout) {
            Ok(()) => {
                if let Some(bvh) = cached
                    .bvh
                    .as_deref()
                    .map(parse_bvh)
                    .transpose()
                    .map_err(anyhow::Error::msg)?
                {
                    run.load_bvh(bvh)?;
                }
                eprintln!(
                    "layout {} from the layout cache ({:.1} Msamples/s when --layout auto measured it, {}; \
                     --layout NAME or --layout auto --retune to choose)",
                    cached.name,
                    cached.samples_per_second / 1e6,
                    cached.measured
                );
                (run.layout, run.decl) = (cached.name, cached.layout);
                return Ok(true);
            }
            Err(e) => eprintln!(
                "warning: the cached layout {} no longer plans ({e}); not used",
                cached.name
            ),
        }
    }
    if !run.spec.auto_layout() {
        return Ok(false);
    }
    tune_layout(gpu, run, args, key)?;
    Ok(true)
}

/// Without `--layout` and with nothing cached: the layout measured fastest for this built-in
/// scene on this adapter, where the run's tuning profile has one (`lightgraph::tuning`).
pub fn take_measured_default(gpu: &Gpu, run: &mut Run) -> Result<()> {
    let tuning = run.options.layout.tuning.clone();
    let Some(profile) = tuning.profile(Some(&gpu.info.name)) else {
        return Ok(());
    };
    let Some(m) = profile.scene_layout(&run.spec.graph, &run.spec.scene) else {
        return Ok(());
    };
    run.relayout(&m.layout)?;
    eprintln!(
        "layout {}: measured fastest for this scene by the tuning profile {} ({:.1} against {:.1} Msamples/s for {}, {}; --layout NAME to choose)",
        m.layout,
        profile.name,
        m.rate / 1e6,
        m.default_rate / 1e6,
        run.graph.default_layout,
        m.measured
    );
    Ok(())
}

/// A BVH as the layout cache writes it (`cwbvh`, `bvh2`: what `--bvh` takes).
fn bvh_name(kind: BvhKind) -> String {
    format!("{kind:?}").to_lowercase()
}

/// What the layout cache keys a render's measurement by.
fn cache_key(gpu: &Gpu, run: &Run) -> layout_cache::Key {
    let opts = &run.options;
    layout_cache::Key {
        graph: run.spec.graph.clone(),
        scene: run.spec.scene.clone(),
        size: (opts.width, opts.height),
        spp: opts.samples_per_frame,
        bvh: run.spec.bvh.0.map_or("auto".to_string(), bvh_name),
        constants: opts
            .constants
            .iter()
            .map(|(k, v)| (k.clone(), format!("{v:?}")))
            .collect(),
        adapter: gpu.describe(),
        version: env!("CARGO_PKG_VERSION").to_string(),
    }
}

/// `--layout auto`: measures every legal layout of `graph` and makes the fastest the run's
/// (with the program its trial compiled: `lightgraph::tune::tune`), writes the table beside
/// the output and stores the winner in the layout cache under `key`.
fn tune_layout(gpu: &Gpu, run: &mut Run, args: &RenderArgs, key: layout_cache::Key) -> Result<()> {
    eprintln!(
        "--layout auto: measuring every legal layout of '{}' for {:?} each",
        run.graph.name, args.tune_time
    );
    let trials = lightgraph::tune::tune(gpu, run, args.tune_time, |t| {
        eprintln!("  {:>9.1} Msamples/s  {}", t.score() / 1e6, t.name);
    })?;
    let table = lightgraph::tune::table(&trials);
    println!("{table}");
    let report = args.out().with_extension("auto.md");
    if let Some(dir) = report.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&report, &table)?;
    let best = &trials[0];
    eprintln!(
        "winner: {} ({:.1} Msamples/s); table in {}",
        best.name,
        best.score() / 1e6,
        report.display()
    );
    let entry = layout_cache::Entry {
        key,
        name: best.name.clone(),
        layout: best.decl.clone(),
        samples_per_second: best.score(),
        measured: layout_cache::now(),
        bvh: Some(bvh_name(run.bvh())),
    };
    match layout_cache::store(entry) {
        Ok(path) => eprintln!("stored in the layout cache {}", path.display()),
        Err(e) => eprintln!("warning: the winner is not stored: {e:#}"),
    }
    Ok(())
}
