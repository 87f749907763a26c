//! Range queries of the photon structures against brute force on the CPU (in f64, on the same
//! f32 inputs), through a test graph with its own contract (tests/data/graphs/pm_query.ron):
//! host-written photon clouds and queries, each query's photons counted and summed into an
//! order-independent checksum of their ids. The clouds: uniform; clustered at 10^6:1
//! density; all photons in one cell; empty regions; photons exactly on cell boundaries and
//! on the cube's bounds; coordinates near 1e4; a scene of scale 1e-4; queries wider than the
//! build radius; none, one and two (equal) photons; more photons counted than stored.
//!
//! The clouds keep every query's loops well below lavapipe's limit: llvmpipe ends a shader's
//! loops after 65535 iterations in all (of its 8 lanes together), so a hash-grid bucket of
//! 20 000 photons already truncates WhileQuery there; a GPU has no such limit.
//!
//! The kD-tree and the full hash grid (its queries whole, and split over threads with room
//! to spare and with too little) must find exactly the brute-force set. A photon whose
//! f64 distance is within a relative 1e-5 of the radius is ambiguous for f32 and excluded
//! from both sides: the GPU's set must be the CPU's plus some of the ambiguous photons (the
//! subset whose count, sum and xor match). A stochastic hash grid (rectified, and the
//! original with its insertion run over the photons in order) keeps one photon per bucket
//! standing for the bucket's photons: every photon it reports must be in range, one photon per
//! cell, always with the same weight, at least the photons of its cell.

use crate::common::{SplitMix64, data, gpu};
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, compile};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// Photon slots of the test graph, queries per cloud, and hash-grid buckets.
const CAPACITY: usize = 40_000;
const QUERIES: usize = 256;
const CELLS: u32 = 1 << 16;
/// Photons each query lists with their weights (QUERY_LISTED in pm_query.wgsl).
const LISTED: usize = 32;

/// Photons, their cube and build radius, and queries (centre, radius).
struct Cloud {
    name: &'static str,
    photons: Vec<[f32; 3]>,
    /// What `pm_count` says (more than the photons: overflow).
    count: u32,
    origin: [f32; 3],
    extent: f32,
    cell_radius: f32,
    queries: Vec<[f32; 4]>,
}

/// What the GPU found for one query.
#[derive(Debug, Clone, Copy)]
struct Found {
    found: u32,
    sum: u32,
    xor: u32,
    weight: f32,
    listed: [(u32, f32); LISTED],
}

/// The hash of an id (query_hash in pm_query.wgsl).
fn hash(id: u32) -> u32 {
    let mut x = id;
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

struct Random(SplitMix64);

impl Random {
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.0.next_f64()
    }
    fn point(&mut self, lo: [f64; 3], hi: [f64; 3]) -> [f32; 3] {
        [0, 1, 2].map(|k| self.range(lo[k], hi[k]) as f32)
    }
    fn cube(&mut self, origin: [f32; 3], size: f64) -> [f32; 3] {
        let o = origin.map(|v| v as f64);
        self.point(o, o.map(|v| v + size))
    }
}

/// `n` queries in the cube of `origin` and `size` (and a little beyond), radii in `radii`.
fn queries(rng: &mut Random, n: usize, origin: [f32; 3], size: f64, radii: (f64, f64)) -> Vec<[f32; 4]> {
    (0..n)
        .map(|_| {
            let o = origin.map(|v| v as f64 - 0.05 * size);
            let c = rng.cube(o.map(|v| v as f32), 1.1 * size);
            [c[0], c[1], c[2], rng.range(radii.0, radii.1) as f32]
        })
        .collect()
}

fn uniform(
    rng: &mut Random,
    name: &'static str,
    n: usize,
    origin: [f32; 3],
    extent: f32,
    cell_radius: f32,
    radii: (f64, f64),
) -> Cloud {
    let photons = (0..n).map(|_| rng.cube(origin, extent as f64)).collect();
    Cloud {
        name,
        photons,
        count: n as u32,
        origin,
        extent,
        cell_radius,
        queries: queries(rng, QUERIES, origin, extent as f64, radii),
    }
}

