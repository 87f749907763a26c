//! Participating media: `homogeneous` media, with Mitsuba 3's extinction `sigma_t` (default 1)
//! and single-scattering `albedo` (default 0.75) or Mitsuba 0.6's `sigma_a` and `sigma_s`,
//! times `scale`, and their nested phase function (`isotropic`, the default, or `hg` with
//! `g`, default 0.8), each converted once and named by its id (`mitsuba:LINE:COLUMN` when
//! anonymous); `heterogeneous` media with a `sigma_t` grid volume (the `grid` submodule). Other media and
//! phase functions, textured or volume coefficients elsewhere and bad values are errors at the
//! element.

mod grid;

use super::xml::{Color, Context, Props, Result};
use crate::model::Rgb;
use crate::model::media::{Medium, Phase, check_medium};
use roxmltree::Node;
use std::collections::BTreeMap;

/// Converts medium elements, each once.
#[derive(Default)]
pub struct Media {
    /// Media by name: a medium's id, or `mitsuba:LINE:COLUMN` for an anonymous one.
    pub media: BTreeMap<String, Medium>,
}

impl Media {
    /// The name of the medium of `node` (a `<medium>` element), converting it on first use.
    pub fn name_of<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<String> {
        let name = ctx.name(node);
        if !self.media.contains_key(&name) {
            let medium = medium(ctx, node)?;
            self.media.insert(name.clone(), medium);
        }
        Ok(name)
    }
}

/// The medium named `slot` (`interior`, `exterior`) of a shape: a nested `<medium>` or a
/// `<ref>` to one.
pub fn slot<'a, 'i>(ctx: &Context<'a, 'i>, props: &Props<'a, 'i>, slot: &str) -> Result<Option<Node<'a, 'i>>> {
    let Some(node) = props.get(slot) else { return Ok(None) };
    let target = ctx.resolve(node)?;
    if !target.has_tag_name("medium") {
        return Err(ctx.error(node, format!("the {slot} must be a <medium>")));
    }
    Ok(Some(target))
}

/// A `<medium>` element as a [`Medium`].
fn medium<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Medium> {
    if !node.has_tag_name("medium") {
        return Err(ctx.error(node, "expected a <medium>"));
    }
    let kind = ctx.plugin_type(node)?;
    match kind.as_str() {
        "homogeneous" => {}
        "heterogeneous" => return grid::heterogeneous(ctx, node),
        _ => {
            return Err(ctx.error(
                node,
                format!(
                    "the medium type '{kind}' is not supported (issue 59): only homogeneous and heterogeneous media"
                ),
            ));
        }
    }
    let props = Props::new(node);
    if let Some(preset) = props.get("material") {
        return Err(ctx.error(
            preset,
            "medium material presets are not supported: give sigma_a and sigma_s, or sigma_t and albedo",
        ));
    }
    let [sigma_a, sigma_s, sigma_t, albedo] =
        ["sigma_a", "sigma_s", "sigma_t", "albedo"].map(|name| constant(ctx, &props, name));
    let (sigma_a, sigma_s) = match ((sigma_a?, sigma_s?), (sigma_t?, albedo?)) {
        ((Some((_, a)), Some((_, s))), (None, None)) => (a, s),
        ((None, None), (t, albedo)) => {
            let t = t.map_or([1.0; 3], |(_, t)| t);
            if let Some(bad) = t.iter().find(|c| !(c.is_finite() && **c >= 0.0)) {
                return Err(ctx.error(
                    node,
                    format!("sigma_t {t:?}: {bad} is not a coefficient (finite, not negative)"),
                ));
            }
            let albedo = match albedo {
                None => [0.75; 3],
                Some((at, value)) if value.iter().any(|c| !(0.0..=1.0).contains(c)) => {
                    return Err(ctx.error(at, format!("the albedo {value:?} is not within [0, 1]")));
                }
                Some((_, value)) => value,
            };
            (
                std::array::from_fn(|c| t[c] * (1.0 - albedo[c])),
                std::array::from_fn(|c| t[c] * albedo[c]),
            )
        }
        ((Some(_), None) | (None, Some(_)), _) => {
            return Err(ctx.error(node, "give both sigma_a and sigma_s (or sigma_t and albedo)"));
        }
        _ => {
            return Err(ctx.error(node, "sigma_a and sigma_s exclude sigma_t and albedo: give one pair"));
        }
    };
    let (scale, phase) = scale_and_phase(ctx, node, &props)?;
    let m = Medium {
        sigma_a,
        sigma_s,
        scale,
        phase,
        grid: None,
    };
    check_medium(&m).map_err(|e| ctx.error(node, e))?;
    props.finish(ctx);
    Ok(m)
}

