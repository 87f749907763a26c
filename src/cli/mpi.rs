//! `render --mpi` (cargo feature `mpi`): one run across the ranks of an MPI job, one GPU each
//! (lightgraph::cluster); rank 0 shows the progress and writes the film.

use super::args::si;
use super::gpus::{Setup, budget};
use super::render::RenderArgs;
use anyhow::{Result, anyhow};
use indicatif::{ProgressBar, ProgressStyle};
use lightgraph::cluster::render_across;
use std::time::Instant;

pub fn render_with_mpi(args: &RenderArgs) -> Result<()> {
    let universe = mpi::initialize().ok_or_else(|| anyhow!("MPI is initialised already"))?;
    let world = universe.world();
    let root = lightgraph::cluster::place(&world).rank == 0;
    let setup = Setup::load(args, "--mpi")?;
    let (w, h) = (setup.opts.width, setup.opts.height);
    let mut film = setup.film(args);
    let run = setup.run(args);
    let bar = if root {
        ProgressBar::new(args.time.map_or(args.frames as u64, |t| t.as_millis() as u64))
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(ProgressStyle::with_template("{bar:30} {msg} ETA {eta}").expect("valid template"));
    let pixels = w as f64 * h as f64;
    let start = Instant::now();
    let outcome = render_across(
        &world,
        &run,
        args.common.adapter.as_deref(),
        budget(args),
        &mut film,
        |p| {
            let secs = start.elapsed().as_secs_f64();
            let per_rank: Vec<String> = p
                .frames_by_rank
                .iter()
                .enumerate()
                .map(|(r, f)| format!("rank {r} {f}"))
                .collect();
            bar.set_message(format!(
                "frame {} | {} samples/s | frames by rank: {}",
                p.film.frames,
                si(p.film.samples_per_pixel() as f64 * pixels / secs),
                per_rank.join(", ")
            ));
            bar.set_position(match args.time {
                Some(_) => start.elapsed().as_millis() as u64,
                None => p.film.frames,
            });
        },
    )?;
    bar.finish();
    if !root {
        return Ok(());
    }
    let seconds = start.elapsed().as_secs_f64();
    film.info.insert("layout".into(), setup.layout.clone());
    let frames_by_rank = &outcome.frames_by_rank;
    film.info.insert("ranks".into(), frames_by_rank.len().to_string());
    film.info
        .insert("rays".into(), outcome.rays_by_rank.iter().sum::<u64>().to_string());
    film.seconds = seconds;
    film.write(&args.out, "render")?;
    let png = args.out.with_extension("png");
    lightgraph::output::write_png(&png, &film.image(), args.exposure)?;
    eprintln!(
        "{} frames, {} spp in {seconds:.2} s on {} ranks: {}samples/s wall-clock; frames by rank: {:?}",
        film.frames,
        film.samples_per_pixel(),
        frames_by_rank.len(),
        si(film.samples_per_pixel() as f64 * pixels / seconds),
        frames_by_rank
    );
    eprintln!(
        "last film reduction: {:.1} MB a rank in {:.1} ms",
        outcome.reduction_bytes as f64 / 1e6,
        1e3 * outcome.last_reduction_seconds
    );
    println!("wrote {} and {}", args.out.display(), png.display());
    Ok(())
}
