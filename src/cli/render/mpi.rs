//! `render --mpi` (cargo feature `mpi`): one run across the ranks of an MPI job, one GPU each
//! (lightgraph::cluster); rank 0 shows the progress and writes the film.

use super::{RenderArgs, progress_bar, write_film};
use crate::cli::args::si;
use anyhow::{Result, anyhow};
use indicatif::ProgressBar;
use lightgraph::cluster::{Outcome, place, rank_adapter, render_across};
use lightgraph::film::Film;
use lightgraph::interrupt::stopped_by_signal;
use lightgraph::live::Live;
use lightgraph::run::Run;
use lightgraph_engine::ConstValue;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::time::Instant;

/// `lightgraph render --mpi`: the frames of one render shared by the ranks of an MPI job, one
/// GPU each; rank 0 shows the progress, takes a resumed film in and writes the film.
pub fn render_with_mpi(args: &RenderArgs, resumed: Option<Film>) -> Result<()> {
    let universe = mpi::initialize().ok_or_else(|| anyhow!("MPI is initialised already"))?;
    let world = universe.world();
    let root = place(&world).rank == 0;
    let mut run = Run::load_named(&args.spec(), "--mpi")?;
    args.check_out()?;
    share_measured(&world, &mut run, args.common.adapter.as_deref());
    let (w, h) = (run.options.width, run.options.height);
    // The ranks render into an empty film; a resumed one takes it in at the end.
    let mut film = args.start_film(&run, None)?;
    if let Some(r) = &resumed {
        args.start_film(&run, Some(r.clone()))?;
    }
    let out = args.out();
    let bar = if root {
        progress_bar(args)
    } else {
        ProgressBar::hidden()
    };
    let pixels = w as f64 * h as f64;
    let mut view = match root {
        true => args.live(&out, (w, h), None)?,
        false => Live::default(),
    };
    let start = Instant::now();
    let outcome = render_across(
        &world,
        &run,
        args.common.adapter.as_deref(),
        args.film.budget(),
        args.tev.tev.is_some() || args.serve.is_some(),
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
            bar.set_position(match args.film.time {
                Some(_) => start.elapsed().as_millis() as u64,
                None => p.film.frames,
            });
            if view.due() {
                view.show(&p.film.mean(), p.film.frames, &bar.message(), false);
            }
        },
    )?;
    bar.finish();
    if !root {
        return match outcome.interrupted {
            true => stopped_by_signal("rank 0 writes the film".into()),
            false => Ok(()),
        };
    }
    view.show(
        &film.mean(),
        film.frames,
        &format!("{} | finished", bar.message()),
        true,
    );
    let seconds = outcome.render_seconds;
    let setup_seconds = start.elapsed().as_secs_f64() - seconds;
    film.info.insert("layout".into(), run.layout.clone());
    let frames_by_rank = &outcome.frames_by_rank;
    film.info.insert("ranks".into(), frames_by_rank.len().to_string());
    film.info
        .insert("rays".into(), outcome.rays_by_rank.iter().sum::<u64>().to_string());
    film.seconds = seconds;
    if let (Some(mut whole), Some(path)) = (resumed, &args.film.resume) {
        whole.merge(&film, path)?;
        film = whole;
    }
    let png = write_film(&film, &out, args.film.exposure)?;
    report(&film, &outcome, pixels, setup_seconds);
    println!("wrote {} and {}", out.display(), png.display());
    if outcome.interrupted {
        return stopped_by_signal(format!(
            "{} holds {} frames ({}); `mpirun ... {}` goes on after the last",
            out.display(),
            film.frames,
            film.ranges
                .iter()
                .map(|r| format!("{}..{}", r.0, r.1))
                .collect::<Vec<_>>()
                .join(", "),
            args.resume_command(&out, seconds, " --mpi")
        ));
    }
    Ok(())
}

/// The run's rates on stderr: samples/s over the time after every rank's set-up (as `--gpus`
/// counts it), the set-up, frames by rank, the ranks' waits and the film reduction.
fn report(film: &Film, outcome: &Outcome, pixels: f64, setup_seconds: f64) {
    let seconds = outcome.render_seconds;
    eprintln!(
        "{} frames, {} spp in {seconds:.2} s on {} ranks (set-up {setup_seconds:.2} s before): {}samples/s wall-clock, {}rays/s",
        film.frames,
        film.samples_per_pixel(),
        outcome.frames_by_rank.len(),
        si(film.samples_per_pixel() as f64 * pixels / seconds),
        si(outcome.rays_by_rank.iter().sum::<u64>() as f64 / seconds),
    );
    eprintln!(
        "frames by rank: {:?}; rank 0 waited {:.1} ms for the ranks at the round ends",
        outcome.frames_by_rank,
        1e3 * outcome.waiting_seconds
    );
    eprintln!(
        "film reduction: {:.1} MB a rank in {:.1} ms",
        outcome.reduction_bytes as f64 / 1e6,
        1e3 * outcome.last_reduction_seconds
    );
}

/// Rank 0 measures the graph's measured constants that the options do not give (on its GPU)
/// and sends them to every rank, so that all ranks render one estimator and the film records
/// the values. A failed measurement ends the job.
fn share_measured(world: &SimpleCommunicator, run: &mut Run, adapter: Option<&str>) {
    let opts = &run.options;
    let names: Vec<String> = run
        .graph
        .measured
        .keys()
        .filter(|name| !opts.constants.contains_key(*name))
        .cloned()
        .collect();
    if names.is_empty() {
        return;
    }
    let place = place(world);
    let mut values = vec![0f32; names.len()];
    if place.rank == 0 {
        let selector = rank_adapter(&place, adapter);
        if let Err(e) = run.measure_on(Some(&selector)) {
            eprintln!("error: rank 0: {e:#}");
            world.abort(1)
        }
        for (value, name) in values.iter_mut().zip(&names) {
            if let Some(ConstValue::F32(v)) = run.options.constants.get(name) {
                *value = *v;
            }
        }
    }
    world.process_at_rank(0).broadcast_into(&mut values[..]);
    for (name, value) in names.into_iter().zip(values) {
        run.options.constants.insert(name, ConstValue::F32(value));
    }
}
