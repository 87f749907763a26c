//! The resolve stage on the shipped graphs: culling by constants (a switched-off pass leaves
//! every kernel and the image), memory shared by transient buffers (never by two live at
//! once; the same image as with memory of their own), and LVC-BPT on the engine's operators
//! rendering what it rendered before them.

use crate::common::{
    borrowed, data, gpu, kernel_sources, largest_relative_difference, measured, options, render, render_with_layout,
};
use lightgraph::run::{LayoutOverrides, device_flags, kernel_flags, load_graph, load_scene, specialization};
use lightgraph_engine::{ConstValue, compile};

/// The kernels' WGSL of `graph` in `layout` for the Cornell box with `constants`.
fn cornell_kernels(graph: &str, layout: &str, constants: &[(&str, ConstValue)]) -> String {
    kernel_sources(graph, layout, &load_scene("cornell-diffuse").unwrap(), constants, false)
}

#[test]
fn a_constant_switches_a_pass_off_its_code_and_its_light() {
    let tint = data("graphs/pt-tint.ron");
    let tint = tint.to_str().unwrap();
    let on = [("TINT", ConstValue::Bool(true))];
    for layout in ["NaivePTsk", "NaivePTmk"] {
        assert!(
            cornell_kernels(tint, layout, &on).contains("fn tint("),
            "{layout}: TINT on"
        );
        let off = cornell_kernels(tint, layout, &[]);
        assert!(
            !off.contains("fn tint("),
            "{layout}: the culled pass's code is in a kernel"
        );
        assert!(
            !off.contains("film_add(index, vec3<f32>(f32(SAMPLES_PER_PIXEL)))"),
            "{layout}"
        );
    }
    let scene = load_scene("cornell-glossy-point").unwrap();
    for layout in ["NaivePTsk", "NaivePTmk"] {
        let pt = render(&scene, "pt", layout, (16, 16), 2, 2, 5, &[]);
        let off = render(&scene, tint, layout, (16, 16), 2, 2, 5, &[]);
        let worst = largest_relative_difference(&pt.image, &off.image);
        assert!(
            worst < 1e-6,
            "{layout}: with TINT off the image differs from pt's by {worst:.2e}"
        );
        assert_eq!(pt.counters, off.counters, "{layout}: the same rays");
        // Switched on, the pass adds exactly 1 to every pixel (a test that can fail).
        let tinted = render(&scene, tint, layout, (16, 16), 2, 2, 5, &on);
        for (a, b) in tinted.image.mean.iter().zip(&pt.image.mean) {
            for c in 0..3 {
                assert!((a[c] - b[c] - 1.0).abs() < 1e-4, "{layout}: tinted {a:?} vs {b:?}");
            }
        }
    }
}

/// Every shipped graph, every layout: buffers that share memory are never live at once,
/// and sharing never takes more than memory of their own.
#[test]
fn shared_memory_is_never_live_twice() {
    let scene = load_scene("cornell-diffuse").unwrap();
    for name in lightgraph::assets::graph_names() {
        let graph = load_graph(&name).unwrap();
        // The LVC's size comes from its measured average: a typical one, set.
        let lvc = [("LVC_AVERAGE_LENGTH", ConstValue::F32(2.0))];
        let constants = if graph.constants.contains_key(lvc[0].0) {
            &lvc[..]
        } else {
            &[]
        };
        let options = options((32, 32), 1, 1, constants, Default::default());
        let spec = specialization(
            &graph,
            &scene.scene,
            &options,
            kernel_flags(device_flags(gpu()), &scene, false),
        );
        for layout in graph.layouts.keys() {
            let program = compile(&graph, layout, &graph.layouts[layout], &spec, &gpu().target()).unwrap();
            let m = &program.resolved.memory;
            for (a, b) in m.sharing() {
                let (la, lb) = (m.lifetimes[&a], m.lifetimes[&b]);
                assert!(
                    !la.overlaps(&lb),
                    "{name} {layout}: {a:?} {la:?} and {b:?} {lb:?} share memory while both live"
                );
            }
            // Sharing never costs more than each buffer's alignment padding (256 bytes at
            // most: wgpu's largest storage offset alignment), which tiny buffers can exceed.
            let padding = 256 * m.placements.len() as u64;
            assert!(m.peak_bytes() <= m.unshared_bytes() + padding, "{name} {layout}");
        }
    }
}

