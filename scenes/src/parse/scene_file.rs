//! RON scene files: parsed into the scene model and validated, each error at the file's line
//! and column.

use crate::error::SceneError;
use crate::model::checks::{check_fov, check_lights};
use crate::model::enclosure::check_enclosures;
use crate::model::media::{check_media, load_grids};
use crate::model::{Scene, Shape, placement};

fn locate(text: &str, needle: &str) -> Option<(usize, usize)> {
    let offset = text.find(needle)?;
    let before = &text[..offset];
    Some((
        before.matches('\n').count() + 1,
        before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1,
    ))
}

/// Reads the density grids of the media of `scene`, parsed from `text` of `file`, with
/// `read` (given each grid's file as the scene names it); an error is at the medium.
pub fn read_grids(
    scene: &mut Scene,
    file: &str,
    text: &str,
    read: impl Fn(&str) -> Result<Vec<u8>, String>,
) -> Result<(), SceneError> {
    load_grids(scene, read).map_err(|(needle, message)| SceneError {
        file: file.to_string(),
        at: locate(text, &needle),
        message,
    })
}

/// Parses and validates the RON scene `text` of `file`.
pub fn parse_scene(file: &str, text: &str) -> Result<Scene, SceneError> {
    let scene: Scene = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| SceneError {
            file: file.to_string(),
            at: Some((e.span.start.line, e.span.start.col)),
            message: e.code.to_string(),
        })?;
    let err = |needle: &str, message: String| SceneError {
        file: file.to_string(),
        at: locate(text, needle),
        message,
    };
    // A glTF asset or a Mitsuba file brings shapes, lights and maybe a camera.
    let imports = scene.gltf.is_some() || scene.mitsuba.is_some();
    if scene.gltf.is_some() && scene.mitsuba.is_some() {
        return Err(err(
            "mitsuba",
            "the scene has both a glTF asset and a Mitsuba file; keep one".into(),
        ));
    }
    if scene.shapes.is_empty() && !imports {
        return Err(err("shapes", "the scene is empty: it has no shapes".into()));
    }
    for shape in &scene.shapes {
        let material = shape.material();
        if !scene.materials.contains_key(material) {
            let known: Vec<&str> = scene.materials.keys().map(|s| s.as_str()).collect();
            return Err(err(
                &format!("\"{material}\""),
                format!("unknown material '{material}' (materials: {})", known.join(", ")),
            ));
        }
        if let Shape::Sphere { radius, .. } = shape
            && (*radius <= 0.0 || !radius.is_finite())
        {
            return Err(err("Sphere", format!("sphere radius {radius} is not positive")));
        }
    }
    let emissive = scene.shapes.iter().any(Shape::emits);
    if !emissive && scene.lights.is_empty() && !imports {
        return Err(err(
            "lights",
            "the scene has no light: add an emissive shape or a light (Point, Directional, Background)".into(),
        ));
    }
    check_lights(&scene.lights).map_err(|(needle, message)| err(needle, message))?;
    check_media(&scene).map_err(|(needle, message)| err(&needle, message))?;
    check_enclosures(&scene).map_err(|(needle, message)| err(&needle, message))?;
    if !scene.gltf_instances.is_empty() && scene.gltf.is_none() {
        return Err(err(
            "gltf_instances",
            "gltf_instances places copies of a glTF asset, but the scene has none (gltf: \"...\")".into(),
        ));
    }
    placement::check(&scene.gltf_instances).map_err(|(needle, message)| err(needle, message))?;
    let (w, h) = scene.resolution;
    if w == 0 || h == 0 {
        return Err(err("resolution", "resolution must be at least 1x1".into()));
    }
    match (&scene.camera, &scene.gltf_camera, &scene.gltf) {
        (Some(camera), None, _) => check_fov(camera.fov_degrees).map_err(|e| err("fov_degrees", e))?,
        (None, Some(_), Some(_)) => {}
        (Some(_), Some(_), _) => {
            return Err(err(
                "gltf_camera",
                "the scene has both a camera and a gltf_camera; keep one".into(),
            ));
        }
        (None, Some(_), None) => {
            return Err(err(
                "gltf_camera",
                "gltf_camera needs a glTF asset (gltf: \"...\")".into(),
            ));
        }
        (None, None, _) if scene.mitsuba.is_some() => {}
        (None, None, _) => {
            return Err(err(
                "Scene",
                "the scene has no camera: add camera: (position: .., look: .., up: .., fov_degrees: ..), or gltf_camera: Index(0) or Name(\"...\") with a glTF asset".into(),
            ));
        }
    }
    if scene.integrator.max_path_length == 0 {
        return Err(err("max_path_length", "max_path_length must be at least 1".into()));
    }
    Ok(scene)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) const BASE: &str = r#"Scene(
    camera: (position: (0.0, -4.0, 0.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 0.0, 1.0), fov_degrees: 40.0),
    materials: { "m": (diffuse: (0.5, 0.5, 0.5)) },
    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: "m")],
    lights: [Point(position: (0.0, -2.0, 2.0), intensity: (1.0, 1.0, 1.0))],
)"#;

    fn error(text: &str) -> String {
        parse_scene("s.ron", text)
            .expect_err("the scene is refused")
            .to_string()
    }

    #[test]
    fn invalid_scenes_are_refused_with_a_location() {
        let e = error(&BASE.replace("material: \"m\")", "material: \"n\")"));
        assert!(e.starts_with("s.ron:4:") && e.contains("unknown material 'n'"), "{e}");
        let e = error(&BASE.replace(
            "lights: [Point(position: (0.0, -2.0, 2.0), intensity: (1.0, 1.0, 1.0))],",
            "",
        ));
        assert!(e.contains("no light"), "{e}");
        let e = error(&BASE.replace(
            "shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: \"m\")]",
            "shapes: []",
        ));
        assert!(e.contains("empty"), "{e}");
        let e = error(&BASE.replace("radius: 1.0", "radius: -1.0"));
        assert!(e.contains("radius"), "{e}");
        let e = error(&BASE.replace("fov_degrees: 40.0", "fov_degrees: 40.0,,"));
        assert!(e.starts_with("s.ron:2:"), "{e}");
        // Media: bad coefficients and phases, unknown names, null boundaries with lobes.
        let media = |medium: &str, material: &str| {
            BASE.replace(
                "materials: { \"m\": (diffuse: (0.5, 0.5, 0.5)) },",
                &format!("media: {{ \"fog\": {medium} }},\n    materials: {{ \"m\": {material} }},"),
            )
        };
        let e = error(&media(
            "(sigma_s: (1.0, -1.0, 1.0))",
            "(null: true, interior: Some(\"fog\"))",
        ));
        assert!(
            e.starts_with("s.ron:3:") && e.contains("medium 'fog'") && e.contains("sigma_s"),
            "{e}"
        );
        let e = error(&media(
            "(phase: HenyeyGreenstein(g: 1.0))",
            "(null: true, interior: Some(\"fog\"))",
        ));
        assert!(e.starts_with("s.ron:3:") && e.contains("(-1, 1)"), "{e}");
        let e = error(&media(
            "(sigma_s: (1.0, 1.0, 1.0))",
            "(null: true, exterior: Some(\"smoke\"))",
        ));
        assert!(
            e.starts_with("s.ron:4:") && e.contains("unknown medium 'smoke' (media: fog)"),
            "{e}"
        );
        let e = error(&media(
            "(sigma_s: (1.0, 1.0, 1.0))",
            "(null: true, diffuse: (0.5, 0.5, 0.5))",
        ));
        assert!(e.starts_with("s.ron:4:") && e.contains("null"), "{e}");
        let e = error(
            &media("(sigma_s: (1.0, 1.0, 1.0))", "(diffuse: (0.5, 0.5, 0.5))")
                .replace("    lights:", "    camera_medium: Some(\"mist\"),\n    lights:"),
        );
        assert!(
            e.contains("camera_medium") && e.contains("unknown medium 'mist'"),
            "{e}"
        );
        // Spheres do not emit: a field a shape does not have is refused, not ignored.
        let e = error(&BASE.replace("material: \"m\")", "material: \"m\", emission: (1.0, 1.0, 1.0))"));
        assert!(e.starts_with("s.ron:4:") && e.contains("emission"), "{e}");
    }

    #[test]
    fn the_media_test_scene_parses_and_compiles() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/scenes/media-boundaries.ron");
        let scene = parse_scene(path, &std::fs::read_to_string(path).unwrap()).unwrap();
        crate::model::checks::check_resolved(&scene).unwrap();
        assert_eq!(scene.media.len(), 3);
        assert_eq!(scene.materials["smoke-ball"].exterior.as_deref(), Some("fog"));
        crate::pack::compile::CompiledScene::new(&scene).unwrap();
    }

    #[test]
    fn the_media_example_of_the_media_guide_parses_and_encloses_its_media() {
        let guide = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/media.md")).unwrap();
        let block = guide
            .split("```ron")
            .skip(1)
            .find(|b| b.contains("camera_medium"))
            .and_then(|b| b.split("```").next())
            .expect("a RON example of media in docs/media.md");
        // Its placeholder line for the camera, shapes and lights, filled in.
        let rest = "    camera: (position: (0.0, 0.0, 3.0), look: Target((0.0, 0.0, 0.0)), up: (0.0, 1.0, 0.0), fov_degrees: 40.0),\n\
                    shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 10.0, material: \"smoke-boundary\"), \
                    Sphere(center: (0.0, 0.0, 0.0), radius: 1.0, material: \"milk-glass\")],\n\
                    lights: [Point(position: (0.0, 2.0, 0.0), intensity: (1.0, 1.0, 1.0))],";
        let text: Vec<&str> = block
            .lines()
            .map(|line| if line.contains("as usual") { rest } else { line })
            .collect();
        let scene = parse_scene("media.md", &text.join("\n")).unwrap();
        crate::model::checks::check_resolved(&scene).unwrap();
        assert_eq!(scene.camera_medium.as_deref(), Some("fog"));
        assert_eq!(scene.materials["milk-glass"].interior.as_deref(), Some("smoke"));
        assert!(scene.materials["smoke-boundary"].null);
    }

    #[test]
    fn media_parse_and_an_open_boundary_is_refused_at_its_material() {
        let with_media = |shape: &str| {
            BASE.replace(
                "materials: {",
                "media: { \"fog\": (sigma_a: (0.1, 0.1, 0.1), sigma_s: (0.5, 0.5, 0.5), phase: HenyeyGreenstein(g: 0.3)) },\n    \
                 camera_medium: \"fog\",\n    materials: {\n        \"box\": (null: true, interior: \"fog\"),",
            )
            .replace("shapes: [", &format!("shapes: [{shape}, "))
        };
        let scene = parse_scene(
            "s.ron",
            &with_media("Sphere(center: (0.0, 0.0, 0.0), radius: 5.0, material: \"box\")"),
        )
        .unwrap();
        assert_eq!(scene.camera_medium.as_deref(), Some("fog"));
        assert_eq!(scene.media["fog"].phase.g(), 0.3);
        assert_eq!(scene.materials["box"].interior.as_deref(), Some("fog"));
        let e = error(&with_media(
            "Quad(corners: ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)), material: \"box\")",
        ));
        assert!(
            e.starts_with("s.ron:6:9: medium 'fog' is not enclosed") && e.contains("material 'box'"),
            "{e}"
        );
    }

    #[test]
    fn a_grid_medium_reads_its_vol_file_and_bad_grids_are_errors_at_the_medium() {
        let with_grid = |medium: &str| {
            BASE.replace(
                "materials: {",
                &format!("media: {{\n        \"cloud\": ({medium}),\n    }},\n    materials: {{\n        \"box\": (null: true, interior: \"cloud\"),"),
            )
            .replace("shapes: [", "shapes: [Sphere(center: (0.0, 0.0, 0.0), radius: 5.0, material: \"box\"), ")
        };
        let grid = "sigma_s: (0.5, 0.5, 0.5), sigma_a: (0.5, 0.5, 0.5), grid: (file: \"c.vol\", filter: Nearest)";
        let bytes = crate::model::grid::tests::vol_bytes([1, 1, 2], &[0.5, 2.0]);
        let text = with_grid(grid);
        let mut scene = parse_scene("s.ron", &text).unwrap();
        read_grids(&mut scene, "s.ron", &text, |name| {
            assert_eq!(name, "c.vol");
            Ok(bytes.clone())
        })
        .unwrap();
        let read = scene.media["cloud"].grid.as_ref().unwrap();
        assert_eq!(read.volume.as_ref().unwrap().data, [0.5, 2.0]);
        assert_eq!(read.filter, crate::model::grid::GridFilter::Nearest);
        // A file that cannot be read, or is no grid: the error is at the medium, naming it and the file.
        let mut scene = parse_scene("s.ron", &text).unwrap();
        let e = read_grids(&mut scene, "s.ron", &text, |_| Ok(b"VOL\x03".to_vec()))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.ron:4:9: medium 'cloud': grid 'c.vol': 4 bytes: shorter than a .vol header"),
            "{e}"
        );
        let e = read_grids(&mut scene, "s.ron", &text, |_| Err("c.vol not found".into()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("medium 'cloud': grid 'c.vol': c.vol not found"), "{e}");
        // A coloured extinction cannot be delta-tracked by one distance.
        let e = error(&with_grid(
            &grid.replace("sigma_a: (0.5, 0.5, 0.5)", "sigma_a: (0.5, 0.1, 0.5)"),
        ));
        assert!(
            e.starts_with("s.ron:4:9: medium 'cloud': a density grid needs a grey extinction"),
            "{e}"
        );
    }
}
