//! `lightgraph compare`: estimators and layouts against a reference, error against time.

use super::args::*;
use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::compare::{ReportContext, RunSpec, run, write_report};
use lightgraph::reference::Reference;
use lightgraph::render::{load_graph, load_scene_with};
use lightgraph_engine::Gpu;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    /// Runs to compare, comma-separated `graph:layout` (or `graph` for its default layout),
    /// e.g. pt:NaivePTsk,pt:RegenerationPTsk.
    #[arg(long)]
    pub runs: String,
    /// The reference EXR (from `lightgraph reference`); the scene, resolution and constants
    /// default to its own.
    #[arg(long)]
    pub reference: PathBuf,
    /// Wall-clock budget of each run.
    #[arg(long, value_parser = humantime::parse_duration, default_value = "10s")]
    pub time: Duration,
    /// The run the others are measured against [default: the first].
    #[arg(long)]
    pub baseline: Option<String>,
    /// Error samples per decade of time (log-spaced from the first frame to the end, at
    /// least 12).
    #[arg(long, default_value_t = 6)]
    pub per_decade: u32,
    /// Seed of the runs' random streams (must differ from the reference's).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Output folder: curves.csv, rmse_vs_time.png, summary.md and each run's EXR and PNG.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Exposure of the PNG previews in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

pub fn compare(mut args: CompareArgs) -> Result<()> {
    let reference = Reference::read(&args.reference)?;
    let info = |k: &str| reference.info.get(k).cloned().unwrap_or_default();
    let c = &mut args.common;
    c.scene.get_or_insert_with(|| info("scene"));
    c.res.get_or_insert(reference.size);
    if c.set.is_empty() && c.max_path_length.is_none() {
        c.set = info("constants").split_whitespace().map(String::from).collect();
    }
    let c = &args.common;
    if c.scene() != info("scene") {
        bail!(
            "{}: the reference shows scene '{}', not '{}'",
            args.reference.display(),
            info("scene"),
            c.scene()
        );
    }
    if info("seed") == args.seed.to_string() {
        bail!(
            "{}: the reference was rendered with seed {}, the seed of the runs: they would repeat its \
             random numbers and their error would look too small; pass another --seed",
            args.reference.display(),
            args.seed
        );
    }
    if args.per_decade == 0 {
        bail!("--per-decade must be at least 1");
    }
    let specs = RunSpec::parse_list(&args.runs)?;
    let scene = load_scene_with(c.scene(), c.bvh)?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    // Every run is checked before any renders: a typo should not cost the others' time.
    let mut runs = Vec::new();
    for spec in &specs {
        let graph = load_graph(&spec.graph)?;
        let (layout, _) = named_layout(&graph, spec.layout.as_deref())?;
        let opts = options(c, &scene, &graph.constants, args.seed)?;
        if constants_text(&opts.constants) != info("constants") {
            bail!(
                "{}: the reference was made with constants '{}', run {} would use '{}'",
                args.reference.display(),
                info("constants"),
                spec.graph,
                constants_text(&opts.constants)
            );
        }
        check_size(&reference, &args.reference, (opts.width, opts.height))?;
        // The run's own settings come after the check: they choose the estimator, not the image.
        let mut opts = opts;
        opts.constants.extend(parse_sets(&spec.sets, &graph.constants)?);
        let label = std::iter::once(format!("{}:{layout}", graph.name))
            .chain(spec.sets.iter().cloned())
            .collect::<Vec<_>>()
            .join("@");
        runs.push((label, graph, layout, opts));
    }
    let labels: Vec<&str> = runs.iter().map(|r| r.0.as_str()).collect();
    let baseline = match &args.baseline {
        None => 0,
        Some(b) => match labels.iter().position(|l| l == b || l.ends_with(&format!(":{b}"))) {
            Some(i) => i,
            None => bail!("--baseline {b} is none of the runs ({})", labels.join(", ")),
        },
    };
    eprintln!(
        "{} | scene {} (loaded in {:.2} s) | {} runs of {:?} | reference {} spp",
        gpu.describe(),
        c.scene(),
        scene.load_seconds,
        specs.len(),
        args.time,
        reference.samples_per_pixel()
    );
    let ref_mean = reference.mean();
    let mut results = Vec::new();
    for (label, graph, layout, opts) in runs {
        let bar = ProgressBar::new(args.time.as_millis() as u64);
        bar.set_style(ProgressStyle::with_template("{prefix:>24} {bar:30} {msg}").expect("valid template"));
        bar.set_prefix(label.clone());
        let result = run(
            &gpu,
            &scene,
            &graph,
            (&layout, label),
            opts,
            args.time,
            &ref_mean,
            args.per_decade,
            |t, e| {
                bar.set_position((t * 1e3) as u64);
                if let Some(e) = e {
                    bar.set_message(format!("{} spp | RMSE {:.4e}", e.samples_per_pixel, e.error.rmse));
                }
            },
        )?;
        bar.finish();
        results.push(result);
    }
    let ctx = ReportContext {
        scene: c.scene(),
        device: &gpu.info.name,
        load_seconds: scene.load_seconds,
        budget: args.time,
        reference_path: &args.reference,
        reference: &reference,
        baseline,
    };
    let summary = write_report(&args.out, &ctx, &results, args.exposure)?;
    println!(
        "{summary}\nwrote {}/curves.csv, rmse_vs_time.png, summary.md and each run's EXR and PNG",
        args.out.display()
    );
    Ok(())
}
