//! `lightgraph operators`: the engine's collective operators (exclusive scans of `u32`s and
//! `f32`s, counting sort, radix sort) checked against the CPU and timed on a GPU.

use anyhow::{Result, bail};
use clap::Args;
use lightgraph_engine::scratch::SortShape;
use lightgraph_engine::selfcheck::sort::{self, Keys, SortCheck};
use lightgraph_engine::selfcheck::{Pattern, check};
use lightgraph_engine::{Gpu, Target};

#[derive(Args)]
pub struct OperatorsArgs {
    /// Element counts, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,1,2,31,32,33,255,256,257,1048583,10000000"
    )]
    pub sizes: Vec<u64>,
    /// Buckets of the counting sort: a number, or `n` for as many as elements.
    #[arg(long, default_value = "n")]
    pub buckets: String,
    /// Inputs: random, equal, concentrated (comma-separated) [default: all].
    #[arg(long, value_delimiter = ',')]
    pub patterns: Vec<String>,
    /// Keys of the radix sort: random, equal, descending, high (comma-separated) [default: all].
    #[arg(long, value_delimiter = ',')]
    pub keys: Vec<String>,
    /// Low bits of the keys the radix sort sorts by (1 to 32).
    #[arg(long, default_value_t = 32)]
    pub bits: u32,
    /// What the radix sort moves: keys (keys alone), pairs (keys and values), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "pairs,keys")]
    pub moves: Vec<String>,
    /// Runs per size; the times are the median.
    #[arg(long, default_value_t = 5, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub runs: u32,
    /// Instances per size and input: each compiles the operators anew, allocates its own
    /// buffers and runs `--runs` times (a row each: later instances against the first).
    #[arg(long, default_value_t = 1, value_parser = super::checks::count::<u32>, allow_negative_numbers = true)]
    pub instances: u32,
    /// Untimed runs before each instance's timed ones, for this long: a GPU that idled
    /// (drawing inputs, checking on the CPU) starts at a fraction of its clock.
    #[arg(long, value_parser = super::checks::duration, default_value = "500ms")]
    pub warm_up: std::time::Duration,
    /// Most elements a thread of the radix sort ranks by subgroup ballots (4 to 16; fewer
    /// where the workgroup memory is short, the per-thread-count ranking below 4).
    #[arg(long, default_value_t = 8)]
    pub sort_items: u32,
    /// Use no subgroup operations even where the adapter has them.
    #[arg(long)]
    pub no_subgroups: bool,
    /// Also print each kernel's time.
    #[arg(long)]
    pub kernels: bool,
    /// GPU adapter whose name contains this text (also LIGHTGRAPH_ADAPTER).
    #[arg(long, env = "LIGHTGRAPH_ADAPTER")]
    pub adapter: Option<String>,
}

fn parse_pattern(name: &str) -> Result<Pattern> {
    Ok(match name {
        "random" => Pattern::Random,
        "equal" => Pattern::Equal,
        "concentrated" => Pattern::Concentrated,
        other => bail!("unknown pattern '{other}' (random, equal, concentrated)"),
    })
}

fn parse_keys(name: &str) -> Result<Keys> {
    Ok(match name {
        "random" => Keys::Random,
        "equal" => Keys::Equal,
        "descending" => Keys::Descending,
        "high" => Keys::HighBits,
        other => bail!("unknown keys '{other}' (random, equal, descending, high)"),
    })
}

/// Whether the sort moves values: `pairs` or `keys`.
fn parse_moves(name: &str) -> Result<bool> {
    Ok(match name {
        "pairs" => true,
        "keys" => false,
        other => bail!("unknown --moves '{other}' (pairs, keys)"),
    })
}

/// How the target's radix sort ranks.
fn describe_sort(shape: SortShape) -> String {
    let ranking = match shape.ballots() {
        true => "subgroup ballots",
        false => "per-thread counts",
    };
    format!(
        "radix sort: {}-bit digits ranked by {ranking}, {} elements a thread",
        shape.digit_bits, shape.items
    )
}

fn ms(s: Option<f64>) -> String {
    s.map_or("-".to_string(), |s| format!("{:.4}", s * 1e3))
}

pub fn operators(args: OperatorsArgs) -> Result<()> {
    let gpu = Gpu::new(args.adapter.as_deref())?;
    let target = Target {
        sort_items: args.sort_items,
        ..gpu.target()
    };
    let target = match args.no_subgroups {
        true => target.without_subgroups(),
        false => target,
    };
    println!("adapter: {}", gpu.describe());
    println!("subgroup kernels: {}", target.subgroups());
    println!("{}", describe_sort(SortShape::of(&target)));
    let failed = scans(&args, &gpu, &target)? + radix_sorts(&args, &gpu, &target)?;
    if failed > 0 {
        bail!("{failed} runs differ from the CPU");
    }
    Ok(())
}

