//! The collective operators against the CPU: an exclusive scan and a counting sort (clear,
//! count, scan of the counts, scatter) at the lengths around every boundary of the kernels
//! (0, 1, 2, a subgroup of 32 and a workgroup of 256 plus or minus one, a scan tile plus or
//! minus one, and 2^20 + 7), with random inputs, all-equal ones (one bucket holding every
//! element) and concentrated ones, with and without subgroup operations, and with small tiles
//! so that the scan goes through two and three levels of partial sums.

use lightgraph_engine::selfcheck::{Pattern, check, run};
use lightgraph_engine::{Gpu, Target};
use std::sync::OnceLock;

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new(None).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"))
}

/// The adapter's target, and the same without subgroup operations when it has them.
fn targets() -> Vec<(&'static str, Target)> {
    let with = gpu().target();
    let mut out = vec![("adapter", with.clone())];
    if with.subgroups() {
        out.push(("no subgroups", with.without_subgroups()));
    }
    out
}

fn check_all(target: &Target, what: &str, lengths: &[u64]) {
    for &n in lengths {
        for buckets in [n.max(1), 7] {
            for pattern in Pattern::ALL {
                let r = check(gpu(), target, n, buckets, pattern, 1).unwrap();
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
fn a_key_beyond_the_buckets_is_an_error_not_a_lost_element() {
    let values = vec![1u32; 40];
    let mut keys: Vec<u32> = (0..40).map(|i| i % 7).collect();
    keys[13] = 7;
    let err = run(gpu(), &gpu().target(), &values, &keys, 7, 1)
        .err()
        .expect("the frame fails");
    let msg = err.to_string();
    assert!(
        msg.contains("operator 'count'") && msg.contains("skipped 1 elements with a key beyond its counts"),
        "{msg}"
    );
}
