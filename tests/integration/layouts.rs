//! Every layout of one estimator with one seed renders the same image, to float rounding:
//! the layouts run the same pass functions on the same random streams, and only the order of
//! the film's atomic additions differs. They also trace exactly the same rays.

use crate::common::{
    assert_same_render, borrowed, gpu, largest_relative_difference, measured, render, render_with_layout,
};
use lightgraph::run::{Image, LayoutOverrides, LoadedScene, Session, SessionOptions, load_graph, load_scene};
use lightgraph::tuning::Tuning;
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Graph};

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
            assert_same_render(&reference, &other, &format!("{name}, {layout} against NaivePTsk"));
        }
    }
    // With every feature compiled in (textures among them), `material` takes the vertex that
    // `logic` set up where the two are fused (`PathVertex`) and sets it up itself elsewhere.
    let scene = load_scene("cornell-glossy-point").unwrap();
    let all = || LayoutOverrides {
        all_features: true,
        ..Default::default()
    };
    let reference = render_with_layout(&scene, "pt", "NaivePTsk", (24, 24), 2, 2, 42, &[], all());
    let plain = render(&scene, "pt", "NaivePTsk", (24, 24), 2, 2, 42, &[]);
    assert_same_render(&plain, &reference, "NaivePTsk with every feature against the scene's");
    for layout in &layouts {
        let other = render_with_layout(&scene, "pt", layout, (24, 24), 2, 2, 42, &[], all());
        assert_same_render(
            &reference,
            &other,
            &format!("every feature, {layout} against NaivePTsk"),
        );
    }
}

/// The H100's tuning profile (data/tuning/nvidia-h100.ron), which the default profile of every
/// other adapter takes too.
fn h100() -> LayoutOverrides {
    LayoutOverrides {
        tuning: Tuning::parse("nvidia-h100", load_graph).unwrap(),
        ..Default::default()
    }
}

/// The layout `layout` of `graph` with the H100 profile's knobs.
fn tuned(graph: &str, layout: &str) -> LayoutDecl {
    let g = load_graph(graph).unwrap();
    h100().tuning.apply(None, &g, layout, g.layouts[layout].clone())
}

/// Layouts whose tuning profile leaves wgpu's loop guards out (`loop_guards: false`) render
/// the image they render with the guards and with no profile at all, to float rounding: the
/// guards only end loops after 2^64 iterations.
#[test]
fn layouts_without_loop_guards_render_what_they_render_with_them() {
    let scene = load_scene("cornell-glossy-sun").unwrap();
    for (graph, layout) in [
        ("pt", "StreamingPTmk2"),
        ("lt", "LTsk"),
        ("ppm", "PPMsk"),
        ("vcm", "VCMmk"),
    ] {
        assert!(
            !tuned(graph, layout).loop_guards,
            "{layout} leaves the loop guards out (data/tuning/nvidia-h100.ron)"
        );
        assert!(
            load_graph(graph).unwrap().layouts[layout].loop_guards,
            "graphs/{graph}.ron keeps no device knob"
        );
        let guarded = LayoutOverrides {
            loop_guards: Some(true),
            ..h100()
        };
        assert!(
            guarded.apply(tuned(graph, layout)).loop_guards,
            "--loop-guards on overrides the profile"
        );
        let with = render_with_layout(&scene, graph, layout, (24, 24), 2, 2, 42, &[], guarded);
        let without = render_with_layout(&scene, graph, layout, (24, 24), 2, 2, 42, &[], h100());
        let untuned = LayoutOverrides {
            tuning: Tuning::None,
            ..Default::default()
        };
        let plain = render_with_layout(&scene, graph, layout, (24, 24), 2, 2, 42, &[], untuned);
        assert_same_render(
            &with,
            &without,
            &format!("{graph} {layout} with and without loop guards"),
        );
        assert_same_render(
            &plain,
            &without,
            &format!("{graph} {layout} with and without the tuning profile"),
        );
    }
}

