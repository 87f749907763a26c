//! The collective operators against the CPU: an exclusive scan of `u32`s and one of `f32`s
//! (against an `f64` sum, to a tolerance from float rounding), a counting sort (clear,
//! count, scan of the counts, scatter) at the lengths around every boundary of the kernels
//! (0, 1, 2, a subgroup of 32 and a workgroup of 256 plus or minus one, a scan tile plus or
//! minus one, and 2^20 + 7), with random inputs, all-equal ones (one bucket holding every
//! element) and concentrated ones, with and without subgroup operations, and with small tiles
//! so that the scan goes through two and three levels of partial sums. The radix sort against
//! a stable CPU sort (values from the indices show any instability): lengths 0, 1, a tile
//! minus one, a tile, a tile plus one and 10^5 and more; random, all-equal, descending and
//! high-bit-only keys; fewer bits (odd passes copy back); small scan tiles; a GPU count; keys
//! without values; its errors; and its scratch as transient memory of its step. Each sort
//! test runs both rankings: subgroup ballots (the adapter's target, 8-bit digits) and
//! per-thread counts (without subgroups, and with subgroups but too little workgroup memory
//! for the ballots' rows).

use lightgraph_engine::ids::OpId;
use lightgraph_engine::resolve::BufferRef;
use lightgraph_engine::scratch::SortShape;
use lightgraph_engine::selfcheck::sort::{Keys, Sorter, compare};
use lightgraph_engine::selfcheck::{Inputs, Pattern, check, run};
use lightgraph_engine::{Graph, Instance, Program, Target, Vfs};
use std::collections::BTreeMap;
use std::time::Duration;

#[path = "common/gpu.rs"]
mod gpu_common;
use gpu_common::{gpu, targets};

fn check_all(target: &Target, what: &str, lengths: &[u64]) {
    for &n in lengths {
        for buckets in [n.max(1), 7] {
            for pattern in Pattern::ALL {
                let r = check(gpu(), target, n, buckets, pattern, 1, Duration::ZERO).unwrap();
                assert!(
                    r.mismatch.is_none(),
                    "{what}: n {n}, {buckets} buckets, {pattern:?}: {}",
                    r.mismatch.unwrap()
                );
            }
        }
    }
}

#[test]
fn scan_and_counting_sort_equal_the_cpu() {
    let lengths = [
        0,
        1,
        2,
        7,
        8,
        9,
        31,
        32,
        33,
        255,
        256,
        257,
        4095,
        4096,
        4097,
        (1 << 20) + 7,
    ];
    for (what, target) in targets() {
        check_all(&target, what, &lengths);
    }
}

#[test]
fn scans_of_two_and_three_levels_equal_the_cpu() {
    // Tiles of 256 elements: 65537 elements need two levels of partial sums, 2^20 + 7 three.
    for (what, mut target) in targets() {
        target.scan_items = 1;
        check_all(
            &target,
            &format!("{what}, tiles of 256"),
            &[255, 256, 257, 65535, 65536, 65537, (1 << 20) + 7],
        );
    }
}

#[test]
fn f32_scans_equal_an_f64_sum_to_float_rounding() {
    // One tile (1, 1000), two (4097), several (70000); with tiles of 256, 4097 and 70000 take
    // one and two levels of partial sums. `check` compares every sum with an f64 one to
    // `F32_SCAN_RELATIVE` (its doc derives it from float rounding); random weights in [0, 4)
    // with a few large ones, all 1 (exact in f32), and 0.25 with one 2^100 among them.
    for (what, mut target) in targets() {
        for items in [16, 1] {
            target.scan_items = items;
            for n in [1, 1000, 4097, 70_000] {
                for pattern in Pattern::ALL {
                    let r = check(gpu(), &target, n, 7, pattern, 1, Duration::ZERO).unwrap();
                    assert!(
                        r.mismatch.is_none(),
                        "{what}, tiles of {}: n {n}, {pattern:?}: {}",
                        256 * items,
                        r.mismatch.unwrap()
                    );
                }
            }
        }
    }
}

