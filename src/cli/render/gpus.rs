//! `render --gpus`: one run on several GPUs of the machine (lightgraph::multi), with a
//! progress line of each GPU's rate and one film at the end.

use super::{RENDER, RenderArgs, progress_bar, write_film};
use crate::cli::args::{reference_mean, si};
use anyhow::Result;
use lightgraph::checkpoint::Checkpoint;
use lightgraph::compare::ErrorSample;
use lightgraph::film::Film;
use lightgraph::interrupt::stopped_by_signal;
use lightgraph::metrics::{ImageError, image_error};
use lightgraph::multi::{Merging, Share, gpu_selectors, render_on_gpus};
use lightgraph::output::shell_word;
use lightgraph::run::Run;
use std::path::Path;
use std::time::{Duration, Instant};

/// The progress line: frames, samples/s and each GPU's rate.
fn progress_line(shares: &[Share], film: &Film, pixels: f64, secs: f64, error: &str) -> String {
    let spf = film.samples_per_pixel() as f64 / film.frames.max(1) as f64;
    let per_gpu: Vec<String> = shares
        .iter()
        .enumerate()
        .map(|(i, s)| format!("GPU {i} {}samples/s", si(s.frames_per_second() * spf * pixels)))
        .collect();
    format!(
        "frame {} | {} samples/s | {}{error}",
        film.frames,
        si(film.samples_per_pixel() as f64 * pixels / secs),
        per_gpu.join(", ")
    )
}

/// `lightgraph render --gpus`: the frames of one render shared by several GPUs, each claiming
/// batches sized to its speed, added into one film.
pub fn render_on_several_gpus(args: &RenderArgs, spec: &str, resumed: Option<Film>) -> Result<()> {
    let selectors = gpu_selectors(spec)?;
    let mut run = Run::load_named(&args.spec(), "--gpus")?;
    args.check_out()?;
    // One measurement shared by every GPU (each measuring its own could differ).
    run.measure_on(selectors.first().map(String::as_str))?;
    let (graph, layout) = (&run.graph, &run.layout);
    let (w, h) = (run.options.width, run.options.height);
    let reference = reference_mean(args.reference.as_ref(), (w, h))?;
    eprintln!(
        "{} GPUs ({}) | scene {} | graph {} layout {layout} | {w}x{h}",
        selectors.len(),
        selectors.join(", "),
        run.spec.scene,
        graph.name
    );
    let mut film = args.start_film(&run, resumed)?;
    let out = args.out();
    let bar = progress_bar(args);
    let start = Instant::now();
    let pixels = (w as f64) * (h as f64);
    let (mut error, mut error_at) = (String::new(), None::<Instant>);
    let mut errors = Vec::new();
    let mut view = args.live(&out, (w, h), reference.as_deref())?;
    let frames_before = film.frames;
    let every = args.film.checkpoint(&RENDER);
    let mut checkpoint = Checkpoint::new(every, &out, "render", args.film.exposure).at_first();
    let mut checkpoint_error = None;
    let (shares, merging) = render_on_gpus(&run, &selectors, args.film.budget(), &mut film, |shares, film| {
        if let Err(e) = checkpoint.write_if_due(film) {
            checkpoint_error.get_or_insert(e);
        }
        if let Some(r) = &reference
            && error_at.is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            let e = image_error(&film.mean(), r);
            error = format!(" | RMSE {:.4e}", e.rmse);
            error_at = Some(Instant::now());
            errors.push(error_sample(film, frames_before, start.elapsed().as_secs_f64(), e));
        }
        let secs = start.elapsed().as_secs_f64();
        bar.set_message(progress_line(shares, film, pixels, secs, &error));
        if view.due() {
            view.show(&film.mean(), film.frames, &bar.message(), false);
        }
        bar.set_position(match args.film.time {
            Some(_) => start.elapsed().as_millis() as u64,
            None => film.frames - frames_before,
        });
    })?;
    bar.finish();
    if let Some(e) = checkpoint_error {
        return Err(e);
    }
    view.show(
        &film.mean(),
        film.frames,
        &format!("{} | finished", bar.message()),
        true,
    );
    // The run's time once every GPU was ready (each GPU's set-up is not on the clock, as a
    // one-GPU render's is not).
    let seconds = merging.run_seconds;
    let mut adapters: Vec<String> = shares.iter().map(|s| s.adapter.clone()).collect();
    adapters.dedup();
    film.info.insert("layout".into(), layout.clone());
    film.info.insert("adapter".into(), adapters.join(", "));
    let rays_before = film.info.get("rays").and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    let rays = rays_before + shares.iter().map(|s| s.rays).sum::<u64>();
    film.info.insert("rays".into(), rays.to_string());
    film.seconds += seconds;
    let png = write_film(&film, &out, args.film.exposure)?;
    if let Some(r) = &reference {
        let e = image_error(&film.mean(), r);
        eprintln!(
            "error against the reference: RMSE {:.4e}, relMSE {:.4e}",
            e.rmse, e.rel_mse
        );
        errors.push(error_sample(&film, frames_before, start.elapsed().as_secs_f64(), e));
    }
    report_shares(&film, &shares, &merging, pixels);
    println!("wrote {} and {}", out.display(), png.display());
    if let Some(path) = &args.reference {
        super::html::write_html(&out, &film, (path, layout), &errors)?;
        println!(
            "wrote {} (opens offline in a browser)",
            super::html::html_path(&out).display()
        );
    }
    stopped_by_signal(format!(
        "{} and {} hold {} frames; `{}` goes on",
        out.display(),
        png.display(),
        film.frames,
        args.resume_command(&out, seconds, &format!(" --gpus {}", shell_word(Path::new(spec))))
    ))
}

/// The error `e` of `film` after `seconds` of this run, which began at frame `frames_before`.
fn error_sample(film: &Film, frames_before: u64, seconds: f64, e: ImageError) -> ErrorSample {
    let frames = film.frames - frames_before;
    ErrorSample {
        seconds,
        frames: u32::try_from(frames).unwrap_or(u32::MAX),
        samples_per_pixel: film.samples_per_pixel() / film.frames.max(1) * frames,
        error: e,
    }
}

/// The rates of a render on several GPUs on stderr: samples/s wall-clock over `film`, each
/// GPU's share, and the host's merging.
fn report_shares(film: &Film, shares: &[Share], merging: &Merging, pixels: f64) {
    let seconds = merging.run_seconds;
    let spf = film.samples_per_pixel() as f64 / film.frames.max(1) as f64;
    eprintln!(
        "{} frames, {} spp in {seconds:.2} s on {} GPUs: {}samples/s wall-clock",
        film.frames,
        film.samples_per_pixel(),
        shares.len(),
        si(film.samples_per_pixel() as f64 * pixels / seconds)
    );
    for (i, s) in shares.iter().enumerate() {
        eprintln!(
            "GPU {i} ({}): {} frames, {}samples/s while rendering, {}rays/s",
            s.adapter,
            s.frames,
            si(s.frames_per_second() * spf * pixels),
            si(s.rays as f64 / s.busy_seconds.max(1e-9))
        );
    }
    eprintln!(
        "host merging: {} batches, {:.2} ms each",
        merging.batches,
        1e3 * merging.seconds / merging.batches.max(1) as f64
    );
}
