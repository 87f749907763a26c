//! Fuzzing of the frame-graph front end with proptest: RON graphs, pass catalogs and WGSL
//! sources are mutated and run through [`Graph::from_text`], [`Plan::new`] for every layout
//! and [`compile`] (WGSL generation and naga validation, on the CPU with
//! [`Target::default`]) for one layout; random layouts are planned and compiled against the
//! unmutated graphs.
//!
//! Seeds: the Collatz test graph (`tests/data`), `graphs/ao.ron` and `graphs/pt.ron` with their
//! catalogs and shaders. Each input mutates one file of a seed with up to three edits (see
//! `common/fuzz.rs`).
//!
//! Properties: no input panics; every refusal is an error whose message is not empty, and a
//! RON or graph error (`Error::Parse`, `Error::Invalid`) starts with `FILE:LINE:COLUMN:` where
//! FILE is a file of the graph and LINE lies within it; a shader error names a source file or
//! generated kernel.
//!
//! Bound: 2000 mutated graphs and 500 layouts, about half a minute in a debug build on two cores;
//! `LIGHTGRAPH_FUZZ_CASES=N cargo test -p lightgraph-engine --test fuzz_graph -- --nocapture`
//! runs N inputs per test (and prints the counts), `LIGHTGRAPH_FUZZ_SEED=K` other inputs.

#[path = "common/fuzz.rs"]
mod fuzz;

use fuzz::{Mutated, Outcome, RON, check_located, edits, fuzz};
use lightgraph_engine::auto;
use lightgraph_engine::ir::{GraphFile, LayoutDecl, LoopMode, PassEntry, Policy, StateStorage};
use lightgraph_engine::{ConstValue, Error, Graph, Layer, Plan, Specialization, Target, Vfs, compile};
use proptest::prelude::*;
use proptest::sample::Index;
use std::path::PathBuf;
use std::sync::OnceLock;

/// A graph with every file it reads.
struct Seed {
    /// The directory its virtual paths are relative to.
    root: PathBuf,
    /// The graph's virtual path.
    graph: String,
    /// Virtual path and text of the graph, its catalogs and WGSL files, the graph first.
    files: Vec<(String, String)>,
}

fn seeds() -> &'static [Seed] {
    static SEEDS: OnceLock<Vec<Seed>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let engine = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
        let repo = engine.parent().expect("the engine lies in the workspace").to_path_buf();
        [
            (engine.join("tests/data"), "collatz.ron"),
            (repo.clone(), "graphs/ao.ron"),
            (repo, "graphs/pt.ron"),
        ]
        .into_iter()
        .map(|(root, graph)| {
            let vfs = Vfs::new(vec![Layer::Dir(root.clone())]);
            let text = vfs.read(graph).unwrap();
            let file: GraphFile = lightgraph_engine::graph::parse_ron(graph, &text).unwrap();
            let loaded = Graph::from_text(&vfs, graph, &text).unwrap();
            let mut paths = vec![graph.to_string()];
            paths.extend(file.catalogs.iter().cloned());
            paths.extend(file.include.iter().cloned());
            paths.extend(loaded.library.iter().cloned());
            for p in &loaded.declared.passes {
                if !paths.contains(&p.decl.source) {
                    paths.push(p.decl.source.clone());
                }
            }
            let files = paths.into_iter().map(|p| (p.clone(), vfs.read(&p).unwrap())).collect();
            Seed {
                root,
                graph: graph.to_string(),
                files,
            }
        })
        .collect()
    })
}

/// The host constants the renderer gives every graph: WIDTH, HEIGHT, PIXELS,
/// SAMPLES_PER_PIXEL and PATHS.
const HOST: [&str; 5] = ["WIDTH", "HEIGHT", "PIXELS", "SAMPLES_PER_PIXEL", "PATHS"];

/// The host constants with `values` (a 4x4 image with 2 samples per pixel by default).
fn specialization(values: [u32; 5]) -> Specialization {
    let constants = HOST
        .iter()
        .zip(values)
        .map(|(k, v)| (k.to_string(), ConstValue::U32(v)))
        .collect();
    Specialization {
        constants,
        ..Default::default()
    }
}

/// A 4x4 image with 2 samples per pixel.
const DEFAULT_HOST: [u32; 5] = [4, 4, 16, 2, 32];

/// A seed (by index) with one file mutated, and the layout to compile (among those that plan).
type Case = (usize, Mutated, Index);