#[test]
fn a_key_beyond_the_buckets_is_an_error_not_a_lost_element() {
    let mut inputs = Inputs::draw(40, 7, Pattern::Random, 1);
    inputs.keys[13] = 7;
    let err = run(gpu(), &gpu().target(), &inputs, 7, 1, Duration::ZERO)
        .err()
        .expect("the frame fails");
    let msg = err.to_string();
    assert!(
        msg.contains("operator 'count'") && msg.contains("skipped 1 elements with a key beyond its counts"),
        "{msg}"
    );
}

/// Sorts `keys` (the first `over`, or with a counted sorter the first `count`) with values
/// from their indices, and asserts that the GPU equals a stable CPU sort of the first
/// `sorted`, the rest untouched.
fn sort_equals_cpu(sorter: &mut Sorter, keys: &[u32], (over, count): (u64, u32), sorted: usize, bits: u32, what: &str) {
    let values: Vec<u32> = (0..keys.len() as u32).map(|i| i ^ 0x5a5a_0000).collect();
    let out = sorter.sort(keys, &values, over, count, 1).unwrap();
    if let Some(m) = compare(keys, &values, sorted, bits, &out) {
        panic!("{what}: {m}");
    }
}

/// The targets the sort tests run: the adapter's and the one without subgroups, and where the
/// adapter ranks by ballots, the same with too little workgroup memory for them (per-thread
/// counts with subgroup scans).
fn sort_targets() -> Vec<(&'static str, Target)> {
    let mut out = targets();
    let adapter = gpu().target();
    if SortShape::of(&adapter).ballots() {
        let small = Target {
            workgroup_bytes: 8 << 10,
            ..adapter
        };
        assert!(!SortShape::of(&small).ballots());
        out.push(("subgroups, ranked by counts", small));
    }
    out
}

#[test]
fn an_adapter_with_subgroups_ranks_the_sort_by_ballots() {
    // lavapipe (subgroups of 8, 32 KiB of workgroup memory) must run the ballot ranking, or
    // CI would not test it: 32 rows of 128 words and 8 elements a thread fit.
    let target = gpu().target();
    if target.subgroups() {
        let shape = SortShape::of(&target);
        assert!(shape.ballots(), "{shape:?} for {target:?}");
        assert_eq!(shape.digit_bits, 8);
        assert_eq!(shape.rows, 256 / target.subgroup_min_size);
    }
    assert_eq!(SortShape::of(&target.without_subgroups()), SortShape::PORTABLE);
}

#[test]
fn radix_sort_equals_a_stable_cpu_sort() {
    for (what, target) in sort_targets() {
        let tile = SortShape::of(&target).tile() as usize;
        let lengths = [0, 1, tile - 1, tile, tile + 1, 100_000, 250_007];
        let mut sorter = Sorter::new(gpu(), &target, 250_012, 32, false).unwrap();
        for n in lengths {
            for pattern in Keys::ALL {
                // Five elements past the sorted ones must keep their places.
                let keys = pattern.draw(n + 5, n as u64);
                sort_equals_cpu(
                    &mut sorter,
                    &keys,
                    (n as u64, 0),
                    n,
                    32,
                    &format!("{what}: n {n}, {pattern:?}"),
                );
            }
        }
    }
}

#[test]
fn radix_sort_by_fewer_bits_and_with_small_scan_tiles() {
    // 30 bits (Morton codes) and 12 and 1 bit (odd passes, copied back), with random keys
    // whose higher bits must not matter; then tiles of 256 for the scan of the histograms,
    // which need a level of partial sums.
    let n = 30_000;
    let keys = Keys::Random.draw(n, 7);
    for (what, mut target) in sort_targets() {
        for bits in [30, 12, 1] {
            let mut sorter = Sorter::new(gpu(), &target, n as u64, bits, false).unwrap();
            sort_equals_cpu(
                &mut sorter,
                &keys,
                (n as u64, 0),
                n,
                bits,
                &format!("{what}: {bits} bits"),
            );
        }
        target.scan_items = 1;
        let mut sorter = Sorter::new(gpu(), &target, n as u64, 32, false).unwrap();
        sort_equals_cpu(
            &mut sorter,
            &keys,
            (n as u64, 0),
            n,
            32,
            &format!("{what}: tiles of 256"),
        );
    }
}

