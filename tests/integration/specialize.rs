//! Scene-specialised kernels: the scene's features decide which WGSL code is generated, and a
//! specialised kernel renders the same image as one with every feature compiled in.

use crate::common::{gpu, kernel_sources, largest_relative_difference, program};
use lightgraph::run::{LayoutOverrides, LoadedScene, Session, SessionOptions, load_graph, load_scene};

/// The generated WGSL of every kernel of `pt` in NaivePTsk for `scene`.
fn kernel_source(scene: &LoadedScene, all_features: bool) -> String {
    kernel_sources("pt", "NaivePTsk", scene, &[], all_features)
}

/// Functions of features no Cornell box uses: textures, alpha masks, the microfacet BSDF,
/// environment maps, spot lights.
const NOT_IN_CORNELL: &[&str] = &[
    "fn texture_sample",
    "fn alpha_solid",
    "fn ggx_d",
    "fn pbr_setup",
    "fn pbr_sample",
    "fn env_lookup",
    "fn env_sample",
    "fn spot_falloff",
];

#[test]
fn cornell_kernels_contain_no_code_of_features_they_do_not_use() {
    for name in ["cornell-diffuse", "cornell-glossy-point", "cornell-mitsuba"] {
        let scene = load_scene(name).unwrap();
        let specialised = kernel_source(&scene, false);
        let general = kernel_source(&scene, true);
        for f in NOT_IN_CORNELL {
            assert!(
                !specialised.contains(f),
                "{name}: the specialised kernel contains '{f}'"
            );
            assert!(general.contains(f), "{name}: the all-features kernel lacks '{f}'");
        }
        assert!(
            specialised.len() < general.len(),
            "{name}: specialised {} bytes, all features {} bytes",
            specialised.len(),
            general.len()
        );
    }
    // The diffuse box has no Phong lobe, mirror or glass either.
    let diffuse = kernel_source(&load_scene("cornell-diffuse").unwrap(), false);
    for f in ["power_cos_pdf(cos_r", "fresnel_dielectric(b.fix.z"] {
        assert!(!diffuse.contains(f), "cornell-diffuse: the kernel contains '{f}'");
    }
}

#[test]
fn specialised_and_all_features_kernels_render_the_same_image() {
    let graph = load_graph("pt").unwrap();
    for name in ["cornell-glossy-point", "cornell-glossy-background", "cornell-diffuse"] {
        let scene = load_scene(name).unwrap();
        let image = |all_features: bool| {
            let options = SessionOptions {
                width: 24,
                height: 24,
                samples_per_frame: 2,
                seed: 7,
                constants: Default::default(),
                layout: LayoutOverrides {
                    all_features,
                    ..Default::default()
                },
            };
            let mut session = Session::new(gpu(), &graph, "NaivePTsk", &scene, options).unwrap();
            session.render_frames(2).unwrap();
            (session.image().unwrap(), session.counters.clone())
        };
        let (a, ca) = image(false);
        let (b, cb) = image(true);
        assert_eq!(ca, cb, "{name}: the kernels trace different rays");
        let worst = largest_relative_difference(&a, &b);
        assert!(
            worst < 1e-5,
            "{name}: specialised and all-features images differ by {worst:.2e}"
        );
    }
}

#[test]
fn only_scenes_with_thin_walled_transmission_compile_it_in() {
    let thin_code = "MATERIAL_THIN_WALLED) != 0u";
    for (material, thin) in [
        ("(pbr: (transmission: 1.0, thin_walled: true))", true),
        ("(pbr: (transmission: 1.0))", false),
        // Without transmission the flag changes nothing: no code for it.
        ("(pbr: (thin_walled: true))", false),
    ] {
        let scene = crate::bsdf::material_scene(material);
        let used = lightgraph_scenes::features::used(&scene.compiled);
        assert_eq!(used.contains("BSDF_THIN_WALLED"), thin, "{material}: {used:?}");
        let source = kernel_source(&scene, false);
        assert_eq!(source.contains(thin_code), thin, "{material}");
    }
}

#[test]
fn only_scenes_with_rough_plastic_read_its_tables() {
    // A rough plastic's kernels read its coating's table; a smooth plastic's and glTF's
    // materials' neither compile that code nor bind the tables.
    for (material, rough) in [
        ("(pbr: (roughness: 0.3, plastic: Some((nonlinear: false))))", true),
        ("(pbr: (roughness: 0.0, plastic: Some((nonlinear: false))))", false),
        ("(pbr: (roughness: 0.3))", false),
    ] {
        let scene = crate::bsdf::material_scene(material);
        let used = lightgraph_scenes::features::used(&scene.compiled);
        assert_eq!(used.contains("BSDF_ROUGH_PLASTIC"), rough, "{material}: {used:?}");
        let source = kernel_source(&scene, false);
        assert_eq!(
            source.contains("fn rough_plastic_transmittance"),
            rough,
            "{material}: the code"
        );
        let program = program("pt", "NaivePTsk", &scene, &[], false);
        let tables = program.plan.graph.resource_id("plastic_tables").unwrap();
        assert_eq!(
            program.resolved.used.contains(&tables),
            rough,
            "{material}: the binding"
        );
    }
}
