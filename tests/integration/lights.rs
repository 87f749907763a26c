//! Lights: sampling against densities (chi-square, see chi2.rs), the alias table's picks on
//! the GPU (by chi-square, and equal to the host's for every value), a spot light's falloff against the analytic direct illumination of a plane,
//! KHR_lights_punctual import, environment maps and their errors.

use crate::chi2::{SphereBins, goodness_of_fit, pearson, significance};
use crate::common::{assert_analytic, data, region, render, render_batches};
use crate::probe::{probe, scene};
use lightgraph::run::LoadedScene;
use lightgraph_engine::ConstValue;
use lightgraph_scenes::alias::{self, luminance};
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::environment::{EnvironmentMap, PatchPoint, TexelLayout, uv};
use lightgraph_scenes::model::Light;
use statrs::distribution::{ContinuousCDF, StudentsT};
use std::path::{Path, PathBuf};

/// The chi-square tests in this file (area light, environment map in two layouts, light
/// picks).
const CHI2_TESTS: u32 = 4;

const CAMERA: &str = "camera: (position: (0, 0, -4), look: Target((0, 0, 0)), up: (0, 1, 0), fov_degrees: 40.0)";

/// Samples `illuminate(light, probe_in[0].xyz, u)` `PER_INDEX` times per index: the direction
/// with w = 1 when it carries light, w = 0 when not; and, as a second vec4, the sample's pdf
/// and `background_radiance`'s pdf and radiance of the sampled direction.
const ILLUMINATE: &str = "fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    var rng = rng_seed(frame.seed, frame.index, index);
    let p = probe_in[0].xyz;
    for (var k = 0u; k < PER_INDEX / 2u; k++) {
        let ill = illuminate(LIGHT, p, rng_vec2(&rng));
        let ok = ill.pdf > 0.0 && !is_black(ill.radiance);
        let slot = index * PER_INDEX + 2u * k;
        out[slot] = vec4<f32>(ill.direction, select(0.0, 1.0, ok));
        let bg = background_radiance(ill.direction);
        out[slot + 1u] = vec4<f32>(ill.pdf, bg.w, luminance(bg.xyz), luminance(ill.radiance));
    }
    return false;
}";

/// Runs [`ILLUMINATE`] for light `light` seen from `p`: `n` × `per` samples, returned as
/// (direction sample, pdf record) pairs.
fn illuminate(s: &LoadedScene, light: u32, p: [f32; 3], n: u32, per: u32) -> Vec<([f32; 4], [f32; 4])> {
    let out = probe(
        s,
        ILLUMINATE,
        n,
        2 * per,
        &[[p[0], p[1], p[2], 0.0]],
        &[("LIGHT", ConstValue::U32(light))],
    );
    out.chunks_exact(2).map(|c| (c[0], c[1])).collect()
}

/// The density of `illuminate` choosing each direction in `probe_in` for an area light seen
/// from `probe_in[0]`, as `logic` computes it when a path hits the light: the light's area
/// density × t² / |cos| at the closest hit, 0 where the ray misses every light.
const AREA_PDF: &str = "fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
    let p = probe_in[0].xyz;
    let d = probe_in[index + 1u].xyz;
    let hit = trace_closest(p, d, INFINITE_DISTANCE);
    var pdf = 0.0;
    if (hit.found && primitive_at(hit.primitive).light >= 0) {
        let light = u32(primitive_at(hit.primitive).light);
        let le = area_light_radiance(light, d);
        pdf = le.w * hit.t * hit.t / abs(dot(lights[light].normal, d));
    }
    out[index] = vec4<f32>(pdf);
    return false;
}";

