//! `lightgraph bench`: layouts over a sweep of frame sizes.

use super::args::*;
use super::checks::count;
use anyhow::Result;
use clap::Args;
use lightgraph::output::{Output, check_outputs};
use lightgraph::run::{Run, Scenes, load_graph};
use lightgraph_engine::{Gpu, Plan};
use lightgraph_scenes::bvh::BvhKind;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub graph: GraphArg,
    /// Layouts to measure, comma-separated; `all` for the graph's named layouts, `auto` for
    /// every legal layout the engine finds.
    #[arg(long, default_value = "all")]
    pub layouts: String,
    /// Frame sizes as WxHxSPP, comma-separated (default: 3.3e5 to 1e8 paths per frame).
    #[arg(long, value_parser = parse_point, value_delimiter = ',', allow_hyphen_values = true)]
    pub points: Vec<(u32, u32, u32)>,
    /// Time each layout renders at each frame size (after a warm-up frame).
    #[arg(long, value_parser = super::checks::duration, allow_hyphen_values = true, default_value = "2s")]
    pub time: Duration,
    /// Output folder for bench.md, bench.csv, rays_per_second.png and report.html.
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
    /// Write into a --out that holds an earlier run's bench.md, bench.csv and plot, replacing them.
    #[arg(long)]
    pub force: bool,
}

/// What `bench` writes into its folder.
const BENCH_FILES: [&str; 4] = ["bench.md", "bench.csv", "rays_per_second.png", "report.html"];

/// Parses a `--points` entry `WxHxSPP`: each at least 1, the frame within the engine's
/// counts and the host's memory.
fn parse_point(s: &str) -> Result<(u32, u32, u32), String> {
    let parts: Vec<&str> = s.split(['x', 'X']).collect();
    let [w, h, spp] = parts[..] else {
        return Err("it is not WxHxSPP, e.g. 1280x720x4".into());
    };
    let (w, h, spp) = (count(w)?, count(h)?, count(spp)?);
    super::checks::image_fits(w, h, spp)?;
    Ok((w, h, spp))
}

/// `lightgraph bench`: every layout at every frame size, reported as tables and a plot.
pub fn bench(args: BenchArgs) -> Result<()> {
    let c = &args.common;
    check_outputs(&[Output::Folder(&args.out, &BENCH_FILES)], args.force, None)?;
    let graph = load_graph(args.graph.name())?;
    let gpu = Gpu::new(c.adapter.as_deref())?;
    let points = match args.points.is_empty() {
        true => lightgraph::bench::DEFAULT_POINTS.to_vec(),
        false => args.points.clone(),
    };
    let layouts: Vec<(String, lightgraph_engine::ir::LayoutDecl)> = match args.layouts.as_str() {
        "all" => graph.layouts.iter().map(|(n, d)| (n.clone(), d.clone())).collect(),
        "auto" => {
            let default = graph.layouts[&graph.default_layout].clone();
            let base = c.tuning.apply(Some(&gpu), &graph, &graph.default_layout, default);
            lightgraph_engine::auto::legal_layouts(&graph, &base)
        }
        list => list
            .split(',')
            .map(|n| Ok((n.to_string(), Plan::new(&graph, n)?.layout)))
            .collect::<Result<_>>()?,
    };
    eprintln!(
        "{} | scene {} | graph {} | {} layouts x {} frame sizes, {:?} each",
        gpu.describe(),
        c.scene(),
        graph.name,
        layouts.len(),
        points.len(),
        args.time
    );
    let mut scenes = Scenes::new(c.scene());
    let kinds: Vec<BvhKind> = layouts
        .iter()
        .map(|(name, decl)| scenes.load_for(c.bvh, name, decl))
        .collect::<Result<_>>()?;
    let mut results = Vec::new();
    for (w, h, spp) in points {
        for ((name, decl), &kind) in layouts.iter().zip(&kinds) {
            let spec = c.spec(&graph.name, Some(name), 1);
            let mut run = Run::with_scene(&spec, graph.clone(), (name.clone(), decl.clone()), scenes.shared(kind))?;
            (run.options.width, run.options.height, run.options.samples_per_frame) = (w, h, spp);
            match lightgraph::bench::measure(&gpu, &run, args.time) {
                Ok(m) => {
                    eprintln!(
                        "  {:>8.2} M paths  {:<20} {:>8.1} Mrays/s ({:>8.1} GPU) {:>8.1} Msamples/s {:>7.1} fps {:>8.1} MiB",
                        m.paths_per_frame() as f64 / 1e6,
                        name,
                        m.rays_per_second() / 1e6,
                        m.gpu_rays_per_second() / 1e6,
                        m.samples_per_second() / 1e6,
                        m.frames_per_second(),
                        m.memory_bytes as f64 / 1048576.0
                    );
                    results.push(m);
                }
                Err(e) => eprintln!(
                    "  {:>8.2} M paths  {name}: failed: {e:#}",
                    (w * h) as f64 * spp as f64 / 1e6
                ),
            }
        }
    }
    let title = format!(
        "{} on {}, {} ({}{})",
        graph.name,
        c.scene(),
        gpu.info.name,
        if args.layouts == "auto" {
            "every legal layout"
        } else {
            "named layouts"
        },
        if c.no_subgroups { ", no subgroups" } else { "" }
    );
    let md = lightgraph::bench::write_reports(&args.out, &title, &results)?;
    println!(
        "{md}\nwrote {}/bench.md, bench.csv, rays_per_second.png and {} (opens offline in a browser)",
        args.out.display(),
        lightgraph::bench::html_path(&args.out).display()
    );
    Ok(())
}
