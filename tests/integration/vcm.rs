//! Vertex connection and merging: its two halves against the estimators they are (LVC-BPT
//! without merging, PBPM without connections) and its layouts against each other, all for one
//! seed to float rounding; then the whole against path tracing, within statistical error, and
//! the specular-diffuse-specular light that LVC-BPT cannot sample.

use crate::bpt::{agrees_with_pt_under, excess_z, mirror_and_floor, sds_scene};
use crate::common::{Rendered, borrowed, gpu, largest_relative_difference, measured, options, render};
use crate::frames::{render_frames, render_frames_with};
use crate::pm::assert_the_mirror_shows_the_caustic;
use lightgraph::aov::{Aov, AovRender};
use lightgraph::run::{LoadedScene, load_scene};
use lightgraph_engine::ConstValue;
use lightgraph_scenes::bvh::BvhKind;

/// The rays two renders traced, by kind (graphs differ in their other counters).
fn rays(r: &Rendered) -> Vec<(String, u64)> {
    let kinds = ["rays_primary", "rays_extension", "rays_light", "rays_shadow"];
    kinds
        .iter()
        .map(|k| (k.to_string(), r.counters.get(*k).copied().unwrap_or(0)))
        .collect()
}

/// `a` and `b` traced the same rays and rendered the same image to float rounding (the film's
/// atomic additions, and a merge's vertices, are summed in the order the threads come).
fn assert_same_render(a: &Rendered, b: &Rendered, what: &str) {
    assert_eq!(rays(a), rays(b), "{what}: different rays");
    let worst = largest_relative_difference(&a.image, &b.image);
    eprintln!("{what}: largest relative difference {worst:.2e}");
    assert!(worst < 1e-5, "{what}: differs by {worst:.2e}");
}

/// VCM with VCM_MERGE false traces LVC-BPT's sub-paths with its random numbers, caches the
/// same vertices and weighs them alike: the same image for one seed (one measurement of the
/// cache's average for both).
#[test]
fn vcm_without_merging_renders_lvc_bpt() {
    let no_merge = [("VCM_MERGE", ConstValue::Bool(false))];
    for name in ["cornell-glossy-point", "cornell-glossy-background"] {
        let scene = load_scene(name).unwrap();
        let owned = measured(&scene, "bpt-lvc", "LVC-BPTsk", ((16, 16), 2, 42), &[]);
        let mut constants = borrowed(&owned);
        let lvc = render(&scene, "bpt-lvc", "LVC-BPTsk", (16, 16), 2, 2, 42, &constants);
        constants.extend(no_merge);
        let vcm = render(&scene, "vcm", "VCMsk", (16, 16), 2, 2, 42, &constants);
        assert_same_render(&lvc, &vcm, &format!("{name}: vcm without merging vs bpt-lvc"));
    }
}

/// VCM measures its hash grid's cell scale (`PM_CELL_SCALE`, graphs/vcm.ron) from a frame's
/// cached vertices found per merge query: 3 on the diffuse box at the default radius, where a
/// query at 32x32 finds about 0.01 of them, 1 at a radius 17 times larger (about 2 a query).
#[test]
fn vcm_measures_larger_cells_where_merges_find_little() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let scale = |radius: f32| {
        let owned = measured(
            &scene,
            "vcm",
            "VCMsk",
            ((32, 32), 1, 7),
            &[("PM_RADIUS", ConstValue::F32(radius))],
        );
        owned
            .into_iter()
            .find(|(name, _)| name == "PM_CELL_SCALE")
            .map(|(_, v)| v)
    };
    assert_eq!(scale(0.003), Some(ConstValue::F32(3.0)));
    assert_eq!(scale(0.05), Some(ConstValue::F32(1.0)));
}

