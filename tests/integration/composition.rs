//! A second estimator made of RON and WGSL alone (graphs/ao.ron, shaders/ao/): ambient
//! occlusion. It is found by name like the built-in path tracer and runs in both of its
//! layouts. Exact cases: a convex sphere occludes nothing (AO = 1 on it, 0 where camera rays
//! escape), and the inside of a closed box occludes everything at unbounded distance.

use crate::common::{data, render};
use lightgraph::run::load_scene;
use lightgraph_engine::ConstValue;

#[test]
fn ambient_occlusion_graph_renders_exact_cases() {
    let sphere = load_scene(data("scenes/diffuse-sphere-background.ron").to_str().unwrap()).unwrap();
    let (w, h) = (32, 32);
    for layout in ["AOsk", "AOmk"] {
        let r = render(&sphere, "ao", layout, (w, h), 2, 2, 5, &[]);
        assert_eq!(r.counters["rays_primary"], (w * h * 4) as u64);
        let (mut ones, mut zeros) = (0, 0);
        for p in &r.image.mean {
            // Each pixel holds the mean of 0/1 samples; on the sphere every sample is 1, off
            // it every sample is 0, so only silhouette pixels may lie in between.
            if p[0] == 1.0 {
                ones += 1;
            } else if p[0] == 0.0 {
                zeros += 1;
            }
            assert!(
                (0.0..=1.0).contains(&p[0]) && p[0] == p[1] && p[1] == p[2],
                "{layout}: AO pixel {p:?}"
            );
        }
        assert!(
            ones > 150 && zeros > 300 && ones + zeros > (w * h) as usize * 9 / 10,
            "{layout}: {ones} ones, {zeros} zeros"
        );
    }
    let inside = load_scene(data("scenes/emissive-box-0.5.ron").to_str().unwrap()).unwrap();
    let r = render(&inside, "ao", "AOmk", (16, 16), 1, 2, 5, &[]);
    assert!(
        r.image.mean.iter().all(|p| p[0] == 0.0),
        "inside a closed box everything is occluded"
    );
    assert_eq!(r.counters["rays_occlusion"], 16 * 16 * 2);
    let r = render(
        &inside,
        "ao",
        "AOsk",
        (16, 16),
        1,
        2,
        5,
        &[("AO_DISTANCE", ConstValue::F32(1e-4))],
    );
    let open = r.image.mean.iter().filter(|p| p[0] == 1.0).count();
    assert!(
        open > 200,
        "with a tiny AO distance almost nothing is occluded ({open} of 256 pixels)"
    );
}
