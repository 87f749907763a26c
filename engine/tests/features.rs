//! Graph features of the engine on graphs with no light transport: a bucket table built by
//! the collective operators alone over a domain counted on the GPU, in every layout the
//! engine enumerates; per-frame parameters changed between frames without recompiling.

use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, Vfs, compile};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

#[path = "common/gpu.rs"]
mod gpu_common;
use gpu_common::{gpu, program};

fn load(file: &str) -> Graph {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    Graph::load(&Vfs::new(vec![Layer::Dir(dir)]), file).expect("the test graph loads")
}

/// The WGSL hash of tests/data/buckets.wgsl.
fn bucket_hash(x: u32) -> u32 {
    let h = x.wrapping_mul(747796405).wrapping_add(2891336453);
    let h = ((h >> ((h >> 28) + 4)) ^ h).wrapping_mul(277803737);
    (h >> 22) ^ h
}

fn coordinate(h: u32) -> f32 {
    (h >> 8) as f32 * (2.0 / 16777216.0) - 1.0
}

/// The points inside the unit disk, by cell, as the CPU finds them.
fn cpu_buckets(candidates: u32, seed: u32) -> Vec<BTreeSet<(u32, u32)>> {
    let mut cells = vec![BTreeSet::new(); 64];
    for i in 0..candidates {
        let x = coordinate(bucket_hash((2 * i).wrapping_add(seed)));
        let y = coordinate(bucket_hash((2 * i + 1).wrapping_add(seed)));
        if x * x + y * y >= 1.0 {
            continue;
        }
        let (cx, cy) = (((x + 1.0) * 4.0) as u32, ((y + 1.0) * 4.0) as u32);
        cells[(cy * 8 + cx) as usize].insert((x.to_bits(), y.to_bits()));
    }
    cells
}

/// One frame of the bucket graph in layout `decl`: the table read back by cell, and the
/// points marked by the counted phase.
fn gpu_buckets(
    g: &Graph,
    name: &str,
    decl: LayoutDecl,
    candidates: u32,
    seed: u32,
) -> (Vec<BTreeSet<(u32, u32)>>, u64) {
    let spec = Specialization {
        constants: [("CANDIDATES".to_string(), ConstValue::U32(candidates))]
            .into_iter()
            .collect(),
        ..Default::default()
    };
    let program = compile(g, name, &decl, &spec, &gpu().target()).unwrap();
    let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    let stats = instance.run_frame(0, seed).unwrap();
    let starts: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("starts").unwrap());
    let counts: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("counts").unwrap());
    let table: Vec<[f32; 2]> = bytemuck::pod_collect_to_vec(&instance.read("table").unwrap());
    let marks: Vec<u32> = bytemuck::pod_collect_to_vec(&instance.read("marks").unwrap());
    let stored: u32 = counts.iter().sum();
    assert!(
        marks.iter().take(stored as usize).all(|&m| m == 1) && marks[stored as usize..].iter().all(|&m| m == 0),
        "layout {name}: the counted phase marks exactly the {stored} stored points once"
    );
    let cells = (0..64)
        .map(|c| {
            let range = starts[c] as usize..(starts[c] + counts[c]) as usize;
            table[range].iter().map(|p| (p[0].to_bits(), p[1].to_bits())).collect()
        })
        .collect();
    (cells, stats.counters["marked"])
}

#[test]
fn operators_build_a_bucket_table_over_a_counted_domain_in_every_layout() {
    let g = load("buckets.ron");
    let (candidates, seed) = (3000, 17);
    let expected = cpu_buckets(candidates, seed);
    let stored: usize = expected.iter().map(|c| c.len()).sum();
    assert!(
        stored > 2000 && stored < 2500,
        "about pi / 4 of the candidates: {stored}"
    );
    let layouts = lightgraph_engine::auto::legal_layouts(&g, &Default::default());
    // Each phase's two passes fused or split (no loop, so no policy makes a difference).
    assert_eq!(
        layouts.len(),
        4,
        "{:?}",
        layouts.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    for (name, decl) in layouts {
        // Split phases store their items: in chunks of 500 too (the counted phase's chunks
        // then count the stored points each chunk holds on the GPU).
        for in_flight in [None, Some(500)] {
            let decl = LayoutDecl {
                max_items_in_flight: in_flight,
                ..decl.clone()
            };
            let (cells, marked) = gpu_buckets(&g, &name, decl, candidates, seed);
            assert_eq!(
                marked, stored as u64,
                "layout {name}: the counted phase runs once per stored point"
            );
            for (c, (got, want)) in cells.iter().zip(&expected).enumerate() {
                assert_eq!(got, want, "layout {name}, chunks {in_flight:?}: cell {c}");
            }
        }
    }
}

/// Runs frames of the parameter graph on one instance; returns `values` after each step.
#[test]
fn parameters_change_between_frames_without_recompiling() {
    let g = load("params.ron");
    let mut instance = Instance::new(gpu(), program(&g, "fused"), &BTreeMap::new()).unwrap();
    let values = |instance: &Instance| -> Vec<f32> { bytemuck::pod_collect_to_vec(&instance.read("values").unwrap()) };
    instance.run_frame(0, 0).unwrap();
    let v = values(&instance);
    assert_eq!(&v[..5], &[0.0, 1.0, 2.0, 3.0, 0.0], "defaults: 4 cells of i x 1");
    instance.set_parameter("SCALE", ConstValue::F32(2.5)).unwrap();
    instance.set_parameter("ACTIVE", ConstValue::U32(10)).unwrap();
    instance.set_parameter("NEGATE", ConstValue::Bool(true)).unwrap();
    instance.run_frame(1, 0).unwrap();
    let v = values(&instance);
    for (i, &x) in v.iter().enumerate() {
        let want = if i < 10 { 1.0 - 2.5 * i as f32 } else { 0.0 };
        assert_eq!(x, want, "frame 1, cell {i}");
    }
    // A schedule: the scale follows the frame index within one batch of frames.
    instance
        .set_parameter_schedule("SCALE", |frame| frame as f64 * 0.5)
        .unwrap();
    instance
        .set_parameter_schedule("ACTIVE", |frame| frame as f64 + 8.0)
        .unwrap();
    instance.run_frames(2, 3, 0).unwrap();
    let v = values(&instance);
    for (i, &x) in v.iter().enumerate().take(12) {
        assert_eq!(x, 4.0 - 2.0 * i as f32, "frame 4 (scale 2, 12 cells), cell {i}");
    }
    let err = instance
        .set_parameter("SCALE", ConstValue::U32(3))
        .unwrap_err()
        .to_string();
    assert!(err.contains("parameter 'SCALE' is f32 but was given as u32"), "{err}");
    let err = instance
        .set_parameter("SCALED", ConstValue::F32(3.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no parameter 'SCALED'") && err.contains("SCALE"), "{err}");
}