/// Half the photons spread over the cube, half in a cube 10^-6 of its volume (in one cell);
/// half the queries at the cluster, with radii to match.
fn clustered(rng: &mut Random) -> Cloud {
    let mut c = uniform(rng, "clustered 10^6:1", 5000, [-1.0; 3], 2.0, 0.05, (0.05, 0.1));
    let corner = [0.31f32, -0.42, 0.05];
    c.photons.extend((0..5000).map(|_| rng.cube(corner, 0.02)));
    c.count = c.photons.len() as u32;
    let near = queries(rng, QUERIES / 2, corner, 0.02, (0.0005, 0.004));
    c.queries.splice(..QUERIES / 2, near);
    c
}

/// Every photon in one cell of both the grid and the Morton grid (equal Morton codes).
fn one_cell(rng: &mut Random) -> Cloud {
    let corner = [0.3f32, 0.3, 0.3];
    let photons: Vec<[f32; 3]> = (0..3000).map(|_| rng.cube(corner, 1e-4)).collect();
    let mut q = queries(rng, QUERIES / 2, corner, 1e-4, (2e-5, 1e-4));
    q.extend(queries(rng, QUERIES / 2, [-1.0; 3], 2.0, (0.2, 0.4)));
    Cloud {
        name: "one cell",
        count: photons.len() as u32,
        photons,
        origin: [-1.0; 3],
        extent: 2.0,
        cell_radius: 0.05,
        queries: q,
    }
}

/// Two slabs of photons, queries between and across them.
fn empty_regions(rng: &mut Random) -> Cloud {
    let photons: Vec<[f32; 3]> = (0..20_000)
        .map(|i| {
            let x = if i % 2 == 0 { -1.0 } else { 0.8 };
            rng.point([x, -1.0, -1.0], [x + 0.2, 1.0, 1.0])
        })
        .collect();
    Cloud {
        name: "empty regions",
        count: photons.len() as u32,
        photons,
        origin: [-1.0; 3],
        extent: 2.0,
        cell_radius: 0.05,
        queries: queries(rng, QUERIES, [-1.0; 3], 2.0, (0.02, 0.3)),
    }
}

/// Photons on the lattice of grid cell corners (spacing 0.125: 64 Morton cells), the cube's
/// faces included, and photons with one coordinate on a cell boundary.
fn boundaries(rng: &mut Random) -> Cloud {
    let h = 0.125f32;
    let mut photons = Vec::new();
    for i in 0..17 {
        for j in 0..17 {
            for k in 0..17 {
                photons.push([i, j, k].map(|v| -1.0 + h * v as f32));
            }
        }
    }
    for n in 0..10_000 {
        let mut p = rng.cube([-1.0; 3], 2.0);
        p[n % 3] = -1.0 + h * (rng.range(0.0, 17.0).floor() as f32);
        photons.push(p);
    }
    let mut q = queries(rng, QUERIES, [-1.0; 3], 2.0, (0.05, 0.3));
    for (n, query) in q.iter_mut().enumerate().take(QUERIES / 2) {
        let corner = (n * 37) % 4913;
        query[..3].copy_from_slice(&photons[corner]);
    }
    Cloud {
        name: "cell boundaries and the cube's faces",
        count: photons.len() as u32,
        photons,
        origin: [-1.0; 3],
        extent: 2.0,
        cell_radius: h / 2.0,
        queries: q,
    }
}

fn tiny(rng: &mut Random, name: &'static str, photons: Vec<[f32; 3]>) -> Cloud {
    Cloud {
        name,
        count: photons.len() as u32,
        photons,
        origin: [-1.0; 3],
        extent: 2.0,
        cell_radius: 0.1,
        queries: queries(rng, QUERIES, [-1.0; 3], 2.0, (0.05, 0.8)),
    }
}

