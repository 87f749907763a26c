//! The numerical stress suite on lavapipe: every stress scene with every radiance estimator,
//! at 8x8 to 32x32 pixels and 32 frames of 1 sample per pixel (the tolerances are in
//! `lightgraph::stress`: Student-t limits from the spread of per-frame region means, exact
//! comparisons where no randomness can enter). The GPU version is `lightgraph stress --scale
//! 8 --spp 16` (docs/testing.md).

use crate::common::gpu;
use lightgraph::stress::{Runner, Settings, cases::cases, estimators};
use lightgraph_scenes::model::{Light, Look, Scene, Shape};
use lightgraph_scenes::parse_scene;

#[test]
fn every_stress_scene_keeps_its_invariant_with_every_estimator() {
    let mut runner = Runner::new(gpu(), Settings::default()).unwrap();
    let mut failed = Vec::new();
    for case in cases() {
        let mut rendered = 0;
        for graph in estimators() {
            let o = runner.run(&case, &graph);
            eprintln!("{} / {}: {} ({:.1} s)", o.scene, o.graph, o.statistic, o.seconds);
            if !o.passed {
                failed.push(format!("{} / {}: {}", o.scene, o.graph, o.failures.join("; ")));
            }
            rendered += usize::from(o.left_out.is_none());
        }
        // A case every estimator leaves out (media no estimator handles) would test nothing.
        assert!(rendered > 0, "no estimator rendered {}", case.scene);
    }
    assert!(failed.is_empty(), "stress invariants broken:\n{}", failed.join("\n"));
}

#[test]
fn every_stress_scene_file_has_a_case() {
    let names: Vec<&str> = cases().iter().map(|c| c.scene).collect();
    let files: Vec<String> = lightgraph::assets::scene_names()
        .into_iter()
        .filter(|(_, path)| path.starts_with("scenes/stress/"))
        .map(|(name, _)| name)
        .collect();
    assert!(files.len() >= 16, "{files:?}");
    for f in &files {
        assert!(names.contains(&f.as_str()), "scenes/stress/{f}.ron has no stress case");
    }
    for n in names {
        assert!(files.iter().any(|f| f == n), "stress case {n} has no scene file");
    }
}

fn scene(name: &str) -> Scene {
    let (file, text) = lightgraph::assets::scene_text(name).unwrap();
    parse_scene(&file, &text).unwrap()
}

fn close(a: f32, b: f64) -> bool {
    (a as f64 - b).abs() <= 1e-6 * b.abs().max(1e-30)
}

fn points(s: &Scene) -> Vec<[f32; 3]> {
    let mut p = vec![s.camera.as_ref().expect("stress scenes have a camera").position];
    for shape in &s.shapes {
        match shape {
            Shape::Triangle { vertices, .. } => p.extend(vertices),
            Shape::Quad { corners, .. } => p.extend(corners),
            Shape::Mesh { positions, .. } => p.extend(positions),
            Shape::Sphere { center, .. } => p.push(*center),
        }
    }
    p
}

fn emissions(s: &Scene) -> Vec<[f32; 3]> {
    let mut e: Vec<[f32; 3]> = s
        .shapes
        .iter()
        .filter_map(|shape| match shape {
            Shape::Triangle { emission, .. } | Shape::Quad { emission, .. } | Shape::Mesh { emission, .. } => *emission,
            Shape::Sphere { .. } => None,
        })
        .collect();
    e.extend(s.lights.iter().map(|l| match l {
        Light::Point { intensity, .. } => *intensity,
        Light::Directional { irradiance, .. } => *irradiance,
        Light::Background { radiance, .. } => *radiance,
        Light::Spot { intensity, .. } => *intensity,
        Light::Environment { scale, .. } => [*scale; 3],
    }));
    e
}

/// The derived stress scenes are their base scene with positions, light or media coefficients
/// scaled, and nothing else changed (they were written by a script from the base; this keeps
/// them so).
#[test]
fn derived_stress_scenes_are_scaled_copies_of_their_base() {
    for (name, base, position_scale, light_scale, media_scale) in [
        ("stress-cornell-scaled-1e-4", "cornell-diffuse", 1e-4, 1.0, 1.0),
        ("stress-cornell-scaled-1e4", "cornell-diffuse", 1e4, 1.0, 1.0),
        ("stress-area-light-1e-8", "cornell-diffuse", 1.0, 1e-8, 1.0),
        ("stress-area-light-1e8", "cornell-diffuse", 1.0, 1e8, 1.0),
        ("stress-point-light-1e-8", "cornell-glossy-point", 1.0, 1e-8, 1.0),
        ("stress-point-light-1e8", "cornell-glossy-point", 1.0, 1e8, 1.0),
        ("stress-media-scaled-1e-4", "media-sphere", 1e-4, 1.0, 1e4),
        ("stress-media-scaled-1e4", "media-sphere", 1e4, 1.0, 1e-4),
        ("stress-media-fog-1e-6", "media-fog", 1.0, 1.0, 1e-6),
    ] {
        let (s, b) = (scene(name), scene(base));
        let (ps, pb) = (points(&s), points(&b));
        assert_eq!(ps.len(), pb.len(), "{name}: shapes differ from {base}");
        for (x, y) in ps.iter().zip(&pb) {
            for k in 0..3 {
                assert!(
                    close(x[k], y[k] as f64 * position_scale),
                    "{name}: {x:?} is not {y:?} x {position_scale}"
                );
            }
        }
        for (x, y) in emissions(&s).iter().zip(&emissions(&b)) {
            for k in 0..3 {
                assert!(
                    close(x[k], y[k] as f64 * light_scale),
                    "{name}: light {x:?} is not {y:?} x {light_scale}"
                );
            }
        }
        let (c, cb) = (s.camera.as_ref().unwrap(), b.camera.as_ref().unwrap());
        let (Look::Forward(d), Look::Forward(db)) = (&c.look, &cb.look) else {
            panic!("{name}: the camera looks along a direction")
        };
        assert_eq!((d, c.up, c.fov_degrees), (db, cb.up, cb.fov_degrees), "{name}");
        assert_eq!(s.materials.len(), b.materials.len(), "{name}");
        assert_eq!(s.integrator.max_path_length, b.integrator.max_path_length, "{name}");
        assert_eq!(s.media.len(), b.media.len(), "{name}: media differ from {base}");
        for ((n, m), (nb, mb)) in s.media.iter().zip(&b.media) {
            let scattering = |m: &lightgraph_scenes::model::media::Medium| m.sigma_s.map(|v| v * m.scale);
            for (what, t, tb) in [
                ("sigma_t", m.sigma_t(), mb.sigma_t()),
                ("sigma_s", scattering(m), scattering(mb)),
            ] {
                for k in 0..3 {
                    assert!(
                        close(t[k], tb[k] as f64 * media_scale),
                        "{name}: medium {n}'s {what} {t:?} is not {nb}'s {tb:?} x {media_scale}"
                    );
                }
            }
            assert_eq!(
                format!("{:?}", m.phase),
                format!("{:?}", mb.phase),
                "{name}: medium {n}"
            );
        }
        assert_eq!(s.camera_medium, b.camera_medium, "{name}");
    }
}
