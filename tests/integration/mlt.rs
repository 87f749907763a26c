//! Markov chain estimators (graphs/pssmlt.ron, mmlt.ron, mvcm.ron, appm.ron, docs/mlt.md) on
//! lavapipe: both layouts of each render the same image for a seed, every chain runs every step
//! of every frame, and the chains' proposals are accepted at a rate between the extremes;
//! adaptive photon tracing judges every uniform path once its marks are made and moves its
//! mutation size towards its target acceptance, and drops no photon for want of room under a
//! narrow spot. Agreement with the other estimators is
//! `verify`'s (tests/integration/verify.rs).

use crate::common::{Rendered, assert_same_render, data, render};
use lightgraph::run::load_scene;

/// The image size, samples per pixel and frames of the runs below: 1152 paths a frame, so
/// 144 bootstrap paths and chains (PATHS / 8) of 8 steps each.
const SIZE: (u32, u32) = (24, 24);
const SPP: u32 = 2;
const FRAMES: u32 = 3;

/// The Markov chain graphs with their two layouts.
const GRAPHS: [(&str, &str, &str); 3] = [
    ("pssmlt", "PSSMLTsk", "PSSMLTmk"),
    ("mmlt", "MMLTsk", "MMLTmk"),
    ("mvcm", "MVCMsk", "MVCMmk"),
];

#[test]
fn markov_chain_layouts_render_the_same_image() {
    for name in ["cornell-glossy-point", "cornell-mitsuba"] {
        let scene = load_scene(name).unwrap();
        for (graph, fused, split) in GRAPHS {
            let a = render(&scene, graph, fused, SIZE, SPP, FRAMES, 7, &[]);
            let b = render(&scene, graph, split, SIZE, SPP, FRAMES, 7, &[]);
            assert_same_render(&a, &b, &format!("{name}, {split} against {fused}"));
        }
    }
}

/// The counter `name` of `r`.
fn counter(r: &Rendered, name: &str) -> u64 {
    r.counters.get(name).copied().unwrap_or(0)
}

#[test]
fn every_chain_runs_every_step_and_some_are_accepted() {
    let scene = load_scene("cornell-glossy-point").unwrap();
    let paths = (SIZE.0 * SIZE.1 * SPP) as u64;
    let chains = paths.div_ceil(8);
    let steps = chains * paths.div_ceil(chains);
    for (graph, layout, _) in GRAPHS {
        let r = render(&scene, graph, layout, SIZE, SPP, FRAMES, 7, &[]);
        assert_eq!(
            counter(&r, "mlt_steps"),
            FRAMES as u64 * steps,
            "{graph}: {:?}",
            r.counters
        );
        // Large steps are drawn with probability 0.3: 3456 steps give 1037 +- 27 of them, so
        // the bounds below are 7 standard deviations off.
        let large = counter(&r, "mlt_large_steps") as f64 / counter(&r, "mlt_steps") as f64;
        assert!((0.245..0.355).contains(&large), "{graph}: large steps {large}");
        // A chain that accepted everything or nothing is broken.
        let accepted = counter(&r, "mlt_accepted") as f64 / counter(&r, "mlt_steps") as f64;
        eprintln!("{graph}: acceptance {accepted:.3}, large steps {large:.3}");
        assert!((0.05..0.95).contains(&accepted), "{graph}: acceptance {accepted}");
    }
    // PSSMLT traces one camera path (one primary ray) for each bootstrap path, each chain's
    // seed (once) and each step.
    let r = render(&scene, "pssmlt", "PSSMLTsk", SIZE, SPP, FRAMES, 7, &[]);
    assert_eq!(
        counter(&r, "rays_primary"),
        FRAMES as u64 * (chains + steps) + chains,
        "{:?}",
        r.counters
    );
}

/// Adaptive photon tracing on the diffuse box seen through 6 degrees (tests/data/scenes), where
/// most photon paths miss what the camera sees: from frame AMC_MARK_FRAMES (4) on, each frame
/// judges all its PM_LIGHT_PATHS uniform paths (one per camera sample), few are visible, and
/// the mutation size moves the chains' acceptance towards 0.234.
#[test]
fn adaptive_photon_tracing_judges_every_path_and_adapts_its_steps() {
    let scene = load_scene(data("scenes/cornell-closeup.ron").to_str().unwrap()).unwrap();
    let frames = 48;
    let r = render(&scene, "appm", "APPMsk", SIZE, SPP, frames, 7, &[]);
    let paths = (SIZE.0 * SIZE.1 * SPP) as u64;
    assert_eq!(
        counter(&r, "amc_uniform"),
        (frames as u64 - 4) * paths,
        "{:?}",
        r.counters
    );
    let visible = counter(&r, "amc_visible") as f64 / counter(&r, "amc_uniform") as f64;
    let mutations = counter(&r, "amc_mutations");
    let accepted = counter(&r, "amc_accepted") as f64 / mutations as f64;
    eprintln!("appm: visible {visible:.3}, acceptance {accepted:.3} of {mutations} mutations");
    // Measured 0.04-0.05 visible; a box seen whole has about half its paths visible at this
    // size (the marks of 4 frames of 1152 samples cover part of the cells).
    assert!((0.005..0.2).contains(&visible), "visible fraction {visible}");
    // Uniform paths that miss make the chains mutate: most of the 44 frames' paths.
    assert!(mutations > paths * 30, "{mutations} mutations");
    // Started at d = 0.5, the size adapts by (rate - 0.234) / t a frame: measured 0.195 over
    // this run (0.23 over 256 frames at 32 x 32); a size that did not move (or moved the wrong
    // way) accepts 0.5 and more.
    assert!((0.15..0.32).contains(&accepted), "acceptance {accepted}");
}

/// Adaptive photon tracing under a narrow spot (bench/peers/fidelity/scenes/spot-falloff.xml,
/// a cone of 30 degrees: about 93% of the uniform photon paths leave the light outside it and
/// store no photon): the chains' states are visible paths, with many more photons than the
/// uniform paths' average, and the photon buffer must hold them all. Sized by that average
/// alone (2.2 times it, before), frames dropped photons: `pm_overflow` 284 in this run (113 of
/// some 560 photons a frame at 32 x 32, one sample per pixel), the image 28-34% dark
/// (verify.rs, `adaptive_photon_tracing_agrees_with_path_tracing_under_a_narrow_spot`).
#[test]
fn adaptive_photon_tracing_drops_no_photon_under_a_narrow_spot() {
    let spot = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/bench/peers/fidelity/scenes/spot-falloff.xml"
    );
    let scene = load_scene(spot).unwrap();
    let frames = 16;
    let r = render(&scene, "appm", "APPMsk", SIZE, SPP, frames, 7, &[]);
    eprintln!("appm under a narrow spot: {:?}", r.counters);
    // The chains run (their states deposited from frame 5 on) and take many states.
    assert!(counter(&r, "amc_accepted") > 0, "{:?}", r.counters);
    assert_eq!(counter(&r, "pm_overflow"), 0, "{:?}", r.counters);
}