fn mutated() -> impl Strategy<Value = Case> {
    (any::<Index>(), 0..10u8, any::<Index>(), edits(3), any::<Index>()).prop_map(|(s, kind, f, edits, layout)| {
        let seed = s.index(seeds().len());
        let files = &seeds()[seed].files;
        // Half the inputs mutate the graph, the rest a catalog or a WGSL file.
        let suffix = match kind {
            0..=4 => "",
            5..=6 => ".ron",
            _ => ".wgsl",
        };
        let candidates: Vec<&(String, String)> = files[1..].iter().filter(|(p, _)| p.ends_with(suffix)).collect();
        let (file, text) = match suffix {
            "" => &files[0],
            _ if candidates.is_empty() => &files[0],
            _ => candidates[f.index(candidates.len())],
        };
        (seed, Mutated::new(file, text, edits, &RON), layout)
    })
}

/// A directory holding one input's mutated file, removed when dropped.
struct CaseDir(PathBuf);

impl CaseDir {
    fn new(file: &str, text: &str) -> CaseDir {
        let dir = std::env::temp_dir().join(format!("lightgraph-fuzz-graph-{}", std::process::id()));
        let path = dir.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
        CaseDir(dir)
    }
}

impl Drop for CaseDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Checks the error's properties (see the file's documentation).
fn check_error(e: &Error, vfs: &Vfs, graph: (&str, &str)) -> Result<(), String> {
    let message = e.to_string();
    match e {
        Error::Parse { at, .. } | Error::Invalid { at, .. } => {
            let text = if at.file == graph.0 {
                graph.1.to_string()
            } else {
                vfs.read(&at.file)
                    .map_err(|_| format!("'{message}' names '{}', which is not a file of the graph", at.file))?
            };
            check_located(&message, &at.file, text.lines().count())
        }
        Error::Shader(m) if m.contains(".wgsl") || m.contains("<generated") => Ok(()),
        _ => Err(format!("'{message}' is not a located error")),
    }
}

/// Loads the graph, plans every layout (or `decl`, with its host constants) and compiles the
/// plan `layout` picks; a refusal must be a good error.
fn run(
    vfs: &Vfs,
    file: &str,
    text: &str,
    layout: &Index,
    decl: Option<(LayoutDecl, [u32; 5])>,
) -> Result<Outcome, String> {
    let checked = |e: Error| check_error(&e, vfs, (file, text)).map(|()| Outcome::Refused(e.to_string()));
    let graph = match Graph::from_text(vfs, file, text) {
        Ok(g) => g,
        Err(e) => return checked(e),
    };
    let mut plans = Vec::new();
    let mut host = DEFAULT_HOST;
    match decl {
        Some((decl, values)) => match Plan::with_decl(&graph, "fuzzed", decl) {
            Ok(p) => {
                plans.push(p);
                host = values;
            }
            Err(e) => return checked(e),
        },
        None => {
            for name in graph.layouts.keys() {
                match Plan::new(&graph, name) {
                    Ok(p) => plans.push(p),
                    Err(e) => checked(e).map(|_| ())?,
                }
            }
        }
    }
    if plans.is_empty() {
        return Ok(Outcome::Refused("no layout plans".into()));
    }
    let plan = &plans[layout.index(plans.len())];
    match compile(
        &plan.graph,
        &plan.layout_name,
        &plan.layout,
        &specialization(host),
        &Target::default(),
    ) {
        Ok(_) => Ok(Outcome::Ok),
        Err(e) => checked(e),
    }
}

#[test]
fn fuzz_graph_files() {
    fuzz("graph", 2000, mutated(), |(seed, m, layout)| {
        let seed = &seeds()[*seed];
        let base = Layer::Dir(seed.root.clone());
        let (vfs, graph_text, _dir) = if m.file == seed.graph {
            (Vfs::new(vec![base]), m.text.clone(), None)
        } else {
            let dir = CaseDir::new(&m.file, &m.text);
            let vfs = Vfs::new(vec![Layer::Dir(dir.0.clone()), base]);
            (vfs, seed.files[0].1.clone(), Some(dir))
        };
        run(&vfs, &seed.graph, &graph_text, layout, None)
    });
}

/// Every legal layout of each seed (`auto::legal_layouts`).
fn legal() -> &'static [Vec<LayoutDecl>] {
    static LEGAL: OnceLock<Vec<Vec<LayoutDecl>>> = OnceLock::new();
    LEGAL.get_or_init(|| {
        seeds()
            .iter()
            .map(|seed| {
                let vfs = Vfs::new(vec![Layer::Dir(seed.root.clone())]);
                let graph = Graph::from_text(&vfs, &seed.graph, &seed.files[0].1).unwrap();
                let legal = auto::legal_layouts(&graph, &LayoutDecl::default());
                legal.into_iter().map(|(_, decl)| decl).collect()
            })
            .collect()
    })
}