/// A merge walks its box of cells (at most 2 along each axis where the cells are at least the
/// query's diameter, more where they are smaller, whose buckets may then coincide) and resumes
/// the walk after every VCM_FOUND_BATCH vertices found: cells of other sizes and other numbers
/// of buckets must find the same vertices (each once, in its own cell's visit) and render the
/// same image, at a radius where queries find many. Scales below 0.5 are left out: their long
/// walks run VCMsk's persistent threads past lavapipe's cap on a shader's loop iterations
/// (docs/performance.md, "Persistent threads on lavapipe"), which then loses sub-paths.
#[test]
fn vcm_cells_of_any_size_find_the_same_vertices() {
    let scene = load_scene("cornell-glossy-mirrorball").unwrap();
    let radius = ("PM_RADIUS", ConstValue::F32(0.05));
    let owned = measured(&scene, "vcm", "VCMsk", ((16, 16), 2, 46), &[radius]);
    let run = |scale: f32, buckets: f32| {
        let mut constants = borrowed(&owned);
        constants.retain(|(name, _)| *name != "PM_CELL_SCALE");
        constants.extend([
            radius,
            ("PM_CELL_SCALE", ConstValue::F32(scale)),
            ("PM_BUCKETS_PER_PATH", ConstValue::F32(buckets)),
        ]);
        render(&scene, "vcm", "VCMsk", (16, 16), 2, 2, 46, &constants)
    };
    let reference = run(1.0, 4.0);
    assert!(reference.counters["pm_found"] > 1000, "too few merges to compare");
    for (scale, buckets) in [(3.0, 4.0), (0.5, 1.0), (0.7, 2.0), (1.0, 0.25)] {
        let other = run(scale, buckets);
        let what = format!("cell scale {scale}, {buckets} buckets a path");
        assert_eq!(
            reference.counters["pm_found"], other.counters["pm_found"],
            "{what}: different vertices merged"
        );
        assert_same_render(&reference, &other, &what);
    }
}

/// VCM with VCM_CONNECT false traces PBPM's sub-paths with its random numbers (no light
/// sampling), merges the same vertices (stored at the same places, their directions in the
/// photons' 24 bits) with PBPM's weights, and counts the light PBPM counts: the same image
/// for one seed, at a radius where every query finds many vertices.
#[test]
fn vcm_without_connections_renders_pbpm() {
    let radius = ("PM_RADIUS", ConstValue::F32(0.05));
    for name in ["cornell-glossy-mirrorball", "cornell-glossy-background"] {
        let scene = load_scene(name).unwrap();
        let pbpm = render(&scene, "pbpm", "PBPMsk", (16, 16), 2, 2, 43, &[radius]);
        let constants = [radius, ("VCM_CONNECT", ConstValue::Bool(false))];
        let vcm = render(&scene, "vcm", "VCMsk", (16, 16), 2, 2, 43, &constants);
        assert_eq!(
            pbpm.counters["pm_found"], vcm.counters["pm_found"],
            "{name}: different vertices merged"
        );
        assert!(vcm.counters["pm_found"] > 1000, "{name}: too few merges to compare");
        assert_same_render(&pbpm, &vcm, &format!("{name}: vcm without connections vs pbpm"));
    }
}

/// VCMmk stores its sub-paths between kernels, compacts them and queues the connections, yet
/// takes the same random numbers, cache vertices and merges as VCMsk, also with two
/// iterations a frame; VCMsk merges at the vertex (its tuning profile sets VCM_MERGE_AT_VERTEX), VCMmk
/// in `vcm_gather` with the BSDF set up again from the pending merge, and VCMsk with the
/// constant given false (its gather fused) renders the same too.
#[test]
fn every_vcm_layout_matches_vcm_sk() {
    let radius = ("PM_RADIUS", ConstValue::F32(0.05));
    let two = ("PM_ITERATIONS", ConstValue::U32(2));
    for (name, iterations) in [
        ("cornell-glossy-point", None),
        ("cornell-glossy-background", None),
        ("cornell-glossy-point", Some(two)),
    ] {
        let scene = load_scene(name).unwrap();
        let owned = measured(&scene, "vcm", "VCMsk", ((16, 16), 2, 44), &[radius]);
        let mut constants = borrowed(&owned);
        constants.push(radius);
        constants.extend(iterations);
        let sk = render(&scene, "vcm", "VCMsk", (16, 16), 2, 2, 44, &constants);
        let mk = render(&scene, "vcm", "VCMmk", (16, 16), 2, 2, 44, &constants);
        assert_eq!(sk.counters, mk.counters, "{name}: VCMmk traced or merged differently");
        assert!(sk.counters["pm_found"] > 1000, "{name}: too few merges to compare");
        assert_same_render(&sk, &mk, &format!("{name}: VCMmk vs VCMsk"));
        constants.push(("VCM_MERGE_AT_VERTEX", ConstValue::Bool(false)));
        let gathered = render(&scene, "vcm", "VCMsk", (16, 16), 2, 2, 44, &constants);
        assert_eq!(
            sk.counters, gathered.counters,
            "{name}: VCMsk with its gather traced or merged differently"
        );
        assert_same_render(&sk, &gathered, &format!("{name}: VCMsk with its gather vs VCMsk"));
    }
}