/// Layouts that visit the CWBVH's children by bit scan (`CWBVH_CHILD_SCAN`, set by their
/// tuning profile) render the image they render with the loop of eight slots: both test the
/// same children against the same ray, so the images agree to float rounding.
#[test]
fn layouts_with_the_child_scan_render_what_the_loop_of_eight_renders() {
    use lightgraph_scenes::bvh::BvhKind;
    let scene = lightgraph::run::load_scene_with("cornell-glossy-sun", BvhKind::Cwbvh).unwrap();
    let eight = [("CWBVH_CHILD_SCAN", ConstValue::Bool(false))];
    for (graph, layout) in [
        ("pt", "NaivePTsk"),
        ("bpt-naive", "NaiveBPT"),
        ("bpt-lvc", "LVC-BPTsk"),
        ("vcm", "VCMsk"),
    ] {
        assert_eq!(
            tuned(graph, layout).constants.get("CWBVH_CHILD_SCAN"),
            Some(&ConstValue::Bool(true)),
            "{layout} visits the children by bit scan (data/tuning/nvidia-h100.ron)"
        );
        let scan = render_with_layout(&scene, graph, layout, (24, 24), 2, 2, 42, &[], h100());
        let unrolled = render_with_layout(&scene, graph, layout, (24, 24), 2, 2, 42, &eight, h100());
        assert_same_render(&scan, &unrolled, &format!("{graph} {layout} with either child loop"));
    }
}

/// PT's pixels in 8x8 tiles (`TILED_PIXELS`), at a size whose last tiles are partial: every
/// layout still renders NaivePTsk's image for one seed, every pixel gets its paths, and the
/// image's mean agrees with the rows' within 4 standard errors
/// (the per-pixel variances over 4 frames give the error of each mean).
#[test]
fn pt_in_tiled_pixel_order_matches_its_layouts_and_the_row_order() {
    use lightgraph_engine::ConstValue;
    let scene = load_scene("cornell-mitsuba").unwrap();
    let tiled = [("TILED_PIXELS", ConstValue::Bool(true))];
    let size = (20, 20);
    let reference = render(&scene, "pt", "NaivePTsk", size, 4, 4, 42, &tiled);
    for layout in ["RegenerationPTmk1", "StreamingPTmk2", "WavefrontPT"] {
        let other = render(&scene, "pt", layout, size, 4, 4, 42, &tiled);
        assert_same_render(&reference, &other, &format!("{layout} against NaivePTsk in tiles"));
    }
    let image = &reference.image;
    let rows = [("TILED_PIXELS", ConstValue::Bool(false))];
    let rows = render(&scene, "pt", "NaivePTsk", size, 4, 4, 43, &rows).image;
    // The box fills the frame: a pixel whose 16 paths all miss the light is rare (rows with
    // seed 43 have 1 of 400, in the shadow under the box); a tile order that skipped pixels
    // would leave whole runs of them black.
    let black = |im: &lightgraph::run::Image| im.mean.iter().filter(|m| m.iter().all(|&v| v <= 0.0)).count();
    assert!(
        black(image) <= 4,
        "{} pixels left black in tile order ({} in rows)",
        black(image),
        black(&rows)
    );
    let stat = |im: &lightgraph::run::Image| {
        let n = im.mean.len() as f64;
        let mean = im.mean.iter().map(|m| m[1] as f64).sum::<f64>() / n;
        let var = im.variance.iter().map(|v| v[1] as f64).sum::<f64>() / (n * n * im.frames as f64);
        (mean, var)
    };
    let ((ma, va), (mb, vb)) = (stat(image), stat(&rows));
    let z = (ma - mb) / (va + vb).sqrt();
    assert!(z.abs() < 4.0, "tiles {ma:.5} against rows {mb:.5}: z {z:.2}");
}

#[test]
fn auto_enumeration_finds_every_named_layout() {
    use lightgraph_engine::Plan;
    use lightgraph_engine::auto::{legal_layouts, signature};
    let graph = load_graph("pt").unwrap();
    let found: Vec<String> = legal_layouts(&graph, &Default::default())
        .iter()
        .map(|(name, decl)| signature(&Plan::with_decl(&graph, name, decl.clone()).unwrap()))
        .collect();
    for (name, decl) in &graph.layouts {
        let named = signature(&Plan::with_decl(&graph, name, decl.clone()).unwrap());
        assert!(found.contains(&named), "--layout auto misses the named layout {name}");
    }
    eprintln!("{} distinct legal layouts of pt", found.len());
    assert!(found.len() > graph.layouts.len());
}

