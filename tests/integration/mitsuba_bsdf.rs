//! Mitsuba's rough plastic's diffuse lobe on the GPU against its host tables
//! (`scenes/src/plastic.rs`): its values, and its albedo as the sampled weights' mean.

use crate::bsdf::{Part, directions, eval, material_scene, mean_weight, sample};
use lightgraph::run::LoadedScene;
use lightgraph_scenes::model::Microfacet;
use lightgraph_scenes::plastic::CoatingTable;
use std::f64::consts::PI;

/// Rough plastics as RON materials: distribution, perceptual roughness, index, nonlinear.
const PLASTICS: [(Microfacet, f32, f32, bool); 3] = [
    (Microfacet::Beckmann, 0.3, 1.5, false),
    (Microfacet::Ggx, 0.6, 2.2, true),
    (Microfacet::Beckmann, 1.0, 1.2, false),
];
const BASE: [f64; 3] = [0.2, 0.5, 0.8];

fn plastic_scene(distribution: Microfacet, roughness: f32, ior: f32, nonlinear: bool) -> LoadedScene {
    material_scene(&format!(
        "(pbr: (base_color: ({}, {}, {}), roughness: {roughness}, ior: {ior}, distribution: {distribution:?}, \
         masking: Separable, plastic: Some((nonlinear: {nonlinear}))))",
        BASE[0], BASE[1], BASE[2]
    ))
}

/// The diffuse lobe's reflectance, base / (1 - R_int) / eta^2 (nonlinear: base / (1 - base
/// R_int) / eta^2), from the host's table.
fn reflectance(table: &CoatingTable, nonlinear: bool) -> [f64; 3] {
    let r = table.internal_reflectance;
    BASE.map(|b| b * table.inv_eta2 / (1.0 - if nonlinear { b * r } else { r }))
}

#[test]
fn the_rough_plastic_diffuse_lobe_on_the_gpu_is_the_host_tables() {
    // The WGSL diffuse part (`bsdf_diffuse_part`) against the host's formula with its table:
    // its value reflectance T(cos_i) T(cos_o) / pi at 48 directions from each of three, to
    // f32 rounding (1e-5); its albedo, the mean of the weights f cos / pdf of 10^5 samples,
    // reflectance T(cos_i) H (H the hemispherical transmittance) within 4 standard errors;
    // and its continuation, that albedo's largest channel, to f32 rounding.
    for (distribution, roughness, ior, nonlinear) in PLASTICS {
        let what = format!("{distribution:?} roughness {roughness} ior {ior} nonlinear {nonlinear}");
        let scene = plastic_scene(distribution, roughness, ior, nonlinear);
        let table = CoatingTable::new((roughness as f64).powi(2), ior as f64, distribution).unwrap();
        let reflectance = reflectance(&table, nonlinear);
        for fix in [[0.0f32, 0.0, 1.0], [0.6, 0.2, 0.7], [0.97, 0.0, 0.05]] {
            let cos_i = fix[2] as f64 / (fix.iter().map(|x| (x * x) as f64).sum::<f64>()).sqrt();
            let t_i = table.transmittance_at(cos_i);
            let gens = directions(48, 57, 1.0);
            for (out, (f, _)) in gens.iter().zip(eval(&scene, fix, Part::Diffuse, &gens)) {
                let through = t_i * table.transmittance_at(out[2] as f64) / PI;
                for c in 0..3 {
                    let want = reflectance[c] * through;
                    assert!(
                        (f[c] as f64 - want).abs() <= 1e-5 * want + 1e-9,
                        "{what}, fix {fix:?}, gen {out:?}: f {} where the host's table gives {want}",
                        f[c]
                    );
                }
            }
            let sampled = sample(&scene, fix, false, Part::Diffuse, 100_000);
            let (mean, se) = mean_weight(&sampled);
            let albedo = reflectance.map(|r| r * t_i * table.hemispherical);
            for c in 0..3 {
                assert!(
                    (mean[c] - albedo[c]).abs() <= 4.0 * se[c] + 1e-6,
                    "{what}, fix {fix:?}: albedo {} +- {} where the host's table gives {}",
                    mean[c],
                    se[c],
                    albedo[c]
                );
            }
            let bound = albedo.iter().copied().fold(0.0, f64::max);
            assert!(
                (sampled.continuation as f64 - bound).abs() <= 1e-5 * bound,
                "{what}, fix {fix:?}: continuation {} where the albedo is {bound}",
                sampled.continuation
            );
        }
    }
}