/// With PM_ITERATIONS = 4 at 4 samples per pixel a frame is four iterations: the same rays
/// (the iterations change no random number), but each merge finds only the vertices of its
/// own iteration's light sub-paths, a subset of what it finds in one iteration of the whole
/// frame, and about a quarter of it. The vertices found are many (about 10^4 in the one
/// iteration), so the quarter's relative standard error is some percent: 0.2 to 0.3 holds it
/// with room, and a merge that still reached the other iterations' vertices gives 1.
#[test]
fn vcm_iterations_of_a_frame_merge_only_their_own_vertices() {
    let scene = load_scene("cornell-diffuse").unwrap();
    let radius = [("PM_RADIUS", ConstValue::F32(0.05)), ("PM_ALPHA", ConstValue::F32(1.0))];
    let owned = measured(&scene, "vcm", "VCMsk", ((16, 16), 4, 45), &radius);
    let mut constants = borrowed(&owned);
    constants.extend(radius);
    let whole = render(&scene, "vcm", "VCMsk", (16, 16), 4, 2, 45, &constants);
    constants.push(("PM_ITERATIONS", ConstValue::U32(4)));
    let four = render(&scene, "vcm", "VCMsk", (16, 16), 4, 2, 45, &constants);
    assert_eq!(rays(&whole), rays(&four), "the iterations traced other rays");
    let (all, own) = (whole.counters["pm_found"], four.counters["pm_found"]);
    let ratio = own as f64 / all as f64;
    eprintln!("vertices found: {all} in one iteration a frame, {own} in four ({ratio:.3})");
    assert!(all > 5000, "too few vertices found to compare ({all})");
    assert!(
        (0.2..0.3).contains(&ratio),
        "four iterations found {ratio:.3} of the vertices"
    );
}

/// At r_0 = 0.025 of the scene's radius a merge counts some 20 times a connection on the
/// diffuse box (pi r^2 N_light with 2048 light sub-paths), so merges carry much of the image;
/// there photon mapping's bias is within the noise (pm.rs), and VCM agrees with path tracing
/// within 4 standard errors as LVC-BPT does (bpt.rs). On the glossy box with a background the
/// radius is 0.01 (light through the opening biases merges near the walls' edges, pm.rs).
#[test]
fn vcm_agrees_with_path_tracing() {
    for (name, radius) in [("cornell-diffuse", 0.025), ("cornell-glossy-background", 0.01)] {
        let constants = [
            ("PM_RADIUS", ConstValue::F32(radius)),
            ("PM_ALPHA", ConstValue::F32(1.0)),
        ];
        agrees_with_pt_under(name, "vcm", "VCMsk", &constants);
    }
}

/// Two iterations a frame (each merge over half the light sub-paths, counted so in its kernel
/// and MIS) agree with path tracing as one does, on the diffuse box at the radius above.
#[test]
fn vcm_with_two_iterations_a_frame_agrees_with_path_tracing() {
    let constants = [
        ("PM_RADIUS", ConstValue::F32(0.025)),
        ("PM_ALPHA", ConstValue::F32(1.0)),
        ("PM_ITERATIONS", ConstValue::U32(2)),
    ];
    agrees_with_pt_under("cornell-diffuse", "vcm", "VCMsk", &constants);
}

