//! Every layout of one estimator with one seed renders the same image, to float rounding:
//! the layouts run the same pass functions on the same random streams, and only the order of
//! the film's atomic additions differs. They also trace exactly the same rays.

use crate::common::render;
use lightgraph::render::{load_graph, load_scene};

#[test]
fn every_pt_layout_matches_naive_pt_sk() {
    let graph = load_graph("pt").unwrap();
    let layouts: Vec<&String> = graph.layouts.keys().filter(|l| *l != "NaivePTsk").collect();
    assert!(
        layouts.len() >= 9,
        "the paper's layouts are in graphs/pt.ron: {layouts:?}"
    );
    for name in ["cornell-glossy-point", "cornell-glossy-background", "cornell-mitsuba"] {
        let scene = load_scene(name).unwrap();
        let reference = render(&scene, "pt", "NaivePTsk", (24, 24), 2, 2, 42, &[]);
        for layout in &layouts {
            let other = render(&scene, "pt", layout, (24, 24), 2, 2, 42, &[]);
            assert_eq!(
                reference.counters, other.counters,
                "{name}, {layout}: the layouts trace different rays"
            );
            let mut worst = 0f64;
            for (p, q) in reference.image.mean.iter().zip(&other.image.mean) {
                for c in 0..3 {
                    let (x, y) = (p[c] as f64, q[c] as f64);
                    // Sums of a few dozen f32 terms in another order: a few ulps of the magnitude.
                    worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
                }
            }
            eprintln!("{name}, {layout}: largest relative difference {worst:.2e}");
            assert!(
                worst < 1e-5,
                "{name}, {layout}: differs from NaivePTsk by {worst:.2e}, more than float rounding"
            );
        }
    }
}
