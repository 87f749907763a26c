//! `lightgraph merge`: adds films (from `render`, `reference` or `merge`) of the same settings
//! over disjoint frame ranges, the shards of one run, into one film.

use anyhow::Result;
use clap::Args;
use lightgraph::film::Film;
use std::path::PathBuf;

#[derive(Args)]
pub struct MergeArgs {
    /// The films to add up: same scene, graph, samples per frame, seed, constants, measured
    /// constants and resolution, disjoint frame ranges.
    #[arg(required = true, num_args = 1..)]
    pub films: Vec<PathBuf>,
    /// Output EXR (it must end in .exr); a PNG preview is written beside it. An existing EXR
    /// or PNG is refused unless --force.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace an existing --out.
    #[arg(long)]
    pub force: bool,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

pub fn merge(args: MergeArgs) -> Result<()> {
    lightgraph::output::check_out(&args.out, args.force, None)?;
    let mut merged = Film::read(&args.films[0])?;
    for path in &args.films[1..] {
        merged.merge(&Film::read(path)?, path)?;
    }
    merged.write(&args.out, "merge")?;
    let png = args.out.with_extension("png");
    lightgraph::output::write_png(&png, &merged.image(), args.exposure)?;
    let ranges: Vec<String> = merged.ranges.iter().map(|r| format!("{}..{}", r.0, r.1)).collect();
    println!(
        "wrote {} and {}: {} films, {} frames ({}), {} spp, {:.1} s of rendering",
        args.out.display(),
        png.display(),
        args.films.len(),
        merged.frames,
        ranges.join(", "),
        merged.samples_per_pixel(),
        merged.seconds
    );
    Ok(())
}
