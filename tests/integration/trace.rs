//! The trace-only benchmark's graph (graphs/trace.ron): rays made in the first frame and cast
//! in every one. Exact cases on a lone sphere (camera rays hit it or leave; its AO rays are
//! never occluded, its diffuse rays never hit, both only from hits), the rays kept across
//! frames (three frames give one frame's image), and the two BVHs find the same hits.

use crate::common::{data, render};
use lightgraph::run::load_scene_with;
use lightgraph_scenes::bvh::BvhKind;

#[test]
fn trace_graph_casts_kept_rays_with_exact_results() {
    let path = data("scenes/diffuse-sphere-background.ron");
    let sphere = load_scene_with(path.to_str().unwrap(), BvhKind::Cwbvh).unwrap();
    let (w, h) = (32, 32);
    let one = render(&sphere, "trace", "Trace", (w, h), 1, 1, 5, &[]);
    let three = render(&sphere, "trace", "Trace", (w, h), 1, 3, 5, &[]);
    let paths = (w * h) as u64;
    assert_eq!(three.counters["rays_primary"], 3 * paths);
    let hits = three.counters["rays_occlusion"];
    assert_eq!(three.counters["rays_diffuse"], hits);
    assert!(
        hits > 3 * paths / 8 && hits < 3 * paths,
        "{hits} camera rays of {} hit the sphere",
        3 * paths
    );
    let mut on = 0;
    for (a, b) in one.image.mean.iter().zip(&three.image.mean) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-6, "frames 1 and 3 differ: {a:?} {b:?}");
        }
        // Red: the camera ray's nearness in (0, 1] on the sphere, 0 off it; green: an open AO
        // ray, exactly where the camera ray hit; blue: a diffuse ray that hit, never.
        let hit = a[0] > 0.0;
        assert!(
            a[0] <= 1.0 && a[1] == if hit { 1.0 } else { 0.0 } && a[2] == 0.0,
            "pixel {a:?}"
        );
        on += hit as u64;
    }
    assert_eq!(on * 3, hits, "pixels on the sphere and rays that hit it (3 frames)");
}

#[test]
fn both_bvhs_find_the_same_hits() {
    let images: Vec<_> = [BvhKind::Bvh2, BvhKind::Cwbvh]
        .into_iter()
        .map(|kind| {
            let scene = load_scene_with("cornell-glossy-point", kind).unwrap();
            render(&scene, "trace", "Trace", (48, 36), 2, 1, 9, &[]).image.mean
        })
        .collect();
    let differing = images[0]
        .iter()
        .zip(&images[1])
        .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-5 * a[c].abs().max(1e-3)))
        .count();
    assert_eq!(
        differing,
        0,
        "{differing} of {} pixels differ between the BVHs",
        images[0].len()
    );
}

/// TRACE_STATS counts what the traversal does without changing what it finds: on a lone
/// sphere (one primitive, a CWBVH of its root alone) every ray visits exactly one node, and
/// every camera ray that hits the sphere tested it.
#[test]
fn trace_stats_count_nodes_and_tests_and_change_no_result() {
    use lightgraph_engine::ConstValue;
    let path = data("scenes/diffuse-sphere-background.ron");
    let sphere = load_scene_with(path.to_str().unwrap(), BvhKind::Cwbvh).unwrap();
    let plain = render(&sphere, "trace", "Trace", (32, 32), 1, 1, 5, &[]);
    let stats = [("TRACE_STATS", ConstValue::Bool(true))];
    let counted = render(&sphere, "trace", "Trace", (32, 32), 1, 1, 5, &stats);
    assert_eq!(plain.image.mean, counted.image.mean, "counting changed the image");
    assert_eq!(plain.counters["nodes_primary"], 0, "no counting without TRACE_STATS");
    let c = &counted.counters;
    assert_eq!(c["nodes_primary"], c["rays_primary"]);
    assert_eq!(c["nodes_ao"], c["rays_occlusion"]);
    assert_eq!(c["nodes_diffuse"], c["rays_diffuse"]);
    assert!(
        c["tests_primary"] >= c["rays_occlusion"],
        "{c:?}: a camera ray that hit tested the sphere"
    );
}

/// TRACE_SORT casts the diffuse rays in the order of their keys (direction first, or origin
/// first) without changing which ray finds what: the same image, pixel for pixel, over two
/// frames (the second casts in the order the first frame's sort left).
#[test]
fn sorted_diffuse_rays_find_the_same_hits() {
    use lightgraph_engine::ConstValue;
    let scene = load_scene_with("cornell-glossy-point", BvhKind::Cwbvh).unwrap();
    let plain = render(&scene, "trace", "Trace", (48, 36), 1, 2, 9, &[]);
    assert!(plain.counters["rays_diffuse"] > 0);
    for origin_first in [false, true] {
        let set = [
            ("TRACE_SORT", ConstValue::Bool(true)),
            ("TRACE_SORT_ORIGIN_FIRST", ConstValue::Bool(origin_first)),
        ];
        let sorted = render(&scene, "trace", "Trace", (48, 36), 1, 2, 9, &set);
        assert_eq!(plain.counters["rays_diffuse"], sorted.counters["rays_diffuse"]);
        assert_eq!(
            plain.image.mean, sorted.image.mean,
            "sorting (origin first: {origin_first}) changed the image"
        );
    }
}