/// The point light inside the glass ball lights the floor with caustics alone, which the
/// mirror shows: LVC-BPT leaves the mirror black there (bpt.rs shows it for BPT), VCM's
/// merges find it.
#[test]
fn vcm_renders_the_caustic_seen_in_a_mirror() {
    let scene = sds_scene();
    let radius = [("PM_RADIUS", ConstValue::F32(0.02))];
    let vcm = render(&scene, "vcm", "VCMsk", (32, 32), 4, 8, 5, &radius);
    assert_the_mirror_shows_the_caustic(&vcm.image, "vcm");
    let lvc = render(&scene, "bpt-lvc", "LVC-BPTsk", (32, 32), 4, 8, 5, &[]);
    let (l_mirror, l_floor) = mirror_and_floor(&lvc.image);
    eprintln!("lvc-bpt: floor {l_floor:.4}, in the mirror {l_mirror:.6}");
    assert!(l_floor > 1e-3, "lvc-bpt: the floor is not lit ({l_floor})");
    assert!(
        l_mirror < 1e-3 * l_floor,
        "LVC-BPT sampled specular-diffuse-specular light ({l_mirror} vs {l_floor})"
    );
}

/// The glossy box lit by the sun: the glass ball's caustic on the floor, seen in the mirror
/// ball, is a specular-diffuse-specular path (the sun is a delta light): LVC-BPT cannot
/// sample it, so where the ball shows the caustic a block (2 x 2 pixels) is far brighter in
/// VCM than in LVC-BPT: more than 6 combined standard errors of 32 frames (seen: 14 and 9 in
/// the two blocks of the caustic). Were the two equal there, some of the ball's ~27 blocks
/// would pass 6 by chance with probability about 27 P(t_31 > 6), some 2e-5.
#[test]
fn vcm_renders_the_sun_caustic_seen_in_the_mirror_ball() {
    let scene = load_scene("cornell-glossy-sun").unwrap();
    let constants = [("PM_RADIUS", ConstValue::F32(0.02)), ("PM_ALPHA", ConstValue::F32(1.0))];
    let vcm = render_frames_with(&scene, "vcm", "VCMsk", (48, 4, 32, 45, 24), &constants);
    let lvc = render_frames(&scene, "bpt-lvc", "LVC-BPTsk", 48, 4, 32, 46, 24);
    let ball = mirror_ball_blocks(48, 24);
    assert!(
        ball.iter().filter(|b| **b).count() >= 8,
        "too few blocks inside the mirror ball"
    );
    // Red: the sun has no blue, and its green is weaker.
    let mut z: Vec<(usize, f64)> = (0..ball.len())
        .filter(|b| ball[*b])
        .map(|b| (b, excess_z(&vcm, &lvc, b, 0)))
        .filter(|(_, z)| z.is_finite())
        .collect();
    z.sort_by(|a, b| b.1.total_cmp(&a.1));
    eprintln!("vcm over lvc-bpt in the mirror ball's blocks (red, standard errors): {z:.1?}");
    assert!(
        z[0].1 > 6.0,
        "vcm: the sun's caustic seen in the mirror ball is missing ({:.1} SE)",
        z[0].1
    );
}

/// The blocks (of `n` x `n`) of a `size` image of cornell-glossy-sun that lie wholly inside
/// the mirror ball: where the albedo of the first non-specular hit is a colour only the ball,
/// made diffuse for the mask, has.
fn mirror_ball_blocks(size: u32, n: u32) -> Vec<bool> {
    let text = std::fs::read_to_string("scenes/cornell/cornell-glossy-sun.ron").unwrap();
    let masked = text
        .replace(
            r#"radius: 0.5, material: "mirror")"#,
            r#"radius: 0.5, material: "mask")"#,
        )
        .replace("materials: {", r#"materials: { "mask": (diffuse: (0.25, 0.5, 0.75)),"#);
    assert_eq!(
        masked.matches(r#""mask""#).count(),
        2,
        "the mirror ball is not in the scene file"
    );
    let scene = LoadedScene::parse("cornell-glossy-sun.ron", &masked, BvhKind::Bvh2, None).unwrap();
    let opts = options((size, size), 16, 1, &[], Default::default());
    let mut aov = AovRender::new(gpu(), &scene, &opts, &[Aov::Albedo]).unwrap();
    aov.render(0, 1).unwrap();
    let layers = aov.layers().unwrap();
    let (_, albedo) = layers
        .iter()
        .find(|(name, _)| name == "albedo.B")
        .expect("an albedo layer");
    let per = size / n;
    (0..n * n)
        .map(|b| {
            let (bx, by) = (b % n, b / n);
            (0..per * per).all(|k| {
                let (x, y) = (bx * per + k % per, by * per + k / per);
                (albedo[(y * size + x) as usize] - 0.75).abs() < 1e-3
            })
        })
        .collect()
}
