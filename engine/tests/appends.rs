//! Queue appends from divergent control flow, aggregated per subgroup where the adapter has
//! subgroups and per item without: every item must arrive exactly once, and a queue that is
//! too small must count exactly the items that did not fit.

use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, Target, Vfs, compile};
use std::collections::BTreeMap;
use std::path::PathBuf;

#[path = "common/gpu.rs"]
mod gpu_common;
use gpu_common::{gpu, targets};

fn graph() -> Graph {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    Graph::load(&Vfs::new(vec![Layer::Dir(dir)]), "appends.ron").expect("the test graph loads")
}

const N: u32 = 1000;
const EMIT: u32 = 5;

/// Parts item `i` emits (appends.wgsl's `parts_of`).
fn parts_of(i: u32) -> u32 {
    (i.wrapping_mul(2654435761) >> 16) % (EMIT + 1)
}

/// What one frame of `layout` with the stream's `per_call` at `per` gives: the marks of every
/// part, the counters or the frame's error, and the queue's capacity.
struct Frame {
    seen: Vec<u32>,
    result: Result<BTreeMap<String, u64>, String>,
    capacity: u64,
}

fn run(layout: &str, target: &Target, per: u32) -> Frame {
    let g = graph();
    let spec = Specialization {
        constants: [("PER".to_string(), ConstValue::U32(per))].into_iter().collect(),
        ..Default::default()
    };
    let program = compile(&g, layout, &g.layouts[layout], &spec, target).unwrap();
    let aggregated = program
        .kernels
        .iter()
        .any(|k| k.source.text().contains("subgroupExclusiveAdd"));
    assert_eq!(
        aggregated,
        target.subgroups(),
        "{layout}: appends aggregate per subgroup exactly where the target has subgroups"
    );
    let capacity = program.resolved.queue_capacity[&program
        .plan
        .graph
        .stream_id("parts")
        .expect("the graph has stream parts")];
    let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    let result = instance.run_frame(0, 0).map(|s| s.counters).map_err(|e| e.to_string());
    let seen = bytemuck::pod_collect_to_vec(&instance.read("seen").unwrap());
    Frame { seen, result, capacity }
}

#[test]
fn every_part_emitted_from_divergent_control_flow_arrives_once() {
    let expected: Vec<u32> = (0..N * EMIT)
        .map(|k| u32::from(k % EMIT < parts_of(k / EMIT)))
        .collect();
    let total: u64 = expected.iter().map(|&s| s as u64).sum();
    assert!(total > 2 * N as u64, "items emit several parts: {total}");
    for (what, target) in targets() {
        for layout in ["queued", "queued_chunked"] {
            let frame = run(layout, &target, EMIT);
            let counters = frame.result.unwrap_or_else(|e| panic!("{what}, {layout}: {e}"));
            assert_eq!(counters["parts"], total, "{what}, {layout}: parts consumed");
            let wrong = expected.iter().zip(&frame.seen).filter(|(a, b)| a != b).count();
            assert_eq!(wrong, 0, "{what}, {layout}: {wrong} parts not received exactly once");
        }
    }
}

#[test]
fn a_queue_too_small_counts_exactly_the_parts_that_did_not_fit() {
    // Two parts per item declared, up to five emitted: about half of them do not fit.
    let per = 2;
    let total: u64 = (0..N).map(|i| parts_of(i) as u64).sum();
    for (what, target) in targets() {
        let frame = run("queued", &target, per);
        assert_eq!(frame.capacity, (N * per) as u64, "{what}: one chunk of N items");
        let lost = total - frame.capacity;
        let err = frame.result.expect_err("the overflow is an error");
        assert!(
            err.contains(&format!("queue 'parts' overflowed by {lost} items")),
            "{what}: {err}"
        );
        assert!(frame.seen.iter().all(|&s| s <= 1), "{what}: a part arrived twice");
        let arrived: u64 = frame.seen.iter().map(|&s| s as u64).sum();
        assert_eq!(arrived, frame.capacity, "{what}: the queue's slots are all used once");
    }
}