fn clouds() -> &'static [Cloud] {
    static CLOUDS: OnceLock<Vec<Cloud>> = OnceLock::new();
    CLOUDS.get_or_init(|| {
        let mut rng = Random(SplitMix64(0x5eed_f07f));
        let mut overflow = uniform(
            &mut rng,
            "more counted than stored",
            CAPACITY,
            [-1.0; 3],
            2.0,
            0.05,
            (0.02, 0.1),
        );
        overflow.count += 777;
        vec![
            uniform(&mut rng, "uniform", 30_000, [-1.0; 3], 2.0, 0.05, (0.02, 0.1)),
            clustered(&mut rng),
            one_cell(&mut rng),
            empty_regions(&mut rng),
            boundaries(&mut rng),
            uniform(
                &mut rng,
                "coordinates near 1e4",
                20_000,
                [1e4; 3],
                16.0,
                0.25,
                (0.1, 0.5),
            ),
            uniform(&mut rng, "scale 1e-4", 20_000, [-1e-4; 3], 2e-4, 4e-6, (2e-6, 1e-5)),
            uniform(
                &mut rng,
                "queries wider than the build radius",
                20_000,
                [-1.0; 3],
                2.0,
                0.02,
                (0.05, 0.15),
            ),
            tiny(&mut rng, "no photons", vec![]),
            tiny(&mut rng, "one photon", vec![[0.25, -0.5, 0.125]]),
            tiny(&mut rng, "two equal photons", vec![[0.25, -0.5, 0.125]; 2]),
            overflow,
        ]
    })
}

/// The photons in range of each query on the CPU (ids), and the ambiguous ones.
fn brute_force(cloud: &Cloud) -> Vec<(Vec<u32>, Vec<u32>)> {
    let stored = &cloud.photons[..(cloud.count as usize).min(CAPACITY).min(cloud.photons.len())];
    cloud
        .queries
        .iter()
        .map(|q| {
            let (mut inside, mut ambiguous) = (Vec::new(), Vec::new());
            let r = q[3] as f64;
            for (id, p) in stored.iter().enumerate() {
                let d = (0..3).map(|k| (p[k] as f64 - q[k] as f64).powi(2)).sum::<f64>().sqrt();
                if (d - r).abs() <= 1e-5 * r {
                    ambiguous.push(id as u32);
                } else if d < r {
                    inside.push(id as u32);
                }
            }
            (inside, ambiguous)
        })
        .collect()
}

/// How NaiveQuery splits the hash grid's queries over threads: above `entries` entries (0:
/// never) in parts of `chunk`, with room for `queries` queries and `parts` parts a run.
#[derive(Clone, Copy)]
struct Split {
    entries: u32,
    chunk: u32,
    queries: u32,
    parts: u32,
}

/// Queries are never split.
const UNSPLIT: Split = Split {
    entries: 0,
    chunk: 1,
    queries: 1,
    parts: 1,
};

/// An instance of the test graph for the structure `PM_STRUCTURE = structure`, the hash grid
/// queried with WhileQuery or NaiveQuery (`PM_WHILE_QUERY = while_query`), split as `split`.
fn instance(structure: u32, while_query: bool, split: Split) -> Instance<'static> {
    let vfs = lightgraph::assets::builtin().with_front(Layer::Dir(data("graphs")));
    let graph = Graph::load(&vfs, "pm_query.ron").unwrap();
    let constants = [
        ("PM_CAPACITY", CAPACITY as u32),
        ("QUERIES", QUERIES as u32),
        ("PM_CELLS", CELLS),
        ("PM_STRUCTURE", structure),
        ("PM_SPLIT_ENTRIES", split.entries),
        ("PM_SPLIT_CHUNK", split.chunk),
        ("PM_SPLIT_QUERIES", split.queries),
        ("PM_SPLIT_PARTS", split.parts),
    ];
    let spec = Specialization {
        constants: constants
            .iter()
            .map(|(k, v)| (k.to_string(), ConstValue::U32(*v)))
            .chain([("PM_WHILE_QUERY".to_string(), ConstValue::Bool(while_query))])
            .collect(),
        ..Default::default()
    };
    let program = compile(&graph, "query", &graph.layouts["query"], &spec, &gpu().target()).unwrap();
    Instance::new(gpu(), program, &BTreeMap::new()).unwrap()
}

