//! `lightgraph operators`: the engine's collective operators (exclusive scan, counting sort)
//! checked against the CPU and timed on a GPU.

use anyhow::{Result, bail};
use clap::Args;
use lightgraph_engine::Gpu;
use lightgraph_engine::selfcheck::{Pattern, check};

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
    /// Runs per size; the times are the median.
    #[arg(long, default_value_t = 5)]
    pub runs: u32,
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

fn ms(s: Option<f64>) -> String {
    s.map_or("-".to_string(), |s| format!("{:.4}", s * 1e3))
}

pub fn operators(args: OperatorsArgs) -> Result<()> {
    let gpu = Gpu::new(args.adapter.as_deref())?;
    let target = match args.no_subgroups {
        true => gpu.target().without_subgroups(),
        false => gpu.target(),
    };
    let patterns = if args.patterns.is_empty() {
        Pattern::ALL.to_vec()
    } else {
        args.patterns.iter().map(|p| parse_pattern(p)).collect::<Result<_>>()?
    };
    println!("adapter: {}", gpu.describe());
    println!("subgroup kernels: {}", target.subgroups());
    println!("\n| elements | buckets | inputs | scan (ms) | counting sort (ms) | against the CPU |");
    println!("|---:|---:|---|---:|---:|---|");
    let mut failed = 0;
    let mut kernel_lines = Vec::new();
    for &n in &args.sizes {
        let buckets = match args.buckets.as_str() {
            "n" => n.max(1),
            b => b.parse()?,
        };
        for &pattern in &patterns {
            let r = check(&gpu, &target, n, buckets, pattern, args.runs)?;
            let verdict = match &r.mismatch {
                None => "equal".to_string(),
                Some(m) => {
                    failed += 1;
                    format!("DIFFERS: {m}")
                }
            };
            println!(
                "| {n} | {buckets} | {pattern:?} | {} | {} | {verdict} |",
                ms(r.scan_seconds),
                ms(r.sort_seconds)
            );
            let each: Vec<String> = r.kernels.iter().map(|(k, s)| format!("{k} {}", ms(Some(*s)))).collect();
            kernel_lines.push(format!("{n} {pattern:?}: {}", each.join(", ")));
        }
    }
    if args.kernels {
        println!("\nkernels (ms): lg_op0 is the scan; lg_op1..4 the clear, count, scan of the counts and scatter");
        for line in kernel_lines {
            println!("  {line}");
        }
    }
    if failed > 0 {
        bail!("{failed} runs differ from the CPU");
    }
    Ok(())
}