#[test]
fn pooled_layouts_regenerate_across_many_iterations() {
    // A pool far smaller than the frame: every thread must take many paths in turn.
    let scene = load_scene("cornell-glossy-point").unwrap();
    let reference = render(&scene, "pt", "NaivePTsk", (24, 24), 2, 1, 5, &[]);
    for layout in [
        "RegenerationPTsk",
        "RegenerationPTmk1",
        "RegenerationPTmk3",
        "StreamingPTmk1",
        "StreamingPTmk3",
        "WavefrontPT",
    ] {
        let other = crate::common::render_with(&scene, "pt", layout, (24, 24), 2, 1, 5, Some(97));
        assert_eq!(reference.counters, other.counters, "{layout} with a pool of 97 threads");
        let worst = largest_relative_difference(&reference.image, &other.image);
        assert!(
            worst < 1e-5,
            "{layout} with a pool of 97 threads differs by {worst:.2e}"
        );
    }
}

#[test]
fn auto_layout_prepares_layouts_on_other_threads_and_measures_each_once() {
    // The GPU path of the tuner (threads compiling the next layouts while one is measured),
    // forced on lavapipe: every legal layout is screened exactly once, every trial is reported
    // once and succeeds, whatever order the threads finish in.
    let run = lightgraph::run::Run::load(&lightgraph::run::RunSpec {
        scene: "cornell-diffuse".into(),
        graph: "ao".into(),
        res: Some((16, 16)),
        ..Default::default()
    })
    .unwrap();
    let tuning = lightgraph::tune::Tuning {
        budget: std::time::Duration::from_millis(10),
        preparers: 3,
    };
    let mut seen = Vec::new();
    let trials =
        lightgraph::tune::autotune_with(crate::common::gpu(), &run, tuning, |t| seen.push(t.name.clone())).unwrap();
    let table = lightgraph::tune::table(&trials);
    assert!(trials.iter().all(|t| t.result.is_ok()), "{table}");
    let mut names: Vec<&String> = trials.iter().map(|t| &t.name).collect();
    assert_eq!(seen.len(), names.len(), "{table}");
    names.sort();
    names.dedup();
    assert_eq!(names.len(), trials.len(), "a layout measured twice: {table}");
    let base = run.graph.layouts[&run.graph.default_layout].clone();
    let legal = lightgraph_engine::auto::legal_layouts(
        &run.graph,
        &lightgraph_engine::ir::LayoutDecl {
            kernels: Vec::new(),
            ..base
        },
    );
    for (name, _) in &legal {
        assert!(
            trials.iter().any(|t| t.name.starts_with(&format!("{name} ("))),
            "{name} not screened: {table}"
        );
    }
    assert!(trials.len() > legal.len(), "no refinement: {table}");
}

#[test]
fn auto_layout_tunes_the_ambient_occlusion_graph() {
    let run = lightgraph::run::Run::load(&lightgraph::run::RunSpec {
        scene: "cornell-diffuse".into(),
        graph: "ao".into(),
        res: Some((16, 16)),
        bvh: lightgraph::run::BvhChoice(Some(lightgraph_scenes::bvh::BvhKind::Bvh2)),
        ..Default::default()
    })
    .unwrap();
    let mut seen = 0;
    let budget = std::time::Duration::from_millis(20);
    let trials = lightgraph::tune::autotune(crate::common::gpu(), &run, budget, |_| seen += 1).unwrap();
    assert_eq!(seen, trials.len());
    assert!(
        trials.iter().all(|t| t.result.is_ok()),
        "{}",
        lightgraph::tune::table(&trials)
    );
    assert!(trials.windows(2).all(|w| w[0].score() >= w[1].score()), "fastest first");
    let table = lightgraph::tune::table(&trials);
    assert!(
        table.contains("ao_primary+ao_occlusion") && table.contains("[ao_primary] [ao_occlusion]"),
        "{table}"
    );
    // The AO layouts keep the loop guards; the fastest is tried once more without them.
    assert_eq!(trials.iter().filter(|t| !t.decl.loop_guards).count(), 1, "{table}");
    assert!(table.contains("loop guards off"), "{table}");
}