#[test]
fn a_counted_radix_sort_sorts_the_counted_elements_only() {
    let (len, over) = (30_000, 25_000u64);
    let keys = Keys::HighBits.draw(len, 11);
    for (what, target) in sort_targets() {
        let mut sorter = Sorter::new(gpu(), &target, len as u64, 32, true).unwrap();
        for count in [0, 1, 12_345, 25_000, 40_000] {
            let sorted = count.min(over) as usize;
            sort_equals_cpu(
                &mut sorter,
                &keys,
                (over, count as u32),
                sorted,
                32,
                &format!("{what}: {count} counted"),
            );
        }
    }
}

#[test]
fn a_radix_sort_of_keys_alone_sorts_them() {
    // Keys only (no values bound or moved), at lengths around a tile and with 1, 12 and 32
    // bits (an odd number of passes copies back); the keys are checked at every place.
    for (what, target) in sort_targets() {
        let tile = SortShape::of(&target).tile() as usize;
        for (n, bits) in [(tile + 1, 32), (3 * tile - 5, 12), (50_000, 1), (50_000, 32)] {
            let keys = Keys::Random.draw(n, n as u64 + 3);
            let mut sorter = Sorter::keys_only(gpu(), &target, n as u64, bits).unwrap();
            let out = sorter.sort(&keys, &[], n as u64, 0, 1).unwrap();
            assert!(out.values.is_none(), "{what}: a sort of keys read values back");
            let unused = vec![0; n];
            if let Some(m) = compare(&keys, &unused, n, bits, &out) {
                panic!("{what}: keys only, n {n}, {bits} bits: {m}");
            }
        }
    }
}

/// A graph of the operators `entries` over 100 `u32` keys and values, `f32` floats and 10^5
/// `u32` words.
fn sort_graph(entries: &str) -> String {
    format!(
        r#"(
    name: "sorting",
    passes: [{entries}],
    resources: {{
        "keys": (ty: "u32", count: "100"),
        "values": (ty: "u32", count: "100"),
        "floats": (ty: "f32", count: "100"),
        "words": (ty: "u32", count: "100000"),
    }},
    outputs: [],
    layouts: {{ "sort": (kernels: []) }},
    default_layout: "sort",
)"#
    )
}

/// The program of `sort_graph(entries)` for `target`.
fn compile_for(entries: &str, target: &Target) -> lightgraph_engine::Result<Program> {
    let graph = Graph::from_text(&Vfs::default(), "sorting.ron", &sort_graph(entries))?;
    lightgraph_engine::compile(&graph, "sort", graph.layout("sort")?, &Default::default(), target)
}

/// The program of `sort_graph(entries)` for a default target (no GPU needed).
fn compile(entries: &str) -> lightgraph_engine::Result<Program> {
    compile_for(entries, &Target::default())
}