/// A medium's `scale` (Mitsuba 0.6: `density_multiplier`; default 1) and its nested phase
/// function (default isotropic); the properties of how Mitsuba samples distances and lights,
/// which leave the expected image as it is, are read.
pub fn scale_and_phase<'a, 'i>(
    ctx: &mut Context<'a, 'i>,
    node: Node<'a, 'i>,
    props: &Props<'a, 'i>,
) -> Result<(f32, Phase)> {
    let scale = match (props.float(ctx, "scale")?, props.float(ctx, "density_multiplier")?) {
        (Some(s), _) | (None, Some(s)) => s,
        (None, None) => 1.0,
    };
    for harmless in ["sample_emitters", "strategy"] {
        props.get(harmless);
    }
    let phase = match props.nested(ctx, "phase")?[..] {
        [] => Phase::Isotropic,
        [one] => phase(ctx, one)?,
        _ => return Err(ctx.error(node, "a medium has one phase function")),
    };
    Ok((scale, phase))
}

/// The constant coefficient `name` (`<rgb>`, `<spectrum>`, `<float>`, ...) and its element; a
/// texture or a volume is an error.
pub fn constant<'a, 'i>(
    ctx: &mut Context<'a, 'i>,
    props: &Props<'a, 'i>,
    name: &str,
) -> Result<Option<(Node<'a, 'i>, Rgb)>> {
    let Some(node) = props.get(name) else { return Ok(None) };
    let target = ctx.resolve(node)?;
    if target.has_tag_name("volume") || target.has_tag_name("texture") {
        return Err(ctx.error(
            target,
            format!("a spatially varying {name} is not supported yet (issue 59): give a constant"),
        ));
    }
    match props.color(ctx, name)? {
        Some(Color::Rgb(c)) => Ok(Some((node, c))),
        _ => Err(ctx.error(node, format!("expected a colour or a number for '{name}'"))),
    }
}

/// A `<phase>` element: `isotropic` or `hg` (Henyey-Greenstein, `g` default 0.8, as Mitsuba's).
fn phase(ctx: &mut Context, node: Node) -> Result<Phase> {
    let kind = ctx.plugin_type(node)?;
    let props = Props::new(node);
    let phase = match kind.as_str() {
        "isotropic" => Phase::Isotropic,
        "hg" => {
            let g = props.float(ctx, "g")?.unwrap_or(0.8);
            if g.abs() >= 1.0 {
                let at = props.get("g").unwrap_or(node);
                return Err(ctx.error(at, format!("g {g} is not within (-1, 1)")));
            }
            Phase::HenyeyGreenstein { g }
        }
        _ => {
            return Err(ctx.error(
                node,
                format!("the phase function '{kind}' is not supported (issue 59): only isotropic and hg"),
            ));
        }
    };
    props.finish(ctx);
    Ok(phase)
}

#[cfg(test)]
mod tests {
    use super::super::tests::data;
    use super::super::{Imported, load, parse};
    use crate::error::SceneError;
    use crate::model::Shape;
    use crate::model::media::{Medium, Phase};
    use std::path::Path;

    /// An isotropic medium.
    fn isotropic(sigma_a: [f32; 3], sigma_s: [f32; 3], scale: f32) -> Medium {
        Medium {
            sigma_a,
            sigma_s,
            scale,
            phase: Phase::Isotropic,
            grid: None,
        }
    }

    /// Imports a scene of format `version` whose body is `body`, lit by a constant emitter.
    fn import(version: &str, body: &str) -> Result<Imported, SceneError> {
        let text = format!("<scene version=\"{version}\">\n{body}\n<emitter type=\"constant\"/></scene>");
        parse("t.xml", &data(""), &text)
    }

    /// The error of importing `body` (format 3.0.0), as it is shown.
    fn error(body: &str) -> String {
        import("3.0.0", body).expect_err("refused").to_string()
    }

