//! `lightgraph stress`: the numerical stress suite, every stress scene with every estimator.

use anyhow::{Result, bail};
use clap::Args;
use lightgraph::output::{Output, check_outputs};
use lightgraph::stress::{Runner, Settings, cases::cases, estimators, table};
use lightgraph_engine::Gpu;
use std::path::PathBuf;

#[derive(Args)]
pub struct StressArgs {
    /// Estimators (graphs), comma-separated [default: every built-in radiance estimator].
    #[arg(long)]
    pub graphs: Option<String>,
    /// Only the stress scenes whose name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Multiply each scene's resolution (8x8 to 32x32 at 1) by this.
    #[arg(long, default_value_t = 1, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub scale: u32,
    /// Samples per pixel per frame.
    #[arg(long, default_value_t = 1, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub spp: u32,
    /// Frames per render (at least 32, for the statistics).
    #[arg(long, default_value_t = 32, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub frames: u32,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Folder for stress.md and a PNG of each render.
    #[arg(long, default_value = "out/stress")]
    pub out: PathBuf,
    /// Write into a --out that holds an earlier run's stress.md and PNGs, replacing them.
    #[arg(long)]
    pub force: bool,
    /// Acceleration structure: bvh2 or cwbvh.
    #[arg(long, value_parser = lightgraph::run::parse_bvh, default_value = "cwbvh")]
    pub bvh: lightgraph_scenes::bvh::BvhKind,
    /// GPU adapter whose name contains this text (also LIGHTGRAPH_ADAPTER).
    #[arg(long, env = "LIGHTGRAPH_ADAPTER")]
    pub adapter: Option<String>,
}

pub fn stress(args: StressArgs) -> Result<()> {
    check_outputs(&[Output::Folder(&args.out, &["stress.md"])], args.force, None)?;
    let graphs: Vec<String> = match &args.graphs {
        Some(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        None => estimators(),
    };
    let gpu = Gpu::new(args.adapter.as_deref())?;
    let settings = Settings {
        scale: args.scale.max(1),
        spp: args.spp.max(1),
        frames: args.frames,
        seed: args.seed,
        bvh: args.bvh,
    };
    let mut runner = Runner::new(&gpu, settings)?;
    let selected: Vec<_> = cases()
        .into_iter()
        .filter(|c| args.only.as_ref().is_none_or(|o| c.scene.contains(o.as_str())))
        .collect();
    eprintln!(
        "{} | {} stress scenes x {} estimators, scale {}, {} spp x {} frames",
        gpu.describe(),
        selected.len(),
        graphs.len(),
        settings.scale,
        settings.spp,
        settings.frames
    );
    std::fs::create_dir_all(&args.out)?;
    let mut outcomes = Vec::new();
    for case in &selected {
        for graph in &graphs {
            let o = runner.run(case, graph);
            let mark = match (&o.left_out, o.passed) {
                (Some(_), _) => "left out",
                (None, true) => "ok",
                (None, false) => "FAILED",
            };
            eprintln!(
                "  {:<34} {:<6} {:<7} {} ({:.1} s)",
                o.scene, o.graph, mark, o.statistic, o.seconds
            );
            for f in o.failures.iter().chain(&o.left_out) {
                eprintln!("      {f}");
            }
            if let Some(image) = &o.image {
                let png = args.out.join(format!("{}-{}.png", o.scene, o.graph));
                lightgraph::output::write_png(&png, image, 0.0)?;
            }
            outcomes.push(o);
        }
    }
    let md = table(&outcomes);
    std::fs::write(args.out.join("stress.md"), &md)?;
    println!("{md}\nwrote {}/stress.md and a PNG per render", args.out.display());
    let failed = outcomes.iter().filter(|o| !o.passed).count();
    if failed > 0 {
        bail!("{failed} of {} stress renders failed their invariant", outcomes.len());
    }
    Ok(())
}