/// Builds the structure over `cloud` and runs its queries.
fn run(instance: &mut Instance, cloud: &Cloud) -> Vec<Found> {
    let photons: Vec<[f32; 8]> = cloud
        .photons
        .iter()
        .enumerate()
        .map(|(id, p)| [p[0], p[1], p[2], 0.0, id as f32, 0.0, 0.0, 0.0])
        .collect();
    let o = cloud.origin;
    let scene = [o[0], o[1], o[2], cloud.extent, cloud.cell_radius, 0.0, 0.0, 0.0];
    instance.write("scene", bytemuck::cast_slice(&scene)).unwrap();
    instance.write("pm_count", bytemuck::bytes_of(&cloud.count)).unwrap();
    if !photons.is_empty() {
        instance.write("pm_staging", bytemuck::cast_slice(&photons)).unwrap();
    }
    instance.write("queries", bytemuck::cast_slice(&cloud.queries)).unwrap();
    instance.run_frame(0, 0).unwrap();
    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("film").unwrap());
    words
        .chunks_exact(4 + 2 * LISTED)
        .map(|w| Found {
            found: w[0],
            sum: w[1],
            xor: w[2],
            weight: f32::from_bits(w[3]),
            listed: std::array::from_fn(|k| (w[4 + 2 * k], f32::from_bits(w[5 + 2 * k]))),
        })
        .collect()
}

/// Whether the GPU's photons are the CPU's plus some ambiguous ones: a subset of `ambiguous`
/// whose count, sum and xor make up the difference. `None` when there are too many ambiguous
/// photons to try every subset.
fn explains(gpu: &Found, inside: &[u32], ambiguous: &[u32]) -> Option<bool> {
    if ambiguous.len() > 16 {
        return None;
    }
    let sum = inside.iter().fold(0u32, |s, &i| s.wrapping_add(hash(i)));
    let xor = inside.iter().fold(0u32, |s, &i| s ^ hash(i));
    Some((0u32..1 << ambiguous.len()).any(|subset| {
        let chosen = ambiguous.iter().enumerate().filter(|(k, _)| subset & (1 << k) != 0);
        let (n, s, x) = chosen.fold((inside.len() as u32, sum, xor), |(n, s, x), (_, &i)| {
            (n + 1, s.wrapping_add(hash(i)), x ^ hash(i))
        });
        (n, s, x) == (gpu.found, gpu.sum, gpu.xor)
    }))
}

/// The first disagreement of an exact structure with brute force over `cloud`; the queries
/// skipped for too many ambiguous photons are counted in `skipped`.
fn exact_mismatch(cloud: &Cloud, found: &[Found], skipped: &mut usize) -> Option<String> {
    for (q, ((inside, ambiguous), gpu)) in brute_force(cloud).iter().zip(found).enumerate() {
        let listed = &gpu.listed[..(gpu.found as usize).min(LISTED)];
        let stray = listed
            .iter()
            .find(|(id, _)| !inside.contains(id) && !ambiguous.contains(id));
        let what = format!("{}: query {q} {:?}", cloud.name, cloud.queries[q]);
        if let Some((id, _)) = stray {
            return Some(format!("{what}: photon {id} is out of range"));
        }
        if gpu.weight != gpu.found as f32 || listed.iter().any(|&(_, w)| w != 1.0) {
            return Some(format!("{what}: weights {} for {} photons", gpu.weight, gpu.found));
        }
        match explains(gpu, inside, ambiguous) {
            None => *skipped += 1,
            Some(true) => {}
            Some(false) => {
                return Some(format!(
                    "{what}: found {} photons, brute force {} (+ {} ambiguous)",
                    gpu.found,
                    inside.len(),
                    ambiguous.len()
                ));
            }
        }
    }
    None
}

/// Runs every cloud through an exact structure; the queries it split over threads.
fn exact_structure(structure: u32, while_query: bool, split: Split, name: &str) -> u64 {
    let mut instance = instance(structure, while_query, split);
    let (mut skipped, mut photons_found) = (0, 0u64);
    for cloud in clouds() {
        let found = run(&mut instance, cloud);
        if let Some(m) = exact_mismatch(cloud, &found, &mut skipped) {
            panic!("{name}: {m}");
        }
        photons_found += found.iter().map(|f| f.found as u64).sum::<u64>();
    }
    eprintln!("{name}: {photons_found} photons found, {skipped} queries skipped");
    // The clouds are not trivially empty, and hardly any query is left unchecked.
    assert!(photons_found > 100_000, "{name}: only {photons_found} photons found");
    assert!(
        skipped < 10,
        "{name}: {skipped} queries with too many ambiguous photons"
    );
    instance.counter_totals().get("pm_split").copied().unwrap_or(0)
}

#[test]
fn kd_tree_queries_find_exactly_the_photons_in_range() {
    exact_structure(3, false, UNSPLIT, "kD-tree");
}