    #[test]
    fn the_test_scene_imports_its_media_boundaries_and_the_cameras_medium() {
        let imported = load(&data("media.xml")).unwrap();
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
        let scene = &imported.scene;
        assert_eq!(scene.camera_medium.as_deref(), Some("fog"));
        assert_eq!(scene.media["fog"], isotropic([0.1; 3], [0.1; 3], 1.0));
        assert_eq!(scene.media["juice"], isotropic([0.5, 2.0, 4.0], [0.0; 3], 2.0));
        // The nested medium of the second sphere (line 48), named by its position.
        let smoke = &scene.media["mitsuba:48:3"];
        assert_eq!(smoke.phase, Phase::HenyeyGreenstein { g: 0.6 });
        assert!((smoke.sigma_s[0] - 2.7).abs() < 1e-6 && (smoke.sigma_a[0] - 0.3).abs() < 1e-6);
        let names: Vec<&str> = scene.shapes.iter().map(Shape::material).collect();
        assert_eq!(
            names,
            [
                "boundary (interior: fog)",
                "mitsuba:42:3",
                "boundary (interior: mitsuba:48:3, exterior: fog)",
                "glass (interior: juice, exterior: fog)"
            ]
        );
        let m = |name: &str| &scene.materials[name];
        let fog_box = m("boundary (interior: fog)");
        assert!(fog_box.null && fog_box.interior.as_deref() == Some("fog") && fog_box.exterior.is_none());
        let glass = m("glass (interior: juice, exterior: fog)");
        assert_eq!(glass.pbr.as_ref().unwrap().transmission, 1.0);
        assert_eq!(
            (glass.interior.as_deref(), glass.exterior.as_deref(), glass.null),
            (Some("juice"), Some("fog"), false)
        );
        assert!(m("boundary").null, "the bsdf itself stays as it is");
        crate::pack::compile::CompiledScene::new(scene).unwrap();
    }

