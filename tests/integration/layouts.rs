//! Every layout of one estimator with one seed renders the same image, to float rounding:
//! the layouts run the same pass functions on the same random streams, and only the order of
//! the film's atomic additions differs.

use crate::common::render;
use lightgraph::render::load_scene;

#[test]
fn naive_pt_single_and_multi_kernel_agree() {
    for name in ["cornell-glossy-point", "cornell-glossy-background", "cornell-mitsuba"] {
        let scene = load_scene(name).unwrap();
        let a = render(&scene, "pt", "NaivePTsk", (48, 48), 2, 3, 42, &[]);
        let b = render(&scene, "pt", "NaivePTmk", (48, 48), 2, 3, 42, &[]);
        assert_eq!(a.counters, b.counters, "{name}: both layouts trace the same rays");
        let mut worst = 0f64;
        for (p, q) in a.image.mean.iter().zip(&b.image.mean) {
            for c in 0..3 {
                let (x, y) = (p[c] as f64, q[c] as f64);
                // Sums of a few dozen f32 terms in another order: a few ulps of the magnitude.
                worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
            }
        }
        eprintln!("{name}: largest relative difference {worst:.2e}");
        assert!(
            worst < 1e-5,
            "{name}: the layouts differ by {worst:.2e}, more than float rounding"
        );
    }
}