#[test]
fn lvc_bpt_mk_shares_memory_and_renders_what_it_renders_without_sharing() {
    let scene = load_scene("cornell-glossy-background").unwrap();
    // One measurement of the average light sub-path length for both sessions.
    let owned = measured(&scene, "bpt-lvc", "LVC-BPTmk", ((24, 24), 2, 9), &[]);
    let constants = &borrowed(&owned)[..];
    let shared = render_with_layout(
        &scene,
        "bpt-lvc",
        "LVC-BPTmk",
        (24, 24),
        2,
        2,
        9,
        constants,
        LayoutOverrides::default(),
    );
    let separate = LayoutOverrides {
        separate_memory: true,
        ..Default::default()
    };
    let own = render_with_layout(&scene, "bpt-lvc", "LVC-BPTmk", (24, 24), 2, 2, 9, constants, separate);
    assert!(
        shared.memory_bytes < own.memory_bytes,
        "sharing memory saves nothing: {} vs {} bytes",
        shared.memory_bytes,
        own.memory_bytes
    );
    assert_eq!(shared.counters, own.counters);
    let worst = largest_relative_difference(&shared.image, &own.image);
    assert!(worst < 1e-5, "shared memory changes the image by {worst:.2e}");
}

/// The reference image was rendered by LVC-BPTsk before the engine had operators (commit
/// 6ae69d8, when three levels of one-thread scan passes put the cache in sub-path order), on
/// lavapipe: 32 x 32, 2 samples per pixel, 3 frames, seed 11; the cache went through the
/// engine's scan and scatter since, with the same random numbers. It was rendered again (the
/// same command, `lightgraph render --graph bpt-lvc --layout LVC-BPTsk --scene
/// cornell-glossy-background --res 32x32 --spp 2 --frames 3 --seed 11 --set
/// LVC_AVERAGE_LENGTH=0.8007`) when camera samples started taking their pixels in tile order
/// (VCM's halves equal LVC-BPT and PBPM, whose order it is), and again when light sub-paths
/// started at stratified points of the light (`light_stratified_point`: other random numbers,
/// the same estimator). Both layouts must render it, up to the float rounding of the film's
/// atomic sums.
/// The average light sub-path length it was rendered with, 0.8007 (8007 vertices stored by the
/// 10^4 sub-paths of the measuring frame), is given rather than measured again: on lavapipe the
/// measuring frame's count can differ between sessions (docs/testing.md).
#[test]
fn lvc_bpt_renders_what_it_rendered_before_the_operators() {
    let path = data("golden/bpt-lvc-sk.exr");
    let golden = lightgraph::output::read_exr(&path).unwrap();
    let scene = load_scene("cornell-glossy-background").unwrap();
    for layout in ["LVC-BPTsk", "LVC-BPTmk"] {
        let measured = [("LVC_AVERAGE_LENGTH", ConstValue::F32(0.8007))];
        let now = render(&scene, "bpt-lvc", layout, (32, 32), 2, 3, 11, &measured);
        let (mut worst, mut sum_now, mut sum_then) = (0f64, 0f64, 0f64);
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let then = golden.channel(name, &path).unwrap();
            for (p, &t) in now.image.mean.iter().zip(then) {
                let (x, y) = (p[c] as f64, t as f64);
                worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
                sum_now += x;
                sum_then += y;
            }
        }
        eprintln!("{layout}: largest relative difference to the reference {worst:.2e}");
        assert!(worst < 1e-4, "{layout}: differs from the reference by {worst:.2e}");
        assert!(
            (sum_now / sum_then - 1.0).abs() < 1e-5,
            "{layout}: mean {sum_now} vs {sum_then}"
        );
    }
}
