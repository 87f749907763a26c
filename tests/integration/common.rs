//! Shared helpers: one GPU per test binary, rendering a scene to an image, region statistics.

use lightgraph::run::{
    Image, LayoutOverrides, LoadedScene, Session, SessionOptions, device_flags, kernel_flags, load_graph,
    specialization,
};
use lightgraph_engine::{Program, compile};

use lightgraph_engine::{ConstValue, Gpu};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::OnceLock;

pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new(None).expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"))
}

pub fn data(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(path)
}

/// What a test render produced.
pub struct Rendered {
    pub image: Image,
    pub counters: BTreeMap<String, u64>,
    pub loops_capped: u64,
    /// The session's GPU memory.
    pub memory_bytes: u64,
}

/// Session options of `size` pixels, `spp` samples per pixel per frame, seed `seed`, with
/// `constants` and layout options `overrides`.
pub fn options(
    size: (u32, u32),
    spp: u32,
    seed: u32,
    constants: &[(&str, ConstValue)],
    overrides: LayoutOverrides,
) -> SessionOptions {
    SessionOptions {
        width: size.0,
        height: size.1,
        samples_per_frame: spp,
        seed,
        constants: constants.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        layout: overrides,
    }
}

/// The graph's measured constants (LVC-BPT's average light sub-path length) for `scene` in
/// `layout` at `size` and `spp` with `seed` and `constants`, measured once: runs that must
/// render the same image are given one measurement (on lavapipe the measuring frame's count
/// can differ between sessions, see docs/testing.md).
pub fn measured(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    (size, spp, seed): ((u32, u32), u32, u32),
    constants: &[(&str, ConstValue)],
) -> Vec<(String, ConstValue)> {
    let loaded = load_graph(graph).unwrap();
    let decl = loaded.layout(layout).unwrap().clone();
    let opts = options(size, spp, seed, constants, Default::default());
    let measured = lightgraph::run::measure_constants(gpu(), &loaded, layout, decl, scene, &opts).unwrap();
    measured.into_iter().collect()
}

/// `owned` constants as the `(&str, value)` pairs the render helpers take.
pub fn borrowed(owned: &[(String, ConstValue)]) -> Vec<(&str, ConstValue)> {
    owned.iter().map(|(k, v)| (k.as_str(), *v)).collect()
}

/// Renders `scene` with `graph` in `layout` with the layout options `overrides`: `size`
/// pixels, `spp` samples per pixel per frame, `frames` frames, seed `seed`, constant overrides
/// `constants`.
#[allow(clippy::too_many_arguments)]
pub fn render_with_layout(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    size: (u32, u32),
    spp: u32,
    frames: u32,
    seed: u32,
    constants: &[(&str, ConstValue)],
    overrides: LayoutOverrides,
) -> Rendered {
    let graph = load_graph(graph).unwrap();
    let options = options(size, spp, seed, constants, overrides);
    let mut session = Session::new(gpu(), &graph, layout, scene, options).unwrap();
    for _ in 0..frames {
        session.render_frame().unwrap();
    }
    Rendered {
        image: session.image().unwrap(),
        counters: session.counters.clone(),
        loops_capped: session.loops_capped,
        memory_bytes: session.memory_bytes(),
    }
}

/// Renders `scene` with `graph` in `layout` (`size` pixels, one sample per pixel a frame,
/// `constants`) in `batches` batches of `frames` frames from seed `seed`: each batch's
/// per-pixel mean, batch by batch (the method of batch means: their spread is the standard
/// error whatever the correlation between pixels, which the light tracers have).
pub fn render_batches(
    scene: &LoadedScene,
    (graph, layout): (&str, &str),
    size: (u32, u32),
    (batches, frames): (u32, u32),
    seed: u32,
    constants: &[(&str, ConstValue)],
) -> Vec<Vec<[f64; 3]>> {
    let graph = load_graph(graph).unwrap();
    let options = options(size, 1, seed, constants, Default::default());
    let mut session = Session::new(gpu(), &graph, layout, scene, options).unwrap();
    (0..batches)
        .map(|_| {
            for _ in 0..frames {
                session.render_frame().unwrap();
            }
            let taken = session.take_accumulation().unwrap();
            let n = taken.frames as f64;
            taken.sum.iter().map(|s| [0, 1, 2].map(|c| s[c] as f64 / n)).collect()
        })
        .collect()
}

/// [`render_with_layout`] with the layout's own options.
#[allow(clippy::too_many_arguments)]
pub fn render(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    size: (u32, u32),
    spp: u32,
    frames: u32,
    seed: u32,
    constants: &[(&str, ConstValue)],
) -> Rendered {
    render_with_layout(
        scene,
        graph,
        layout,
        size,
        spp,
        frames,
        seed,
        constants,
        Default::default(),
    )
}

/// [`render_with_layout`] without constants, with the layout's thread pool overridden.
#[allow(clippy::too_many_arguments)]
pub fn render_with(
    scene: &LoadedScene,
    graph: &str,
    layout: &str,
    size: (u32, u32),
    spp: u32,
    frames: u32,
    seed: u32,
    threads: Option<u64>,
) -> Rendered {
    let overrides = LayoutOverrides {
        threads,
        ..Default::default()
    };
    render_with_layout(scene, graph, layout, size, spp, frames, seed, &[], overrides)
}