    #[test]
    fn the_fidelity_suites_media_scenes_import_without_warnings() {
        // Mitsuba 3's own scenes of media (bench/peers/fidelity, rendered there by volpath).
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench/peers/fidelity/scenes");
        let mut scenes: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("media-"))
            .collect();
        scenes.sort();
        assert!(scenes.len() >= 6, "{scenes:?}");
        for path in &scenes {
            let imported = load(path).unwrap();
            assert!(
                imported.warnings.is_empty(),
                "{}: {:?}",
                path.display(),
                imported.warnings
            );
            assert!(!imported.scene.media.is_empty(), "{}", path.display());
        }
        // The fog around the camera: sigma_t 0.15 of albedo 0.8.
        let fog = load(&dir.join("media-fog-camera.xml")).unwrap().scene;
        assert_eq!(fog.camera_medium.as_deref(), Some("fog"));
        let m = &fog.media["fog"];
        assert!(
            (m.sigma_s[0] - 0.12).abs() < 1e-6 && (m.sigma_a[0] - 0.03).abs() < 1e-6,
            "{m:?}"
        );
    }

    #[test]
    fn mitsuba_0_6_coefficients_and_boundaries_without_a_bsdf() {
        // Mitsuba 0.6: sigmaA and sigmaS; a shape with a medium and no bsdf is index-matched.
        let body = "<medium type=\"homogeneous\" id=\"m\"><rgb name=\"sigmaA\" value=\"0.1 0.2 0.3\"/>\
                    <float name=\"sigmaS\" value=\"0.5\"/><float name=\"scale\" value=\"10\"/></medium>\
                    <shape type=\"sphere\"><ref name=\"interior\" id=\"m\"/></shape>";
        let scene = import("0.6.0", body).unwrap().scene;
        assert_eq!(scene.media["m"], isotropic([0.1, 0.2, 0.3], [0.5; 3], 10.0));
        let material = scene.shapes[0].material();
        assert_eq!(material, "mitsuba:null (interior: m)");
        assert!(scene.materials[material].null);
        // Mitsuba 3 gives it its default diffuse, and a medium its default coefficients.
        let body =
            "<medium type=\"homogeneous\" id=\"m\"/><shape type=\"sphere\"><ref name=\"interior\" id=\"m\"/></shape>";
        let scene = import("3.0.0", body).unwrap().scene;
        let m = &scene.materials[scene.shapes[0].material()];
        assert_eq!((m.null, m.diffuse, m.interior.as_deref()), (false, [0.5; 3], Some("m")));
        assert_eq!(
            (scene.media["m"].sigma_a, scene.media["m"].sigma_s),
            ([0.25; 3], [0.75; 3])
        );
    }

    #[test]
    fn unsupported_media_and_bad_values_are_errors_at_their_element() {
        let sphere = "<shape type=\"sphere\"><ref name=\"interior\" id=\"m\"/></shape>";
        let cases = [
            (
                "<medium type=\"heterogeneous\" id=\"m\"/>",
                "t.xml:2:1: <medium type=\"heterogeneous\" id=\"m\">: a heterogeneous medium needs a sigma_t gridvolume",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\"><float name=\"sigma_t\" value=\"-1\"/></medium>",
                "t.xml:2:1: <medium type=\"homogeneous\" id=\"m\">: sigma_t [-1.0, -1.0, -1.0]",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\">\n<rgb name=\"albedo\" value=\"0.5 1.5 0.5\"/></medium>",
                "t.xml:3:1: <rgb name=\"albedo\">: the albedo [0.5, 1.5, 0.5] is not within [0, 1]",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\"><rgb name=\"sigma_a\" value=\"-1\"/><rgb name=\"sigma_s\" value=\"1\"/></medium>",
                "t.xml:2:1: <medium type=\"homogeneous\" id=\"m\">: sigma_a [-1.0, -1.0, -1.0] must be finite and not negative",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\"><phase type=\"hg\">\n<float name=\"g\" value=\"1\"/></phase></medium>",
                "t.xml:3:1: <float name=\"g\">: g 1 is not within (-1, 1)",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\">\n<phase type=\"rayleigh\"/></medium>",
                "t.xml:3:1: <phase type=\"rayleigh\">: the phase function 'rayleigh' is not supported",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\">\n<volume type=\"gridvolume\" name=\"albedo\"/></medium>",
                "t.xml:3:1: <volume type=\"gridvolume\" name=\"albedo\">: a spatially varying albedo is not supported yet",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\"><float name=\"sigma_a\" value=\"1\"/></medium>",
                "give both sigma_a and sigma_s",
            ),
            (
                "<medium type=\"homogeneous\" id=\"m\"><float name=\"sigma_a\" value=\"1\"/><float name=\"sigma_s\" value=\"1\"/>\
                 <float name=\"albedo\" value=\"1\"/></medium>",
                "exclude sigma_t and albedo",
            ),
            ("<bsdf type=\"diffuse\" id=\"m\"/>", "the interior must be a <medium>"),
        ];
        for (medium, expected) in cases {
            let e = error(&format!("{medium}{sphere}"));
            assert!(e.contains(expected), "{medium}:\n{e}\nlacks\n{expected}");
        }
    }

    #[test]
    fn an_open_boundary_is_refused_naming_the_medium_and_the_material() {
        let e = error(
            "<medium type=\"homogeneous\" id=\"m\"/><shape type=\"rectangle\"><bsdf type=\"null\" id=\"window\"/>\
             <ref name=\"interior\" id=\"m\"/></shape>",
        );
        assert!(
            e.starts_with("t.xml:2:36: <shape type=\"rectangle\">: medium 'm' is not enclosed")
                && e.contains("material 'window (interior: m)' has it as its interior"),
            "{e}"
        );
    }

    #[test]
    fn unused_media_and_the_path_integrator_are_warned_about() {
        let body = "<integrator type=\"path\"/>\n<medium type=\"homogeneous\" id=\"unused\"/>\n\
                    <medium type=\"homogeneous\" id=\"m\"/><sensor type=\"perspective\"><ref id=\"m\"/></sensor>\
                    <shape type=\"cube\"/>";
        let imported = import("3.0.0", body).unwrap();
        assert_eq!(imported.scene.camera_medium.as_deref(), Some("m"));
        assert_eq!(
            imported.warnings,
            [
                "t.xml:3:1: <medium type=\"homogeneous\" id=\"unused\">: no shape or sensor refers to this medium: ignored",
                "t.xml:2:1: <integrator type=\"path\">: Mitsuba's path integrator renders no media (its volpath does): lightgraph renders them"
            ]
        );
    }
}