/// The table of scans (`u32` and `f32`) and counting sorts; the runs that differ from the CPU.
fn scans(args: &OperatorsArgs, gpu: &Gpu, target: &Target) -> Result<usize> {
    let patterns = if args.patterns.is_empty() {
        Pattern::ALL.to_vec()
    } else {
        args.patterns.iter().map(|p| parse_pattern(p)).collect::<Result<_>>()?
    };
    println!(
        "\n| elements | buckets | inputs | instance | scan (ms) | f32 scan (ms) | counting sort (ms) | against the CPU |"
    );
    println!("|---:|---:|---|---:|---:|---:|---:|---|");
    let mut failed = 0;
    let mut kernel_lines = Vec::new();
    for &n in &args.sizes {
        let buckets = match args.buckets.as_str() {
            "n" => n.max(1),
            b => b.parse()?,
        };
        for (&pattern, i) in patterns
            .iter()
            .flat_map(|p| std::iter::repeat(p).zip(1..=args.instances))
        {
            let r = check(gpu, target, n, buckets, pattern, args.runs, args.warm_up)?;
            failed += r.mismatch.is_some() as usize;
            println!(
                "| {n} | {buckets} | {pattern:?} | {i} | {} | {} | {} | {} |",
                ms(r.scan_seconds),
                ms(r.f32_scan_seconds),
                ms(r.sort_seconds),
                verdict(&r.mismatch)
            );
            kernel_lines.push(format!("{n} {pattern:?} #{i}: {}", kernel_times(&r.kernels)));
        }
    }
    if args.kernels {
        println!(
            "\nkernels (ms): lg_op0 is the scan; lg_op1..4 the clear, count, scan of the counts and scatter; lg_op5 the scatter of 48-byte elements; lg_op8 the f32 scan"
        );
        for line in kernel_lines {
            println!("  {line}");
        }
    }
    Ok(failed)
}

/// The table of radix sorts; the runs that differ from the CPU.
fn radix_sorts(args: &OperatorsArgs, gpu: &Gpu, target: &Target) -> Result<usize> {
    let keys = if args.keys.is_empty() {
        Keys::ALL.to_vec()
    } else {
        args.keys.iter().map(|k| parse_keys(k)).collect::<Result<_>>()?
    };
    let moves = args.moves.iter().map(|m| parse_moves(m)).collect::<Result<Vec<_>>>()?;
    println!("\n| elements | keys | moves | bits | instance | radix sort (ms) | keys/s | against the CPU |");
    println!("|---:|---|---|---:|---:|---:|---:|---|");
    let mut failed = 0;
    let mut kernel_lines = Vec::new();
    for &n in &args.sizes {
        for &values in &moves {
            for (&pattern, i) in keys.iter().flat_map(|k| std::iter::repeat(k).zip(1..=args.instances)) {
                let c = SortCheck {
                    n,
                    pattern,
                    bits: args.bits,
                    values,
                    runs: args.runs,
                    warm_up: args.warm_up,
                };
                let r = sort::check(gpu, target, c)?;
                failed += r.mismatch.is_some() as usize;
                let rate = r
                    .seconds
                    .filter(|&s| s > 0.0)
                    .map_or("-".to_string(), |s| format!("{:.3e}", n as f64 / s));
                let moved = if values { "pairs" } else { "keys" };
                println!(
                    "| {n} | {pattern:?} | {moved} | {} | {i} | {} | {rate} | {} |",
                    args.bits,
                    ms(r.seconds),
                    verdict(&r.mismatch)
                );
                kernel_lines.push(format!("{n} {pattern:?} {moved} #{i}: {}", kernel_times(&r.kernels)));
            }
        }
    }
    if args.kernels {
        println!("\nkernels (ms) of the radix sort, per pass: digit histograms, their scan, scatter");
        for line in kernel_lines {
            println!("  {line}");
        }
    }
    Ok(failed)
}

fn verdict(mismatch: &Option<String>) -> String {
    match mismatch {
        None => "equal".to_string(),
        Some(m) => format!("DIFFERS: {m}"),
    }
}

fn kernel_times(kernels: &[(String, f64)]) -> String {
    let each: Vec<String> = kernels.iter().map(|(k, s)| format!("{k} {}", ms(Some(*s)))).collect();
    each.join(", ")
}