#[test]
fn full_hash_grid_queries_find_exactly_the_photons_in_range() {
    // NaiveQuery reads a bucket's photons four at a time: buckets of every size mod 4.
    exact_structure(0, false, UNSPLIT, "full hash grid, NaiveQuery");
    exact_structure(0, true, UNSPLIT, "full hash grid, WhileQuery");
}

#[test]
fn queries_split_over_threads_find_exactly_the_photons_in_range() {
    // Parts of sizes that are not multiples of four, starting anywhere in a bucket; then so
    // little room that most split queries walk their cells themselves after all.
    let roomy = Split {
        entries: 64,
        chunk: 13,
        queries: QUERIES as u32,
        parts: 1 << 20,
    };
    let split = exact_structure(0, false, roomy, "full hash grid, split above 64 entries");
    assert!(split > 200, "only {split} queries split");
    let cramped = Split {
        entries: 8,
        chunk: 5,
        queries: 40,
        parts: 300,
    };
    let split = exact_structure(0, false, cramped, "full hash grid, split with little room");
    assert!(split > 0, "no query split");
}

/// The cell of a photon (cell_of in shaders/pm/cells.wgsl), or `None` within 1e-4 of a cell
/// boundary, where f32 may round either way.
fn cell_of(cloud: &Cloud, p: [f32; 3]) -> Option<[i64; 3]> {
    let size = 2.0 * cloud.cell_radius as f64;
    let x = [0, 1, 2].map(|k| (p[k] as f64 - cloud.origin[k] as f64) / size);
    x.iter()
        .all(|v| (v - v.round()).abs() > 1e-4)
        .then(|| x.map(|v| v.floor() as i64))
}

/// The first inconsistency of a stochastic grid's reports over `cloud`.
fn stochastic_mismatch(cloud: &Cloud, found: &[Found]) -> Option<String> {
    let stored = &cloud.photons[..(cloud.count as usize).min(CAPACITY).min(cloud.photons.len())];
    let mut per_cell: BTreeMap<[i64; 3], u32> = BTreeMap::new();
    for p in stored {
        if let Some(c) = cell_of(cloud, *p) {
            *per_cell.entry(c).or_default() += 1;
        }
    }
    let mut kept: BTreeMap<u32, f32> = BTreeMap::new();
    let mut kept_in_cell: BTreeMap<[i64; 3], u32> = BTreeMap::new();
    for (q, ((inside, ambiguous), gpu)) in brute_force(cloud).iter().zip(found).enumerate() {
        let what = format!("{}: query {q} {:?}", cloud.name, cloud.queries[q]);
        for &(id, w) in &gpu.listed[..(gpu.found as usize).min(LISTED)] {
            if !inside.contains(&id) && !ambiguous.contains(&id) {
                return Some(format!("{what}: photon {id} is out of range"));
            }
            if *kept.entry(id).or_insert(w) != w || w.fract() != 0.0 || w < 1.0 || w > stored.len() as f32 {
                return Some(format!("{what}: photon {id} stands for {w} and {} photons", kept[&id]));
            }
            let Some(cell) = cell_of(cloud, stored[id as usize]) else {
                continue;
            };
            if w < per_cell[&cell] as f32 {
                return Some(format!(
                    "{what}: photon {id} stands for {w} photons, its cell holds {}",
                    per_cell[&cell]
                ));
            }
            if *kept_in_cell.entry(cell).or_insert(id) != id {
                return Some(format!(
                    "{what}: photons {id} and {} kept for one cell",
                    kept_in_cell[&cell]
                ));
            }
        }
    }
    None
}

#[test]
fn stochastic_hash_grids_report_photons_in_range_with_consistent_weights() {
    for (structure, name) in [(1, "rectified"), (2, "original")] {
        let mut instance = instance(structure, false, UNSPLIT);
        let mut reported = 0;
        for cloud in clouds() {
            let found = run(&mut instance, cloud);
            if let Some(m) = stochastic_mismatch(cloud, &found) {
                panic!("{name} stochastic hash grid: {m}");
            }
            reported += found.iter().map(|f| f.found as usize).sum::<usize>();
        }
        assert!(reported > 1000, "{name}: only {reported} photons reported");
    }
}
