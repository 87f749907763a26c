//! The render driver (lightgraph::drive) changes no image: a driven run (batches of the
//! driver's choosing, frames in flight while the host records the next) holds the same frames
//! as the frames rendered one group at a time, and the GPUs' executor (two devices of one
//! adapter sharing the budget) holds them too.

use crate::common::gpu;
use lightgraph::drive::{Budget, Plan, Stopwatch, drive};
use lightgraph::film::Film;
use lightgraph::multi::render_on_gpus;
use lightgraph::run::{Run, RunOptions};

/// A run of LVC-BPT (light sub-paths shared by the frame's pixels, measured constants) on a
/// small box.
fn run() -> Run {
    let options = RunOptions {
        scene: Some("cornell-glossy-point".into()),
        res: Some((16, 12)),
        spp: Some(2),
        ..Default::default()
    };
    let mut run = Run::load(&options.spec("bpt-lvc", None, 7)).unwrap();
    run.measure(gpu()).unwrap();
    run
}

const FRAMES: u32 = 9;

#[test]
fn a_driven_run_holds_the_frames_rendered_one_group_at_a_time() {
    let run = run();
    let mut driven = run.session(gpu()).unwrap();
    let plan = Plan::new(Budget::Frames(FRAMES as u64));
    drive(&mut driven, plan, &mut Stopwatch::start(), &mut []).unwrap();
    let mut stepped = run.session(gpu()).unwrap();
    while stepped.frames < FRAMES {
        stepped.render_frame().unwrap();
    }
    let (a, b) = (driven.image().unwrap(), stepped.image().unwrap());
    assert_eq!((a.frames, b.frames), (FRAMES, FRAMES));
    assert!(a.mean.iter().flatten().any(|&v| v > 0.0), "the render is black");
    // The same frames; light sub-paths splat into the film with atomic adds, whose order
    // varies from dispatch to dispatch: equal to float rounding.
    assert_close(&a.mean, &b.mean, "driven", "rendered one group at a time");

    // The GPUs' executor: two devices of the one adapter claim the frames between them; the
    // film's f64 sums of their f32 batches equal the one session's to float rounding.
    let mut film = Film::new((16, 12), Default::default());
    render_on_gpus(
        &run,
        &["0".into(), "0".into()],
        Budget::Frames(FRAMES as u64),
        &mut film,
        |_, _| {},
    )
    .unwrap();
    assert_eq!(film.frames, FRAMES as u64);
    assert_close(&film.mean(), &b.mean, "on two devices", "on one");
}

/// Asserts two images equal to float rounding (a relative 1e-5: a few f32 ulps).
fn assert_close(a: &[[f32; 3]], b: &[[f32; 3]], what_a: &str, what_b: &str) {
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            assert!(
                (x[c] - y[c]).abs() <= 1e-5 * y[c].abs().max(1e-3),
                "pixel {i}: {x:?} {what_a}, {y:?} {what_b}"
            );
        }
    }
}