#[test]
fn frames_recorded_in_one_batch_match_frames_run_one_by_one() {
    // 40 frames of StreamingPTmk3 record over 2000 dispatches, so the batch is submitted in
    // parts while it is recorded (every 512 dispatches) and its loops run their bound.
    const FRAMES: u32 = 40;
    let scene = load_scene("cornell-glossy-point").unwrap();
    let graph = load_graph("pt").unwrap();
    for layout in ["NaivePTsk", "StreamingPTmk3"] {
        let options = SessionOptions {
            width: 16,
            height: 16,
            samples_per_frame: 1,
            seed: 9,
            constants: Default::default(),
            layout: Default::default(),
        };
        let mut one = Session::new(crate::common::gpu(), &graph, layout, &scene, options.clone()).unwrap();
        for _ in 0..FRAMES {
            one.render_frame().unwrap();
        }
        let mut batch = Session::new(crate::common::gpu(), &graph, layout, &scene, options.clone()).unwrap();
        let stats = batch.render_frames(FRAMES).unwrap();
        assert_eq!(one.counters, batch.counters, "{layout}");
        assert_eq!(
            stats.counters["rays_primary"],
            FRAMES as u64 * 256,
            "{layout}: the batch's counters"
        );
        let (a, b) = (one.image().unwrap(), batch.image().unwrap());
        assert_eq!(a.frames, FRAMES);
        let worst = largest_relative_difference(&a, &b);
        assert!(worst < 1e-5, "{layout}: batched frames differ by {worst:.2e}");
        // Batches rendered while the one before is still running (`render_for`), their
        // statistics read back behind: the same counters and image once settled.
        let mut ahead = Session::new(crate::common::gpu(), &graph, layout, &scene, options).unwrap();
        let mut overlapped = false;
        while ahead.frames < FRAMES {
            ahead.render_for(None, FRAMES - ahead.frames).unwrap();
            overlapped |= ahead.settled < ahead.frames;
        }
        ahead.settle().unwrap();
        assert!(overlapped, "{layout}: no batch was submitted while another ran");
        assert_eq!(
            one.counters, ahead.counters,
            "{layout}: statistics of overlapped batches"
        );
        let worst = largest_relative_difference(&a, &ahead.image().unwrap());
        assert!(worst < 1e-5, "{layout}: overlapped batches differ by {worst:.2e}");
    }
}

/// Frames rendered at once (`FRAMES_AT_ONCE`, each frame's paths in its own film slot, drawing
/// that frame's random numbers) give every PT layout, NaiveBPT and StreamingBPT the image, the
/// per-frame variance and the counters of the same frames rendered one by one, to float
/// rounding (the variance, a difference of sums, to 1e-4: seen 1.6e-5); runs that would split a
/// group and graphs that render one frame at a time are refused. In sunlight: BPT's light
/// sub-paths start at points of the sun's disc stratified per frame (a point light has none).
#[test]
fn frames_rendered_at_once_match_frames_rendered_one_by_one() {
    let scene = load_scene("cornell-glossy-sun").unwrap();
    for graph in ["pt", "bpt-naive", "bpt-streaming"] {
        let graph = load_graph(graph).unwrap();
        let first = graph.layouts.keys().next().unwrap();
        let single = frames_at_once(&scene, &graph, first, 1);
        for layout in graph.layouts.keys() {
            let (mut grouped, four) = frames_at_once(&scene, &graph, layout, 4);
            let what = format!("{} {layout}", graph.name);
            assert_eq!(single.0.counters, grouped.counters, "{what}: different rays");
            assert_eq!(four.frames, AT_ONCE_FRAMES, "{what}");
            let worst = largest_relative_difference(&single.1, &four);
            let variance = |i: &Image| Image {
                mean: i.variance.clone(),
                ..i.clone()
            };
            let worst_variance = largest_relative_difference(&variance(&single.1), &variance(&four));
            eprintln!("{what}: largest relative difference {worst:.2e}, of the variance {worst_variance:.2e}");
            assert!(worst < 1e-5, "{what}: frames at once differ by {worst:.2e}");
            assert!(
                worst_variance < 1e-4,
                "{what}: their variance differs by {worst_variance:.2e}"
            );
            let split = grouped.render_frames(3).unwrap_err().to_string();
            assert!(split.contains("FRAMES_AT_ONCE = 4"), "{what}: {split}");
        }
    }
    let lvc = load_graph("bpt-lvc").unwrap();
    let options = at_once_options(2);
    let refused = Session::new(crate::common::gpu(), &lvc, "LVC-BPTsk", &scene, options)
        .err()
        .expect("bpt-lvc took frame slots");
    assert!(
        format!("{refused:#}").contains("renders one frame at a time"),
        "{refused:#}"
    );
}

/// Frames of [`frames_rendered_at_once_match_frames_rendered_one_by_one`].
const AT_ONCE_FRAMES: u32 = 8;