/// The program of `graph` in `layout` for `scene` with `constants` (every scene feature
/// compiled in with `all_features`).
pub fn program(
    graph: &str,
    layout: &str,
    scene: &LoadedScene,
    constants: &[(&str, ConstValue)],
    all_features: bool,
) -> Program {
    let graph = load_graph(graph).unwrap();
    let options = options((8, 8), 1, 1, constants, Default::default());
    let flags = kernel_flags(device_flags(gpu()), scene, all_features);
    let spec = specialization(&graph, &scene.scene, &options, flags);
    compile(&graph, layout, &graph.layouts[layout], &spec, &gpu().target()).unwrap()
}

/// The generated WGSL of every kernel of [`program`], joined.
pub fn kernel_sources(
    graph: &str,
    layout: &str,
    scene: &LoadedScene,
    constants: &[(&str, ConstValue)],
    all_features: bool,
) -> String {
    let program = program(graph, layout, scene, constants, all_features);
    let sources: Vec<&str> = program.kernels.iter().map(|k| k.source.text()).collect();
    sources.join("\n")
}

/// Mean and standard error of the mean radiance over the pixels `select` keeps, per channel.
/// Pixels are independent (each pixel's paths are its own), so the variance of the region
/// mean is the sum of the pixels' variances of the mean over the pixel count squared.
pub fn region(image: &Image, select: impl Fn(u32, u32) -> bool) -> ([f64; 3], [f64; 3], usize) {
    let mut sum = [0f64; 3];
    let mut var = [0f64; 3];
    let mut n = 0usize;
    for y in 0..image.height {
        for x in 0..image.width {
            if !select(x, y) {
                continue;
            }
            let i = (y * image.width + x) as usize;
            for c in 0..3 {
                sum[c] += image.mean[i][c] as f64;
                var[c] += image.variance[i][c] as f64 / image.frames as f64;
            }
            n += 1;
        }
    }
    let nf = n as f64;
    (sum.map(|s| s / nf), var.map(|v| v.sqrt() / nf), n)
}

/// Asserts no pixel is NaN, infinite or negative.
pub fn assert_finite(image: &Image, what: &str) {
    for (i, p) in image.mean.iter().enumerate() {
        assert!(
            p.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{what}: pixel {i} is {p:?}"
        );
    }
}

/// The largest difference between two images' pixels, relative to the larger of the two
/// values (at least 1e-3), over all channels.
pub fn largest_relative_difference(a: &Image, b: &Image) -> f64 {
    let mut worst = 0f64;
    for (p, q) in a.mean.iter().zip(&b.mean) {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
        }
    }
    worst
}

/// Asserts that `b` traced the rays `a` traced and renders `a`'s image to float rounding
/// (relative differences below 1e-5: the order of the film's atomic additions), with `what`
/// naming the runs.
pub fn assert_same_render(a: &Rendered, b: &Rendered, what: &str) {
    assert_eq!(a.counters, b.counters, "{what}: different rays");
    let worst = largest_relative_difference(&a.image, &b.image);
    eprintln!("{what}: largest relative difference {worst:.2e}");
    assert!(worst < 1e-5, "{what}: differs by {worst:.2e}, more than float rounding");
}

/// A seeded SplitMix64 generator of uniform numbers in [0, 1) (consecutive outputs of a plain
/// 64-bit LCG are too correlated for pairs of numbers).
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next number in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Asserts that a region's per-channel `mean` (standard error `se`) is the analytic
/// `expected` within `z` standard errors plus `rounding` of the value (float rounding, for
/// renders with next to no noise), and that the standard error is under 1.5% of the value, so
/// that the check has the power to see a bias of a few percent.
pub fn assert_analytic(what: &str, mean: [f64; 3], se: [f64; 3], expected: [f64; 3], z: f64, rounding: f64) {
    for c in 0..3 {
        eprintln!(
            "{what} channel {c}: {:.5} +- {:.5} (expected {:.5})",
            mean[c], se[c], expected[c]
        );
        assert!(
            se[c] < 0.015 * expected[c],
            "{what}: standard error {} too large to test {}",
            se[c],
            expected[c]
        );
        let tolerance = z * se[c] + rounding * expected[c];
        assert!(
            (mean[c] - expected[c]).abs() < tolerance,
            "{what} channel {c}: {} differs from {} by more than {z} standard errors ({}) and rounding",
            mean[c],
            expected[c],
            se[c]
        );
    }
}

/// The asset root (LIGHTGRAPH_ASSETS, else ../shared/scenes) for a test of the assets tier
/// (ignored by default, with the reason; `cargo xtask test` runs the tier where the asset
/// root exists, `cargo xtask test --assets` demands it; their names hold `shared_assets`),
/// which holds every asset of `assets` intact for what the tests read: every file of the
/// catalog's entry, by size. Panics naming the root and what is missing otherwise, so that
/// a test of the tier never passes without running.
pub fn shared_assets(assets: &[&str]) -> PathBuf {
    let Some(root) = lightgraph::assets::asset_root() else {
        panic!(
            "this test of the assets tier found no asset root: set LIGHTGRAPH_ASSETS or put shared/scenes beside the repository"
        );
    };
    let catalog = lightgraph::asset_catalog::Catalog::builtin();
    for name in assets {
        let asset = catalog.find(name).unwrap();
        let missing: Vec<&str> = asset
            .files
            .iter()
            .filter(|f| !std::fs::metadata(f.location(&root, asset)).is_ok_and(|m| m.len() == f.size))
            .map(|f| f.path.as_str())
            .collect();
        assert!(
            missing.is_empty(),
            "this test of the assets tier needs the asset {name} under {}, where these of its files are missing or of another size: {} (lightgraph assets fetch {name} --to {} gets those with a public download)",
            root.display(),
            missing.join(", "),
            root.display()
        );
    }
    root
}