#[test]
fn an_f32_scan_in_place_leaves_the_exclusive_sums() {
    // Weights i + 0.5: every partial sum is a multiple of 0.5 below 2^23, exact in f32 in any
    // order, and the sum before element i is i^2 / 2.
    let weights: Vec<f32> = (0..100).map(|i| i as f32 + 0.5).collect();
    let want: Vec<f32> = (0..100).map(|i| (i * i) as f32 / 2.0).collect();
    for (what, target) in targets() {
        let program = compile_for(r#"Scan(name: "cdf", input: "floats", over: "100")"#, &target).unwrap();
        let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
        instance.write("floats", bytemuck::cast_slice(&weights)).unwrap();
        instance.run_frame(0, 0).unwrap();
        let sums: Vec<f32> = bytemuck::pod_collect_to_vec(&instance.read("floats").unwrap());
        assert_eq!(sums, want, "{what}");
    }
}

/// An in-place scan run twice gives the sums of the sums; with the input restored from its
/// snapshot before the second run, it gives the first run's sums again.
#[test]
fn a_snapshot_puts_an_operators_input_back_on_the_gpu() {
    let weights: Vec<f32> = (0..100).map(|i| i as f32 + 0.5).collect();
    let program = compile_for(r#"Scan(name: "cdf", input: "floats", over: "100")"#, &gpu().target()).unwrap();
    let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    let read = |instance: &Instance| -> Vec<f32> { bytemuck::pod_collect_to_vec(&instance.read("floats").unwrap()) };
    instance.write("floats", bytemuck::cast_slice(&weights)).unwrap();
    instance.snapshot("floats").unwrap();
    instance.run_frame(0, 0).unwrap();
    let once = read(&instance);
    instance.run_frame(1, 0).unwrap();
    assert_ne!(read(&instance), once, "a second in-place scan changes the sums");
    instance.restore("floats").unwrap();
    instance.run_frame(2, 0).unwrap();
    assert_eq!(read(&instance), once);
    let program = compile_for(r#"Scan(name: "cdf", input: "floats", over: "100")"#, &gpu().target()).unwrap();
    let fresh = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    let err = fresh.restore("floats").unwrap_err().to_string();
    assert!(err.contains("'floats' has no snapshot"), "{err}");
}

#[test]
fn sort_errors_name_the_operator() {
    let cases = [
        (
            r#"Sort(name: "order", keys: "keys", values: "floats", over: "100")"#,
            "operator 'order' (radix sort) needs u32 elements in 'floats', which holds 'f32'",
        ),
        (
            r#"Sort(name: "order", keys: "keys", values: "keys", over: "100")"#,
            "operator 'order' sorts 'keys' with itself as its values",
        ),
        (
            r#"Sort(name: "order", keys: "keys", values: "values", over: "100", bits: 0)"#,
            "operator 'order': bits 0 is not in 1..=32",
        ),
        (
            r#"Sort(name: "order", keys: "keys", values: "values", over: "100", bits: 33)"#,
            "operator 'order': bits 33 is not in 1..=32",
        ),
        (
            r#"Sort(name: "order", keys: "keys", values: "values", over: "101")"#,
            "operator 'order' runs over 101 elements but 'keys' holds 100",
        ),
        (
            r#"Sort(name: "order", keys: "words", values: "values", over: "1000")"#,
            "operator 'order' runs over 1000 elements but 'values' holds 100",
        ),
    ];
    for (entry, want) in cases {
        let e = compile(entry)
            .err()
            .unwrap_or_else(|| panic!("{entry} is accepted"))
            .to_string();
        assert!(e.contains(want) && e.starts_with("sorting.ron:"), "{entry}: {e}");
    }
}

#[test]
fn sort_scratch_is_transient_memory_of_its_step() {
    // The sort's scratch (keys, values, histograms) lives in its step only, so the scan after
    // it reuses that memory for its partial sums.
    let program = compile(
        r#"Sort(name: "order", keys: "keys", values: "values", over: "100"), Scan(name: "sums", input: "words", over: "100000")"#,
    )
    .unwrap();
    let memory = &program.resolved.memory;
    let scratch = |o: usize, i: usize| BufferRef::Scratch(OpId(o), i);
    for i in 0..3 {
        let life = memory.lifetimes[&scratch(0, i)];
        assert_eq!((life.first, life.last), (0, 0), "sort scratch {i}");
    }
    let (sort_keys, partials) = (memory.placements[&scratch(0, 0)], memory.placements[&scratch(1, 0)]);
    assert!(sort_keys.arena.is_some() && sort_keys.arena == partials.arena);
    assert!(
        partials.offset < sort_keys.offset + sort_keys.bytes,
        "{sort_keys:?} {partials:?}"
    );
}