/// 16 x 16 pixels, 2 samples per pixel a frame, `n` frames at once.
fn at_once_options(n: u32) -> SessionOptions {
    SessionOptions {
        width: 16,
        height: 16,
        samples_per_frame: 2,
        seed: 10,
        constants: [("FRAMES_AT_ONCE".to_string(), ConstValue::U32(n))].into(),
        layout: Default::default(),
    }
}

/// [`AT_ONCE_FRAMES`] frames of `graph` in `layout`, `n` at once: the session and its image.
fn frames_at_once(scene: &LoadedScene, graph: &Graph, layout: &str, n: u32) -> (Session<'static>, Image) {
    let mut session = Session::new(crate::common::gpu(), graph, layout, scene, at_once_options(n)).unwrap();
    assert_eq!(session.frames_at_once(), n);
    while session.frames < AT_ONCE_FRAMES {
        session.render_for(None, AT_ONCE_FRAMES - session.frames).unwrap();
    }
    session.settle().unwrap();
    let image = session.image().unwrap();
    (session, image)
}

/// The persistent-thread layouts (an idle thread takes the next item from a global counter)
/// against layouts without, at sizes where every thread takes many items: the same rays and
/// the same image, 512×512 on a GPU, 128×128 (16,384 paths) on lavapipe. There, before
/// persistent threads took fair shares, a few items were lost from a few thousand on (at
/// 64×64, LVC-BPTsk traced 4091 or 4092 of 4096 camera paths; more under CPU load): a
/// persistent thread runs the loops of all the items it takes in one invocation, and llvmpipe
/// ends an invocation's loops after 65,535 iterations in all (docs/performance.md,
/// "Persistent threads on lavapipe"). Ignored by the plain test run (2 minutes on a loaded
/// 2-core CI machine): `cargo xtask test` runs it afterwards with a busy thread on every core.
#[test]
#[ignore]
fn persistent_thread_layouts_match_at_gpu_sizes() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let size = if gpu().caps_invocation_loops() {
        (128, 128)
    } else {
        (512, 512)
    };
    for (graph, persistent, other) in [
        ("pt", "RegenerationPTsk", "NaivePTsk"),
        ("bpt-lvc", "LVC-BPTsk", "LVC-BPTmk"),
        ("vcm", "VCMsk", "VCMmk"),
    ] {
        let owned = match graph {
            "pt" => Vec::new(),
            _ => measured(&scene, graph, persistent, (size, 1, 7), &[]),
        };
        let constants = borrowed(&owned);
        let a = render(&scene, graph, persistent, size, 1, 1, 7, &constants);
        let b = render(&scene, graph, other, size, 1, 1, 7, &constants);
        let paths = (size.0 * size.1) as u64;
        assert_eq!(a.counters["rays_primary"], paths, "{persistent}: camera paths lost");
        assert_same_render(&a, &b, &format!("{persistent} vs {other} at {}x{}", size.0, size.1));
    }
}

#[test]
fn a_run_takes_another_layout_with_that_layouts_bvh() {
    use lightgraph_scenes::bvh::BvhKind;
    // PPMsk's hint is the BVH2, PPMmk takes the CWBVH: the scene is loaded again, unless the
    // spec names a BVH.
    let spec = |bvh| lightgraph::run::RunSpec {
        scene: "cornell-diffuse".into(),
        graph: "ppm".into(),
        res: Some((16, 16)),
        bvh: lightgraph::run::BvhChoice(bvh),
        ..Default::default()
    };
    let mut run = lightgraph::run::Run::load(&spec(None)).unwrap();
    assert_eq!((run.layout.as_str(), run.bvh()), ("PPMsk", BvhKind::Bvh2));
    run.relayout("PPMmk").unwrap();
    assert_eq!((run.layout.as_str(), run.bvh()), ("PPMmk", BvhKind::Cwbvh));
    assert_eq!(run.decl.kernels, run.graph.layouts["PPMmk"].kernels);
    let mut named = lightgraph::run::Run::load(&spec(Some(BvhKind::Bvh2))).unwrap();
    named.relayout("PPMmk").unwrap();
    assert_eq!(named.bvh(), BvhKind::Bvh2);
    let err = format!("{:#}", run.relayout("PPMxx").unwrap_err());
    assert!(err.contains("unknown layout 'PPMxx'") && err.contains("PPMsk"), "{err}");
}