#[test]
fn area_light_sampling_matches_its_solid_angle_pdf() {
    let s = scene(&format!(
        "Scene({CAMERA}, materials: {{\"m\": (diffuse: (0.5, 0.5, 0.5))}},
            shapes: [Triangle(vertices: ((-1, -1, 2), (0, 1.5, 2), (1.5, -1, 2.5)), material: \"m\", emission: (1, 1, 1))])"
    ));
    let p = [0.2f32, 0.1, 0.0];
    let samples = illuminate(&s, 0, p, 256, 256);
    let directions: Vec<[f32; 4]> = samples.iter().map(|s| s.0).collect();
    assert!(directions.iter().all(|d| d[3] == 1.0), "every sample reaches the light");
    // A cap around the direction to the centroid that holds the whole triangle (its corners
    // lie within 50 degrees of it), binned finely enough to resolve the density's variation.
    let centroid = [0.1666 - 0.2, -0.1666 - 0.1, 2.1666];
    let grid = SphereBins::cap(centroid, 0.5f64.to_radians().cos().min(0.6), 16, 32);
    let sub = 8;
    let mut input = vec![[p[0], p[1], p[2], 0.0]];
    input.extend(grid.quadrature_points(sub));
    let pdf: Vec<f32> = probe(&s, AREA_PDF, (input.len() - 1) as u32, 1, &input, &[])
        .iter()
        .map(|v| v[0])
        .collect();
    let outcome = goodness_of_fit(&grid, &directions, &pdf, sub, &[]);
    let alpha = significance(CHI2_TESTS);
    eprintln!("area light: {outcome}");
    assert!(
        outcome.passes(alpha),
        "area light sampling: {outcome} (alpha {alpha:.2e})"
    );
    // The cap holds the whole triangle, so the density integrates to 1 over it, up to the
    // midpoint rule's error in the sub-cells the triangle's edges cut (about 1% of the mass
    // lies in such cells here, each of whose integral is off by at most its own mass).
    assert!(
        (outcome.pdf_integral - 1.0).abs() < 0.01,
        "area light pdf integrates to {}",
        outcome.pdf_integral
    );
    // The pdf `illuminate` reports equals the one `logic` uses when a path hits the light.
    for (k, (d, record)) in samples.iter().take(64).enumerate() {
        let input = [[p[0], p[1], p[2], 0.0], *d];
        let hit_pdf = probe(&s, AREA_PDF, 1, 1, &input, &[])[0][0];
        assert!(
            (hit_pdf - record[0]).abs() <= 1e-4 * record[0],
            "sample {k}: illuminate's pdf {} against the hit's {hit_pdf}",
            record[0]
        );
    }
}

/// A temporary asset root holding an environment map `name` of `width` × `height` texels.
fn environment_root(
    test: &str,
    name: &str,
    width: usize,
    height: usize,
    texel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lightgraph-lights-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    exr::prelude::write_rgb_file(dir.join(name), width, height, |x, y| {
        let t = texel(x, y);
        (t[0], t[1], t[2])
    })
    .unwrap();
    dir
}

fn environment_scene(lights: &str) -> String {
    format!(
        "Scene({CAMERA}, materials: {{\"m\": (diffuse: (0.5, 0.5, 0.5))}},
            shapes: [Sphere(center: (0, 0, 0), radius: 0.5, material: \"m\")], lights: [{lights}])"
    )
}

#[test]
fn environment_sampling_follows_the_filtered_maps_pdf() {
    let (w, h) = (16, 8);
    // Luminances from 0.03 to about 40, with a bright patch and one black texel (sampled only
    // where its lit neighbours make the bilinear density nonzero).
    let texel = |x: usize, y: usize| {
        let base = 0.05 + 0.3 * ((x * 7 + y * 3) % 11) as f32;
        if (x, y) == (10, 5) {
            [0.0; 3]
        } else if (5..8).contains(&x) && (2..4).contains(&y) {
            [40.0, 35.0, 30.0]
        } else {
            [base, 0.5 * base, 2.0 * base]
        }
    };
    let texels: Vec<[f32; 3]> = (0..w * h).map(|k| texel(k % w, k / w)).collect();
    let map = EnvironmentMap::new(w as u32, h as u32, texels).unwrap();
    for (layout, name) in [
        (TexelLayout::Centred, "Centred"),
        (TexelLayout::PoleToPole, "PoleToPole"),
    ] {
        let root = environment_root(&format!("sampling-{name}"), "sky.exr", w, h, texel);
        let (scale, rotation) = (2.0f64, 30.0f64);
        let text = environment_scene(&format!(
            "Environment(file: \"sky.exr\", scale: 2.0, rotation_degrees: 30.0, layout: {name})"
        ));
        let s = LoadedScene::parse("env.ron", &text, BvhKind::Bvh2, Some(&root)).unwrap();
        std::fs::remove_dir_all(&root).unwrap();
        let light = s.compiled.info.background as u32;
        let samples = illuminate(&s, light, [0.0; 3], 512, 256);
        // The expected distribution from the host's mirror of the GPU's: each patch split in
        // 2 x 2 bins, whose probability the midpoint rule gives exactly (the density over
        // (u, v) is bilinear within a patch).
        let d = map.distribution(layout);
        let p = d.patches;
        let bin = |q: &PatchPoint| (q.row * w + q.col) * 4 + (q.st[0] >= 0.5) as usize + 2 * (q.st[1] >= 0.5) as usize;
        let mut probability = vec![0.0; p.rows() * w * 4];
        for row in 0..p.rows() {
            for col in 0..w {
                for st in [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]] {
                    let q = PatchPoint { row, col, st };
                    let (u, v) = p.uv(&q);
                    probability[bin(&q)] = d.pdf(u, v) * (p.edge(row + 1) - p.edge(row)) / w as f64 / 4.0;
                }
            }
        }
        let (sin, cos) = rotation.to_radians().sin_cos();
        let mut observed = vec![0.0; probability.len()];
        let mut checked = 0;
        for (k, (dir, record)) in samples.iter().enumerate() {
            assert_eq!(dir[3], 1.0, "{name}: sample {k} carries light");
            let dir = [dir[0] as f64, dir[1] as f64, dir[2] as f64];
            // World to map: the inverse of the rotation about +Y.
            let m = [cos * dir[0] - sin * dir[2], dir[1], sin * dir[0] + cos * dir[2]];
            let (u, v) = uv(m);
            let q = p.locate(u, v);
            observed[bin(&q)] += 1.0;
            // sin θ from the horizontal components: exact near the poles, where the density
            // grows as 1 / sin θ and 1 - cos² θ would lose the digits.
            let sin_theta = m[0].hypot(m[2]) / (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
            let expected_pdf = d.pdf(u, v) / (2.0 * std::f64::consts::PI * std::f64::consts::PI * sin_theta);
            let expected_lum = scale * luminance(map.radiance(layout, u, v).map(|c| c as f32));
            let [pdf, lookup_pdf, lookup_lum, radiance_lum] = record.map(|v| v as f64);
            // The density jumps between patch rows, so f32 trigonometry within about 1e-6 of a
            // row's edge may put the sampled and the looked-up direction on different sides
            // (a rare MIS weight off by the ratio of two rows' densities, not a bias); and
            // near the black texel's corner the filtered values vanish, so that the f32
            // position's error is a larger part of them. The values are compared for samples
            // away from their patch's edges (where they are at least a tenth of the nearest
            // lit corner's); all samples count in the chi-square test.
            // The lookup finds (u, v) again from the f32 direction by atan2 (with acos(y), whose
            // digits go near the poles, the two differed by 1.2e-3 there on lavapipe).
            let inside = q.st.iter().all(|x| (x - 0.5).abs() < 0.45);
            if inside {
                assert!(
                    (pdf - lookup_pdf).abs() <= 1e-4 * pdf,
                    "{name}: sample {k}: sampled pdf {pdf}, lookup {lookup_pdf}"
                );
                assert!(
                    (radiance_lum - lookup_lum).abs() <= 1e-4 * radiance_lum,
                    "{name}: sample {k}: radiance {radiance_lum}, lookup {lookup_lum}"
                );
                assert!(
                    (pdf - expected_pdf).abs() <= 1e-3 * expected_pdf,
                    "{name}: sample {k}: pdf {pdf}, the host's mirror gives {expected_pdf}"
                );
                assert!(
                    (radiance_lum - expected_lum).abs() <= 1e-3 * expected_lum,
                    "{name}: sample {k}: radiance {radiance_lum}, the host's mirror gives {expected_lum}"
                );
                checked += 1;
            }
        }
        assert!(
            checked as f64 > 0.5 * samples.len() as f64,
            "{name}: {checked} samples checked"
        );
        let n = samples.len() as f64;
        let expected: Vec<f64> = probability.iter().map(|p| p * n).collect();
        assert_counts_fit(&observed, &expected, &format!("environment sampling ({name})"));
    }
}

/// Renders `scene` (a white Lambertian quad filling the view under a two-texel map) with
/// path tracing and compares every pixel's mean with the analytic radiance `expected`,
/// within 4 standard errors of the image mean (each required under 1.5% of the value, so a
/// bias of a few percent, such as the nearest texel's instead of the filtered radiance,
/// fails).
fn assert_lambertian_radiance(what: &str, scene: &LoadedScene, expected: [f64; 3]) {
    let r = render(scene, "pt", "NaivePTsk", (16, 16), 16, 16, 5, &[]);
    let (mean, se, n) = region(&r.image, |_, _| true);
    assert_eq!(n, 256);
    assert_analytic(what, mean, se, expected, 4.0, 0.0);
}

#[test]
fn lambertian_surfaces_under_two_texel_maps_reflect_the_filtered_irradiance() {
    use std::f64::consts::PI;
    // Texels a and b, each channel a different pair: (0, 1), (1, 0) and (0.5, 0.5).
    let (a, b) = ([0.0f32, 1.0, 0.5], [1.0f32, 0.0, 0.5]);
    let channels = |f: fn(f64, f64) -> f64| -> [f64; 3] { std::array::from_fn(|c| f(a[c] as f64, b[c] as f64)) };
    // A white (albedo 1) quad at x = 0 facing +X under a 2 x 1 map (a at u = 1/4, looking
    // along -X; b at u = 3/4, +X; wrapping through u = 0, +Z), seen from +X: its hemisphere is
    // u in (1/2, 1), where the radiance blends from (a + b)/2 to b and back, and it reflects
    // (1/π) ∫ L cos dω = (a + b + 2 (b − a)/π) / 2 in either layout (the map has one row).
    // The nearest texel would give b.
    let wall = "camera: (position: (3, 0, 0), look: Target((0, 0, 0)), up: (0, 1, 0), fov_degrees: 20.0)";
    let wall_quad = "Quad(corners: ((0, -1, -1), (0, 1, -1), (0, 1, 1), (0, -1, 1)), material: \"white\")";
    // A white quad at y = 0 facing +Y under a 1 x 2 map (a on top, b below), seen from above:
    // the radiance at θ from +Y blends a into b, from pole to pole (3a + b)/4 is reflected,
    // centred (a up to θ = π/4, then linear to the horizon's (a + b)/2)
    // a + (b − a)(1/4 − 1/(2π)). The nearest texel would give a.
    let floor = "camera: (position: (0, 3, 0), look: Target((0, 0, 0)), up: (0, 0, 1), fov_degrees: 20.0)";
    let floor_quad = "Quad(corners: ((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)), material: \"white\")";
    // (what, map size, layout, camera, quad, expected radiance)
    type Case<'a> = (&'a str, (usize, usize), &'a str, &'a str, &'a str, [f64; 3]);
    let cases: [Case; 4] = [
        (
            "wall, 2 x 1, centred",
            (2, 1),
            "Centred",
            wall,
            wall_quad,
            channels(|a, b| (a + b + 2.0 * (b - a) / PI) / 2.0),
        ),
        (
            "wall, 2 x 1, pole to pole",
            (2, 1),
            "PoleToPole",
            wall,
            wall_quad,
            channels(|a, b| (a + b + 2.0 * (b - a) / PI) / 2.0),
        ),
        (
            "floor, 1 x 2, pole to pole",
            (1, 2),
            "PoleToPole",
            floor,
            floor_quad,
            channels(|a, b| (3.0 * a + b) / 4.0),
        ),
        (
            "floor, 1 x 2, centred",
            (1, 2),
            "Centred",
            floor,
            floor_quad,
            channels(|a, b| a + (b - a) * (0.25 - 0.5 / PI)),
        ),
    ];
    for (k, (what, (w, h), layout, camera, quad, expected)) in cases.into_iter().enumerate() {
        let root = environment_root(&format!("two-texel-{k}"), "two.exr", w, h, |x, y| {
            if x + y == 0 { a } else { b }
        });
        let text = format!(
            "Scene({camera}, materials: {{\"white\": (diffuse: (1, 1, 1))}}, shapes: [{quad}],
                lights: [Environment(file: \"two.exr\", layout: {layout})])"
        );
        let s = LoadedScene::parse("two.ron", &text, BvhKind::Bvh2, Some(&root)).unwrap();
        std::fs::remove_dir_all(&root).unwrap();
        assert_lambertian_radiance(what, &s, expected);
    }
}

/// 300 point lights of intensities over four orders of magnitude (one black), an area light
/// and a background.
fn many_lights() -> LoadedScene {
    let mut lights: Vec<String> = (0..300)
        .map(|i| {
            let v = if i == 17 {
                0.0
            } else {
                10f32.powf((i * 37 % 300) as f32 / 75.0 - 2.0)
            };
            format!(
                "Point(position: ({}, 1, 0), intensity: ({v}, {v}, {v}))",
                i as f32 * 0.01
            )
        })
        .collect();
    lights.push("Background(radiance: (0.01, 0.02, 0.03))".into());
    scene(&format!(
        "Scene({CAMERA}, materials: {{\"m\": (diffuse: (0.5, 0.5, 0.5))}},
            shapes: [Triangle(vertices: ((-1, -1, 2), (0, 1.5, 2), (1.5, -1, 2.5)), material: \"m\", emission: (5, 5, 5))],
            lights: [{}])",
        lights.join(", ")
    ))
}

#[test]
fn gpu_light_picks_follow_the_alias_table() {
    let s = many_lights();
    let c = &s.compiled;
    let n = c.lights.len();
    let total: f64 = c.light_power.iter().sum();
    // The table's probabilities are whole numbers of 2^24 values (scenes/src/build/alias.rs),
    // within a value of the normalised power (or one value for the smallest).
    let values = (1u64 << alias::PICK_BITS) as f64;
    let table_p: Vec<f64> = c.light_alias[..n].iter().map(|e| e.pmf as f64).collect();
    for (i, (p, power)) in table_p.iter().zip(&c.light_power).enumerate() {
        let share = power / total * values;
        assert!(
            (p * values - share).abs() <= 1.0 + share * n as f64 / values,
            "light {i}: probability {p}, normalised power {}",
            power / total
        );
    }
    let wgsl = "fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
        var rng = rng_seed(frame.seed, frame.index, index);
        for (var k = 0u; k < PER_INDEX; k++) {
            let pick = pick_light(rng_f32(&rng));
            out[index * PER_INDEX + k] = vec4<f32>(f32(pick.index), pick.probability, light_pmf(pick.index), 0.0);
        }
        return false;
    }";
    let picks = probe(&s, wgsl, 1024, 256, &[], &[]);
    let mut observed = vec![0.0; n];
    for p in &picks {
        let i = p[0] as usize;
        observed[i] += 1.0;
        assert_eq!(p[1], p[2], "pick_light's probability is light_pmf's");
        assert_eq!(p[1] as f64, table_p[i], "light {i}: the probability is the table's");
    }
    // Light 0 is the triangle; point light 17 is light 18.
    assert_eq!(c.light_power[18], 0.0);
    assert_eq!(observed[18], 0.0, "a black light is never picked");
    let expected: Vec<f64> = table_p.iter().map(|p| p * picks.len() as f64).collect();
    assert_counts_fit(&observed, &expected, "light picks");
}

/// The GPU's `pick_light` picks what the host's `alias::pick` does for every one of the 2^24
/// values of its bits (so each light exactly as often as its pmf says, by the alias tests):
/// 4096 threads each run over 4096 consecutive values and return the sum of the picked
/// indices and a position-weighted sum, which the host computes the same way.
#[test]
fn gpu_light_picks_are_the_hosts_for_every_value() {
    const RUN: u32 = 4096;
    let s = many_lights();
    let c = &s.compiled;
    let wgsl = "fn probe(item: ptr<function, ProbeItem>, index: u32) -> bool {
        var sum = 0u;
        var weighted = 0u;
        for (var j = 0u; j < RUN; j++) {
            let pick = pick_light(f32(index * RUN + j) / 16777216.0);
            sum += pick.index;
            weighted = (weighted + pick.index * (j + 1u)) & 0xffffffu;
        }
        out[index] = vec4<f32>(f32(sum), f32(weighted), 0.0, 0.0);
        return false;
    }";
    let sums = probe(
        &s,
        wgsl,
        (1 << alias::PICK_BITS) / RUN,
        1,
        &[],
        &[("RUN", ConstValue::U32(RUN))],
    );
    let mut wrong = 0;
    for (index, got) in sums.iter().enumerate() {
        let (mut sum, mut weighted) = (0u32, 0u32);
        for j in 0..RUN {
            let pick = alias::pick(&c.light_alias, c.lights.len(), index as u32 * RUN + j);
            sum += pick;
            weighted = (weighted + pick * (j + 1)) & 0xffffff;
        }
        wrong += usize::from([got[0], got[1]] != [sum as f32, weighted as f32]);
    }
    assert_eq!(
        wrong, 0,
        "runs of 4096 values where the GPU picks other lights than the host"
    );
}

/// Pearson's test of `observed` cell counts against `expected` ones, at this file's
/// significance (CHI2_TESTS tests share the false-failure budget).
fn assert_counts_fit(observed: &[f64], expected: &[f64], what: &str) {
    let (statistic, dof, p_value, failure) = pearson(observed, expected);
    let alpha = significance(CHI2_TESTS);
    eprintln!("{what}: chi2 = {statistic:.1} with {dof} dof, p = {p_value:.3e}");
    assert!(
        failure.is_none() && p_value > alpha,
        "{what}: chi2 = {statistic} with {dof} dof, p = {p_value:e} (alpha {alpha:e}), {failure:?}"
    );
}

/// glTF's spot falloff.
fn falloff(cos: f64, cos_inner: f64, cos_outer: f64) -> f64 {
    if cos >= cos_inner {
        1.0
    } else if cos <= cos_outer {
        0.0
    } else {
        ((cos - cos_outer) / (cos_inner - cos_outer)).powi(2)
    }
}

/// Mitsuba's spot falloff, linear in the angle.
fn linear_falloff(cos: f64, cos_inner: f64, cos_outer: f64) -> f64 {
    let (angle, inner, outer) = (cos.acos(), cos_inner.acos(), cos_outer.acos());
    ((outer - angle) / (outer - inner)).clamp(0.0, 1.0)
}

#[test]
fn spot_light_falloff_matches_the_direct_illumination_of_a_plane() {
    check_spot_falloff("Smooth", falloff);
    check_spot_falloff("Linear", linear_falloff);
}

/// A spot 1 above a diffuse plane (albedo 0.5) with the falloff `name` (`expected` of cos θ,
/// cos inner, cos outer), pointing straight down; the camera looks down at it. Each pixel's
/// radiance is ρ/π × I × falloff(θ) × cos θ / r² averaged over the pixel (the only randomness
/// is the pixel jitter; the bounce ray escapes into black).
fn check_spot_falloff(name: &str, expected_falloff: fn(f64, f64, f64) -> f64) {
    let (inner, outer, height, intensity) = (20.0f64, 40.0f64, 1.0f64, 3.0f64);
    let text = format!(
        "Scene(camera: (position: (0, 0, 3), look: Target((0, 0, 0)), up: (0, 1, 0), fov_degrees: 40.0),
            materials: {{\"m\": (diffuse: (0.5, 0.5, 0.5))}},
            shapes: [Quad(corners: ((-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)), material: \"m\")],
            lights: [Spot(position: (0, 0, {height}), direction: (0, 0, -1), intensity: ({intensity}, {intensity}, {intensity}),
                inner_cone_degrees: {inner}, outer_cone_degrees: {outer}, falloff: {name})],
            integrator: (max_path_length: 2))"
    );
    let s = scene(&text);
    let (size, spp, frames) = (24u32, 16, 32);
    let r = render(&s, "pt", "NaivePTsk", (size, size), spp, frames, 3, &[]);
    let camera = lightgraph_scenes::CompiledScene::camera(&s.scene, size, size);
    let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
    let radiance_at = |x: f64, y: f64| {
        // The camera ray through raster (x, y) and its hit on the plane z = 0.
        let ndc = (2.0 * x / size as f64 - 1.0, 1.0 - 2.0 * y / size as f64);
        let d: [f64; 3] = std::array::from_fn(|k| {
            camera.forward[k] as f64 + ndc.0 * camera.right[k] as f64 + ndc.1 * camera.up[k] as f64
        });
        let t = -camera.position[2] as f64 / d[2];
        let (px, py) = (
            camera.position[0] as f64 + t * d[0],
            camera.position[1] as f64 + t * d[1],
        );
        let r2 = px * px + py * py + height * height;
        let cos = height / r2.sqrt();
        0.5 / std::f64::consts::PI * intensity * expected_falloff(cos, ci, co) * cos / r2
    };
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    let samples = (spp * frames) as f64;
    for y in 0..size {
        for x in 0..size {
            // The pixel's value and the variance of one jittered sample, from a 16 x 16 grid of
            // points in the pixel (the radiance is smooth at that scale: the ramp between the
            // cones spans several pixels).
            let sub = 16;
            let (mut mean_f, mut mean_f2) = (0.0, 0.0);
            for j in 0..sub {
                for i in 0..sub {
                    let f = radiance_at(
                        x as f64 + (i as f64 + 0.5) / sub as f64,
                        y as f64 + (j as f64 + 0.5) / sub as f64,
                    );
                    mean_f += f;
                    mean_f2 += f * f;
                }
            }
            let n = (sub * sub) as f64;
            let expected = mean_f / n;
            let se = ((mean_f2 / n - expected * expected).max(0.0) / samples).sqrt();
            let k = (y * size + x) as usize;
            let mean = r.image.mean[k][0] as f64;
            // Six standard errors of the jitter's noise, plus 0.5% for the 16² midpoint rule
            // (smooth within a pixel) and f32 rounding.
            let tolerance = 6.0 * se + 0.005 * expected + 1e-6;
            worst = worst.max((mean - expected).abs() / tolerance);
            assert!(
                (mean - expected).abs() <= tolerance,
                "{name} falloff, pixel ({x}, {y}): {mean}, analytic {expected} ± {se}"
            );
            checked += (expected > 0.0) as usize;
        }
    }
    eprintln!("spot ({name}): {checked} lit pixels, worst deviation {worst:.2} of the tolerance");
    assert!(checked > 100, "the cone lights much of the image ({checked} pixels)");
}

#[test]
fn khr_lights_punctual_spot_and_point_lights_import() {
    let spot = lightgraph_scenes::gltf::import(&data("lights_punctual/Spot/LightsSpot.gltf")).unwrap();
    assert_eq!(spot.lights.len(), 3);
    let Light::Spot {
        position,
        direction,
        intensity,
        inner_cone_degrees,
        outer_cone_degrees,
        falloff,
    } = &spot
        .lights
        .iter()
        .find(|l| matches!(l, Light::Spot { intensity, .. } if intensity[0] > 0.0))
        .unwrap()
    else {
        panic!("spot lights import as Spot: {:?}", spot.lights);
    };
    // SpotRed: node at (2, 5, 0) rotated -90 degrees about X, so its -Z axis points down -Y;
    // colour (0.8, 0, 0) × intensity 450; cones 0.314 and 0.524 radians.
    let close = |a: &[f32], b: &[f32], eps: f32| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= eps);
    assert!(close(position, &[2.0, 5.0, 0.0], 1e-6), "{position:?}");
    assert!(close(direction, &[0.0, -1.0, 0.0], 1e-6), "{direction:?}");
    assert!(close(intensity, &[360.0, 0.0, 0.0], 1e-3), "{intensity:?}");
    assert!((inner_cone_degrees - 18.0).abs() < 1e-4 && (outer_cone_degrees - 30.0).abs() < 1e-4);
    assert_eq!(
        *falloff,
        lightgraph_scenes::model::SpotFalloff::Smooth,
        "glTF's falloff"
    );
    // Every spot points at the plane y = 0, 30 degrees from the vertical.
    for l in &spot.lights {
        let Light::Spot { direction, .. } = l else {
            panic!("{l:?}")
        };
        let d = glam::Vec3::from_array(*direction);
        assert!((d.length() - 1.0).abs() < 1e-5 && d.y < -0.5, "{d:?}");
    }
    let point = lightgraph_scenes::gltf::import(&data("lights_punctual/Point/LightsPoint.gltf")).unwrap();
    assert_eq!(point.lights.len(), 3);
    assert!(point.lights.iter().all(|l| matches!(l, Light::Point { .. })));
}

#[test]
fn imported_spot_lights_light_the_plane_as_the_analytic_direct_illumination() {
    // The KHR_lights_punctual spots over their plane (albedo 0.8), seen from above; direct
    // light only. At each spot's centre the pixel must equal ρ/π Σ I falloff cos θ / r² over
    // the three spots (their cones overlap), averaged over the pixel.
    let text = "Scene(camera: (position: (0, 12, 0.01), look: Target((0, 0, 0)), up: (0, 0, -1), fov_degrees: 50.0),
        gltf: \"Spot/LightsSpot.gltf\", integrator: (max_path_length: 2))";
    let s = LoadedScene::parse("spots.ron", text, BvhKind::Bvh2, Some(&data("lights_punctual"))).unwrap();
    let (size, spp, frames) = (32u32, 4, 32);
    let r = render(&s, "pt", "NaivePTsk", (size, size), spp, frames, 5, &[]);
    let camera = lightgraph_scenes::CompiledScene::camera(&s.scene, size, size);
    let v3 = |a: [f32; 3]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (eye, forward, right, up) = (v3(camera.position), v3(camera.forward), v3(camera.right), v3(camera.up));
    // Direct radiance (RGB) at raster position (x, y).
    let radiance_at = |x: f64, y: f64| {
        let d = forward + (2.0 * x / size as f64 - 1.0) * right + (1.0 - 2.0 * y / size as f64) * up;
        let p = eye + d * (-eye.y / d.y);
        let mut sum = glam::DVec3::ZERO;
        for l in &s.scene.lights {
            let Light::Spot {
                position,
                direction,
                intensity,
                inner_cone_degrees,
                outer_cone_degrees,
                ..
            } = l
            else {
                panic!("{l:?}");
            };
            let to_p = p - v3(*position);
            let r2 = to_p.length_squared();
            let w = to_p / r2.sqrt();
            let f = falloff(
                w.dot(v3(*direction)),
                (*inner_cone_degrees as f64).to_radians().cos(),
                (*outer_cone_degrees as f64).to_radians().cos(),
            );
            sum += v3(*intensity) * (0.8 / std::f64::consts::PI * f * (-w.y) / r2);
        }
        sum
    };
    let mut lit = 0;
    for l in &s.scene.lights {
        let Light::Spot {
            position, direction, ..
        } = l
        else {
            continue;
        };
        // The pixel where the spot's axis meets the plane y = 0.
        let hit = v3(*position) + v3(*direction) * (-position[1] as f64 / direction[1] as f64);
        let v = (hit - eye) / (hit - eye).dot(forward);
        let (px, py) = (
            ((v.dot(right) / right.length_squared() + 1.0) * 0.5 * size as f64) as u32,
            ((1.0 - v.dot(up) / up.length_squared()) * 0.5 * size as f64) as u32,
        );
        let sub = 16;
        let mut expected = glam::DVec3::ZERO;
        for j in 0..sub {
            for i in 0..sub {
                expected += radiance_at(
                    px as f64 + (i as f64 + 0.5) / sub as f64,
                    py as f64 + (j as f64 + 0.5) / sub as f64,
                );
            }
        }
        expected /= (sub * sub) as f64;
        let k = (py * size + px) as usize;
        for c in 0..3 {
            let (mean, se) = (
                r.image.mean[k][c] as f64,
                (r.image.variance[k][c] as f64 / frames as f64).sqrt(),
            );
            // Six standard errors (the light pick and the jitter vary per sample; 128 samples)
            // and 0.5% for the midpoint rule over the pixel.
            assert!(
                (mean - expected[c]).abs() <= 6.0 * se + 0.005 * expected[c] + 1e-6,
                "pixel ({px}, {py}) channel {c}: {mean} ± {se}, analytic {}",
                expected[c]
            );
            lit += (expected[c] > 0.1) as usize;
        }
    }
    assert!(lit >= 3, "each spot lights its centre");
}

#[test]
fn environment_map_errors_name_the_file_and_the_asset_root() {
    let text = environment_scene("Environment(file: \"nowhere/sky.hdr\")");
    let root = Path::new("/tmp");
    let e = LoadedScene::parse("env.ron", &text, BvhKind::Bvh2, Some(root))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.starts_with("env.ron: ") && e.contains("'nowhere/sky.hdr'") && e.contains("asset root /tmp"),
        "{e}"
    );
    let e = LoadedScene::parse("env.ron", &text, BvhKind::Bvh2, None)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("'nowhere/sky.hdr'") && e.contains("no asset root"), "{e}");
    let two = environment_scene("Environment(file: \"a.hdr\"), Background(radiance: (1, 1, 1))");
    let e = lightgraph_scenes::parse_scene("two.ron", &two).unwrap_err().to_string();
    assert!(
        e.starts_with("two.ron:") && e.contains("at most one Background or Environment"),
        "{e}"
    );
    let root = environment_root("errors", "sky.exr", 2, 1, |_, _| [1.0; 3]);
    std::fs::write(root.join("bad.hdr"), b"#?RADIANCE\nnot an image").unwrap();
    let e = LoadedScene::parse(
        "env.ron",
        &environment_scene("Environment(file: \"bad.hdr\")"),
        BvhKind::Bvh2,
        Some(&root),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("bad.hdr: "), "{e}");
    let map = EnvironmentMap::load(&root.join("sky.exr")).unwrap();
    assert_eq!((map.width, map.height), (2, 1));
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_diffuse_sphere_under_a_constant_environment_map_is_albedo_times_its_radiance() {
    // A convex diffuse sphere (albedo 0.5) under a map of constant radiance L × scale 2:
    // every reflected path escapes, so the sphere shows 0.5 × 2 L and the rest 2 L, whatever
    // the mix of light sampling and BSDF sampling MIS makes (a wrong density in either
    // strategy's weight or estimate would bias it).
    let radiance = [0.4f32, 0.6, 0.8];
    let root = environment_root("constant", "flat.exr", 8, 4, |_, _| radiance);
    let text = environment_scene("Environment(file: \"flat.exr\", scale: 2.0, rotation_degrees: 10.0)");
    let s = LoadedScene::parse("env.ron", &text, BvhKind::Bvh2, Some(&root)).unwrap();
    std::fs::remove_dir_all(&root).unwrap();
    let r = render(&s, "pt", "NaivePTsk", (32, 32), 16, 16, 9, &[]);
    // The central 4 x 4 pixels see only the sphere (its image is 11 pixels wide); the corner
    // pixels see only the environment.
    let (mean, se, n) = region(&r.image, |x, y| (14..18).contains(&x) && (14..18).contains(&y));
    assert_eq!(n, 16);
    let (sky, _, _) = region(&r.image, |x, y| x < 4 && y < 4);
    for c in 0..3 {
        let expected = 0.5 * 2.0 * radiance[c] as f64;
        // Four standard errors of the region mean (from 16 independent frames per pixel),
        // which must itself be small enough (2%) to catch a bias of a few percent.
        assert!(
            se[c] < 0.02 * expected,
            "channel {c}: standard error {} too large",
            se[c]
        );
        assert!(
            (mean[c] - expected).abs() < 4.0 * se[c],
            "channel {c}: sphere {} ± {}, expected {expected}",
            mean[c],
            se[c]
        );
        assert!(
            (sky[c] - 2.0 * radiance[c] as f64).abs() < 1e-5,
            "channel {c}: sky {}",
            sky[c]
        );
    }
}

/// A small bright sphere over a diffuse floor, beside a large light of 2,500 times its power
/// hidden under the floor (tests/data/mitsuba/two-sphere-emitters.xml): the floor's radiance
/// is the small sphere's, ρ L (r / d)² cos θ at distance d and angle θ from the normal (the
/// irradiance of a uniformly emitting sphere wholly above the horizon), in every estimator
/// that picks lights. Mitsuba meshes emitting spheres: the small one's 65,024 triangles are
/// lights with shares of 10^-9 to 10^-8, which an alias table that rounded shares picked
/// about ten times too often; that made the floor 100-230% too bright in all four.
#[test]
fn a_small_emitter_beside_a_powerful_one_lights_as_the_analytic_sphere() {
    let scene = LoadedScene::from_mitsuba(&data("mitsuba/two-sphere-emitters.xml"), BvhKind::Bvh2).unwrap();
    let size = 32u32;
    let (center, radius, radiance, albedo) = ([1.0f64, 0.4, 1.0], 0.03f64, 901.8f64, 0.5f64);
    // The floor point each raster position sees (y = 0), and the floor's radiance there.
    let camera = lightgraph_scenes::CompiledScene::camera(&scene.scene, size, size);
    let at = |x: f64, y: f64| -> [f64; 3] {
        let ndc = (2.0 * x / size as f64 - 1.0, 1.0 - 2.0 * y / size as f64);
        let d: Vec<f64> = (0..3)
            .map(|i| (camera.forward[i] + ndc.0 as f32 * camera.right[i] + ndc.1 as f32 * camera.up[i]) as f64)
            .collect();
        let t = -camera.position[1] as f64 / d[1];
        [0, 1, 2].map(|i| camera.position[i] as f64 + t * d[i])
    };
    let floor_radiance = |p: [f64; 3]| {
        let v = [center[0] - p[0], center[1] - p[1], center[2] - p[2]];
        let d2 = v.iter().map(|c| c * c).sum::<f64>();
        albedo * radiance * radius * radius / d2 * (v[1] / d2.sqrt())
    };
    // Each pixel's expected value, 8 x 8 points across it; the pixels under the sphere
    // (within 0.08 of its foot, where it hides the floor) are left out.
    let mut pixels = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let c = at(x as f64 + 0.5, y as f64 + 0.5);
            if (c[0] - center[0]).hypot(c[2] - center[2]) < 0.08 {
                continue;
            }
            let mut e = 0.0;
            for k in 0..64 {
                let p = at(
                    x as f64 + (k % 8) as f64 / 8.0 + 1.0 / 16.0,
                    y as f64 + (k / 8) as f64 / 8.0 + 1.0 / 16.0,
                );
                e += floor_radiance(p) / 64.0;
            }
            pixels.push(((y * size + x) as usize, e));
        }
    }
    let expected = pixels.iter().map(|p| p.1).sum::<f64>() / pixels.len() as f64;
    // 16 batches: the batch means' spread gives the standard error (15 degrees of freedom);
    // four estimators tested at a family-wise 10^-3, two-sided.
    let batches = 16;
    let critical = StudentsT::new(0.0, 1.0, (batches - 1) as f64)
        .unwrap()
        .inverse_cdf(1.0 - 1e-3 / 8.0);
    for (graph, layout, frames) in [
        ("pt", "NaivePTsk", 256),
        ("lt", "LTsk", 128),
        ("bpt-lvc", "LVC-BPTsk", 64),
        ("vcm", "VCMsk", 64),
    ] {
        let means: Vec<f64> = render_batches(&scene, (graph, layout), (size, size), (batches, frames), 3, &[])
            .iter()
            .map(|batch| pixels.iter().map(|&(i, _)| batch[i][0]).sum::<f64>() / pixels.len() as f64)
            .collect();
        let mean = means.iter().sum::<f64>() / batches as f64;
        let se = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / ((batches - 1) * batches) as f64).sqrt();
        let t = (mean - expected) / se;
        eprintln!(
            "{graph}: floor {mean:.5} +- {se:.5}, analytic {expected:.5} ({:+.2}%, t = {t:.2})",
            100.0 * (mean / expected - 1.0)
        );
        assert!(se < 0.05 * expected, "{graph}: standard error {se} too large to test");
        assert!(
            t.abs() < critical,
            "{graph}: floor {mean} against {expected}, t = {t} beyond {critical}"
        );
    }
}