/// A layout of a seed: mostly one of its legal layouts, otherwise each pass in one of four
/// kernels, now and then with one more name, unknown or repeated; options random, mostly
/// legal.
fn layout() -> impl Strategy<Value = (usize, LayoutDecl)> {
    let rare = |common: Vec<u64>, odd: Vec<u64>| prop_oneof![9 => prop::sample::select(common), 1 => prop::sample::select(odd)];
    let options = (
        rare(vec![1, 32, 64, 256], vec![0, 1025, u32::MAX as u64]),
        prop::option::of(rare(vec![1, 100, 1 << 20], vec![0, u64::MAX])),
        prop::option::of(rare(vec![1, 7, 1 << 20], vec![0, u64::MAX])),
        prop::sample::select(vec![LoopMode::InKernel, LoopMode::Host]),
        prop::sample::select(vec![Policy::Naive, Policy::Regeneration, Policy::Compaction]),
        prop::sample::select(vec![StateStorage::SoA, StateStorage::AoS]),
    );
    let random = (
        prop::collection::vec(0..4usize, 8),
        prop::option::weighted(0.2, (any::<Index>(), 0..4usize)),
    );
    let kernels = prop::option::weighted(0.2, random);
    (any::<Index>(), any::<Index>(), kernels, options).prop_map(
        |(s, l, kernels, (wg, flight, threads, loops, policy, state))| {
            let seed = s.index(seeds().len());
            let legal = &legal()[seed];
            let options = LayoutDecl {
                state,
                workgroup_size: wg as u32,
                max_items_in_flight: flight,
                threads,
                ..legal[l.index(legal.len())].clone()
            };
            let Some((kernel_of, extra)) = kernels else {
                return (seed, options);
            };
            let file: GraphFile = lightgraph_engine::graph::parse_ron("g", &seeds()[seed].files[0].1).unwrap();
            // Operators are not listed in layouts.
            let mut names: Vec<String> = file
                .passes
                .iter()
                .filter_map(|p| match p {
                    PassEntry::Use(name) => Some(name.clone()),
                    PassEntry::UseWith(with) => Some(with.name.clone()),
                    PassEntry::Pass(decl) => Some(decl.name.clone()),
                    _ => None,
                })
                .collect();
            let mut kernels: Vec<Vec<String>> = vec![Vec::new(); 4];
            for (name, &k) in names.iter().zip(&kernel_of) {
                kernels[k].push(name.clone());
            }
            if let Some((pick, k)) = extra {
                names.push("no_such_pass".into());
                kernels[k].push(names[pick.index(names.len())].clone());
            }
            kernels.retain(|k| !k.is_empty());
            (
                seed,
                LayoutDecl {
                    kernels,
                    loops,
                    policy,
                    ..options
                },
            )
        },
    )
}

/// Host constants: mostly the defaults, now and then extreme values.
fn host() -> impl Strategy<Value = [u32; 5]> {
    let odd = prop::array::uniform5(prop::sample::select(vec![0, 1, 3, 65535, u32::MAX]));
    prop_oneof![3 => Just(DEFAULT_HOST), 1 => odd]
}

#[test]
fn fuzz_graph_layouts() {
    fuzz(
        "layout",
        500,
        (layout(), host(), any::<Index>()),
        |((seed, decl), host, i)| {
            let seed = &seeds()[*seed];
            let vfs = Vfs::new(vec![Layer::Dir(seed.root.clone())]);
            run(&vfs, &seed.graph, &seed.files[0].1, i, Some((decl.clone(), *host)))
        },
    );
}

#[test]
fn seeds_compile() {
    for seed in seeds() {
        let vfs = Vfs::new(vec![Layer::Dir(seed.root.clone())]);
        let graph = Graph::from_text(&vfs, &seed.graph, &seed.files[0].1).unwrap();
        let (layout, decl) = (&graph.default_layout, &graph.layouts[&graph.default_layout]);
        compile(&graph, layout, decl, &specialization(DEFAULT_HOST), &Target::default()).unwrap();
    }
}

#[test]
fn errors_are_checked() {
    let bad = Error::Invalid {
        at: lightgraph_engine::Location {
            file: "collatz.ron".into(),
            line: 999,
            column: 1,
        },
        message: "x".into(),
    };
    let vfs = Vfs::new(vec![Layer::Dir(seeds()[0].root.clone())]);
    assert!(check_error(&bad, &vfs, ("collatz.ron", "")).is_err());
}
