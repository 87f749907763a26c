//! Mitsuba scene files (XML, format versions 0.5 to 3.x, as Bitterli's scene collection and
//! Mitsuba 3 write them) imported into the scene model: shapes ([`shapes`], [`serialized`]
//! meshes) with their `to_world` transforms ([`transform`]), `shapegroup`s placed by
//! `instance`s, bsdfs ([`materials`]), homogeneous media ([`media`]) inside and outside shapes
//! and around the sensor, emitters ([`emitters`]), the perspective sensor and its film
//! ([`camera`]), the integrator's `max_depth`, `<default>` parameters and `$name`
//! substitution, and `<ref>`s by id ([`xml`]).
//!
//! What the model cannot express is imported approximately or left out, each time with a
//! warning naming the file, the line and the element; malformed XML, bad values and missing
//! files are errors at file:line:column. docs/mitsuba.md lists the mapping.

pub mod camera;
pub mod emitters;
pub mod export;
pub mod materials;
pub mod media;
pub mod mesh;
pub mod serialized;
pub mod shapes;
pub mod textures;
pub mod transform;
pub mod xml;

use crate::error::SceneError;
use crate::model::{Integrator, Rgb, Scene, Shape};
use glam::{Mat4, Vec3};
use materials::Materials;
use media::Media;
use roxmltree::Node;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use xml::{Context, Props, Result};

/// A Mitsuba scene as the scene model, and what was imported approximately.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The scene, with its textures and environment maps loaded.
    pub scene: Scene,
    /// One line each: `file:line:column: <element>: what`.
    pub warnings: Vec<String>,
}

/// Imports the Mitsuba scene file at `path` (relative file names start at its folder).
pub fn load(path: &Path) -> std::result::Result<Imported, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        at: None,
        message: e.to_string(),
    })?;
    parse(&file, path.parent().unwrap_or(Path::new(".")), &text)
}

/// Imports the Mitsuba scene `text` of `file`, whose relative file names start at `dir`.
pub fn parse(file: &str, dir: &Path, text: &str) -> std::result::Result<Imported, SceneError> {
    let error = |at: (usize, usize), message: String| SceneError {
        file: file.to_string(),
        at: Some(at),
        message,
    };
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        error((p.row as usize, p.col as usize), e.to_string())
    })?;
    let mut ctx = Context::new(file, dir, &doc).map_err(|e| error(e.at, e.message))?;
    let scene = import(&mut ctx, doc.root_element()).map_err(|e| error(e.at, e.message))?;
    Ok(Imported {
        scene,
        warnings: ctx.warnings,
    })
}

/// Nesting of instances in shapegroups (Mitsuba allows none) and of shapegroups beyond
/// which an import stops.
const MAX_INSTANCING: u32 = 8;

/// What the shapes of a scene add up to.
struct Builder<'a, 'i> {
    materials: Materials,
    media: Media,
    shapes: Vec<Shape>,
    /// The first shape element of each material with media, where an error about its
    /// boundary is reported.
    bounding: HashMap<String, Node<'a, 'i>>,
    /// A file of format 0.x: a shape with a medium and no bsdf is an index-matched boundary
    /// (Mitsuba 0.6's `null`), not Mitsuba 3's diffuse.
    legacy: bool,
}

fn import<'a, 'i>(ctx: &mut Context<'a, 'i>, root: Node<'a, 'i>) -> Result<Scene> {
    if !root.has_tag_name("scene") {
        return Err(ctx.error(root, "the root element must be <scene>"));
    }
    let version = ctx.optional_attribute(root, "version")?.unwrap_or_default();
    let major = version.split('.').next().and_then(|m| m.parse::<u32>().ok());
    if !matches!(major, Some(0..=3)) {
        ctx.warn(
            root,
            format!("version '{version}' is not one of 0.5 to 3.x: read as 3.x"),
        );
    }
    let mut builder = Builder {
        materials: Materials::default(),
        media: Media::default(),
        shapes: Vec::new(),
        bounding: HashMap::new(),
        legacy: major == Some(0),
    };
    let mut lights = Vec::new();
    let mut camera = None;
    let mut camera_medium = None;
    let mut integrator = Integrator::default();
    let mut path_integrator = None;
    for node in root.children().filter(|n| n.is_element()) {
        match node.tag_name().name() {
            "default" => ctx.add_default(node)?,
            "integrator" => {
                integrator.max_path_length = max_depth(ctx, node)?.unwrap_or(integrator.max_path_length);
                path_integrator = (ctx.plugin_type(node)? == "path").then_some(node);
            }
            "sensor" => {
                if camera.is_some() {
                    ctx.warn(node, "a second sensor is ignored");
                } else {
                    camera = Some(camera::sensor(ctx, node)?);
                    if let Some(medium) = camera::medium(ctx, node)? {
                        camera_medium = Some(builder.media.name_of(ctx, medium)?);
                    }
                }
            }
            "shape" => shape(ctx, &mut builder, node, Mat4::IDENTITY, 0)?,
            "emitter" => lights.extend(emitters::light(ctx, node)?),
            // Used where they are referenced.
            "bsdf" | "texture" | "medium" | "phase" => {}
            _ => ctx.warn(node, "unsupported element: ignored"),
        }
    }
    unused_media(ctx, root, &builder.media);
    let mut scene = Scene {
        description: format!("the Mitsuba scene {}", ctx.file),
        camera: None,
        gltf_camera: None,
        resolution: (768, 576),
        materials: BTreeMap::new(),
        shapes: builder.shapes,
        lights,
        integrator,
        media: builder.media.media,
        camera_medium,
        gltf: None,
        gltf_diffuse: false,
        gltf_instances: Vec::new(),
        mitsuba: None,
        textures: builder.materials.images.textures,
    };
    scene.materials = builder.materials.materials;
    match camera {
        Some((c, size)) => {
            scene.camera = Some(c);
            scene.resolution = size;
        }
        None => {
            ctx.warn(root, "the scene has no sensor: a default camera frames its bounds");
            scene.camera = Some(crate::model::framing::default_camera(&scene));
        }
    }
    if let Some(node) = path_integrator
        && crate::model::media::uses_media(&scene)
    {
        ctx.warn(
            node,
            "Mitsuba's path integrator renders no media (its volpath does): lightgraph renders them",
        );
    }
    crate::model::checks::check_lights(&scene.lights).map_err(|(_, message)| ctx.error(root, message))?;
    // An open boundary is reported at the first shape of its material.
    crate::model::enclosure::check_enclosures(&scene).map_err(|(material, message)| {
        let shape = builder.bounding.get(material.trim_matches('"')).copied();
        ctx.error(shape.unwrap_or(root), message)
    })?;
    crate::model::checks::check_resolved(&scene).map_err(|message| ctx.error(root, message))?;
    Ok(scene)
}

/// Warns about the top-level media no shape or sensor refers to.
fn unused_media(ctx: &mut Context, root: Node, media: &Media) {
    for node in root.children().filter(|n| n.has_tag_name("medium")) {
        if !node.attribute("id").is_some_and(|id| media.media.contains_key(id)) {
            ctx.warn(node, "no shape or sensor refers to this medium: ignored");
        }
    }
}

/// An integrator's `max_depth` (Mitsuba's -1, unlimited, is capped at 100 with a warning);
/// the integrator itself is lightgraph's graph, so a type other than `path` and `volpath` is
/// warned about.
fn max_depth(ctx: &mut Context, node: Node) -> Result<Option<u32>> {
    let kind = ctx.plugin_type(node)?;
    let props = Props::new(node);
    let path = matches!(kind.as_str(), "path" | "volpath");
    if !path {
        ctx.warn(
            node,
            format!("the integrator '{kind}' is not used: --graph chooses the estimator (max_depth is kept)"),
        );
    }
    let depth = match props.integer(ctx, "max_depth")? {
        None => None,
        Some(d) if d < 0 => {
            ctx.warn(node, "an unlimited max_depth is capped at 100");
            Some(100)
        }
        Some(0) => return Err(ctx.error(node, "max_depth 0 renders nothing")),
        Some(d) => Some(d.min(100_000) as u32),
    };
    if path {
        props.finish(ctx);
    }
    Ok(depth)
}

/// Adds the triangles of shape `node` (or of the shapes an instance places) under `parent`.
fn shape<'a, 'i>(
    ctx: &mut Context<'a, 'i>,
    b: &mut Builder<'a, 'i>,
    node: Node<'a, 'i>,
    parent: Mat4,
    depth: u32,
) -> Result<()> {
    if depth > MAX_INSTANCING {
        return Err(ctx.error(node, format!("instances nest more than {MAX_INSTANCING} deep")));
    }
    let kind = ctx.plugin_type(node)?;
    let props = Props::new(node);
    let m = parent * transform::to_world(ctx, &props)?;
    match kind.as_str() {
        // A group is drawn where instances place it.
        "shapegroup" if depth == 0 => return Ok(()),
        "shapegroup" => {
            for child in props.nested(ctx, "shape")? {
                shape(ctx, b, child, m, depth + 1)?;
            }
            return Ok(());
        }
        "instance" => {
            let groups = props.nested(ctx, "shape")?;
            if groups.is_empty() {
                return Err(ctx.error(node, "an instance needs a shapegroup (<ref id=\"..\"/>)"));
            }
            for group in groups {
                shape(ctx, b, group, m, depth + 1)?;
            }
            props.finish(ctx);
            return Ok(());
        }
        _ => {}
    }
    let emitters = props.nested(ctx, "emitter")?;
    let material = material(ctx, b, &props, !emitters.is_empty())?;
    let mut emission: Option<Rgb> = None;
    for emitter in emitters {
        emission = emitters::area(ctx, emitter)?;
    }
    let face_normals = props.boolean(ctx, "face_normals")?.unwrap_or(false);
    let flip = props.boolean(ctx, "flip_normals")?.unwrap_or(false);
    let mesh = if kind == "sphere" {
        let center = Vec3::from(props.point(ctx, "center")?.unwrap_or([0.0; 3]));
        let radius = props.float(ctx, "radius")?.unwrap_or(1.0);
        if radius <= 0.0 || !radius.is_finite() {
            return Err(ctx.error(node, format!("the radius {radius} is not positive")));
        }
        // The analytic sphere has no texture coordinates: a textured one is meshed (with
        // Mitsuba's parameterisation, u the azimuth and v the polar angle over pi).
        let textured = b.materials.materials[&material]
            .pbr
            .as_ref()
            .is_some_and(|p| p.textures.any());
        match similarity_scale(m) {
            Some(s) if emission.is_none() && !flip && !textured => {
                b.shapes.push(Shape::Sphere {
                    center: m.transform_point3(center).to_array(),
                    radius: radius * s,
                    material,
                });
                props.finish(ctx);
                return Ok(());
            }
            _ => shapes::sphere(center, radius),
        }
    } else {
        match shapes::mesh(ctx, &props, &kind)? {
            Some(mesh) => mesh,
            None => {
                ctx.warn(node, "unsupported shape: ignored");
                return Ok(());
            }
        }
    };
    let mut mesh = mesh;
    if face_normals {
        mesh.normals = None;
    }
    let mesh = mesh.placed(m, flip);
    if mesh.indices.is_empty() {
        ctx.warn(node, "the shape has no triangles");
    } else {
        b.shapes.push(Shape::Mesh {
            positions: mesh.positions.iter().map(|p| p.to_array()).collect(),
            indices: mesh.indices,
            material,
            emission,
            uvs: mesh.uvs,
            normals: mesh.normals.map(|n| n.iter().map(|v| v.to_array()).collect()),
            tangents: None,
        });
    }
    props.finish(ctx);
    Ok(())
}

/// The material of a shape: its bsdf (or the default one) with its `interior` and `exterior`
/// media, a variant of the bsdf's material named after them (`glass (interior: water)`).
/// Without a bsdf, a shape with a medium is Mitsuba 3's default diffuse, or in a 0.x file
/// Mitsuba 0.6's index-matched boundary (`null`).
fn material<'a, 'i>(
    ctx: &mut Context<'a, 'i>,
    b: &mut Builder<'a, 'i>,
    props: &Props<'a, 'i>,
    emits: bool,
) -> Result<String> {
    let mut sides = Vec::new();
    for slot in ["interior", "exterior"] {
        if let Some(node) = media::slot(ctx, props, slot)? {
            sides.push((slot, b.media.name_of(ctx, node)?));
        }
    }
    let base = match props.nested(ctx, "bsdf")?.first() {
        Some(&bsdf) => b.materials.name_of(ctx, bsdf)?,
        None if b.legacy && !emits && !sides.is_empty() => b.materials.null_name(),
        None => b.materials.default_name(emits),
    };
    if sides.is_empty() {
        return Ok(base);
    }
    let described: Vec<String> = sides.iter().map(|(slot, m)| format!("{slot}: {m}")).collect();
    let name = format!("{base} ({})", described.join(", "));
    if !b.materials.materials.contains_key(&name) {
        let mut m = b.materials.materials[&base].clone();
        for (slot, medium) in sides {
            *if slot == "interior" {
                &mut m.interior
            } else {
                &mut m.exterior
            } = Some(medium);
        }
        b.materials.materials.insert(name.clone(), m);
        b.bounding.insert(name.clone(), props.node());
    }
    Ok(name)
}

/// The scale of `m` when it is a rotation, uniform scale and translation.
fn similarity_scale(m: Mat4) -> Option<f32> {
    let [x, y, z] = [Vec3::X, Vec3::Y, Vec3::Z].map(|a| m.transform_vector3(a));
    let s = x.length();
    let tolerance = 1e-4 * s;
    let similar = (y.length() - s).abs() < tolerance
        && (z.length() - s).abs() < tolerance
        && x.dot(y).abs() < tolerance * s
        && y.dot(z).abs() < tolerance * s
        && x.dot(z).abs() < tolerance * s;
    (similar && s > 0.0).then_some(s)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{FovAxis, Light};

    /// The test data file `name`.
    pub(crate) fn data(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data/mitsuba")
            .join(name)
    }

    /// Imports `text` as a scene file beside the test data.
    fn import_text(text: &str) -> std::result::Result<Imported, SceneError> {
        parse("t.xml", &data(""), text)
    }

    #[test]
    fn an_opacity_bitmap_with_an_alpha_channel_cuts_out_by_its_alpha() {
        let dir = std::env::temp_dir().join(format!("lightgraph-mitsuba-alpha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A white texel left transparent beside an opaque green one, as a leaf texture holds
        // them: the white must be cut out, though its red channel is 255.
        image::RgbaImage::from_raw(2, 1, vec![255, 255, 255, 0, 10, 200, 10, 255])
            .unwrap()
            .save(dir.join("leaf.png"))
            .unwrap();
        let leaf = r#"<texture type="bitmap" name="NAME"><string name="filename" value="leaf.png"/></texture>"#;
        let text = format!(
            r#"<scene version="0.5.0"><bsdf type="mask" id="leaves">{}<bsdf type="diffuse">{}</bsdf></bsdf>
               <shape type="rectangle"><ref id="leaves"/></shape>
               <emitter type="constant"/></scene>"#,
            leaf.replace("NAME", "opacity"),
            leaf.replace("NAME", "reflectance")
        );
        let imported = parse("t.xml", &dir, &text).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let pbr = imported.scene.materials["leaves"].pbr.as_ref().unwrap();
        let base = pbr.textures.base_color.expect("a base colour texture");
        let alphas: Vec<u32> = imported.scene.textures[base.texture as usize]
            .texels
            .iter()
            .map(|t| t >> 24)
            .collect();
        assert_eq!(alphas, [0, 255]);
        assert_eq!(pbr.alpha_cutoff, Some(0.5));
    }

    #[test]
    fn every_feature_imports_and_compiles() {
        let imported = load(&data("all-features.xml")).unwrap();
        let scene = &imported.scene;
        assert_eq!(scene.resolution, (32, 24));
        assert_eq!(scene.integrator.max_path_length, 6);
        assert_eq!(scene.camera.as_ref().unwrap().fov_axis, FovAxis::Smaller);
        // Floor, quad, tetrahedron, glass sphere, cube, two instances of (sphere, cube), the
        // emitting disk and three panes.
        let names: Vec<&str> = scene.shapes.iter().map(|s| s.material()).collect();
        assert_eq!(scene.shapes.len(), 13, "{names:?}");
        let spheres = scene
            .shapes
            .iter()
            .filter(|s| matches!(s, Shape::Sphere { .. }))
            .count();
        assert_eq!(spheres, 3);
        let Some(Shape::Sphere { center, radius, .. }) =
            scene.shapes.iter().rev().find(|s| matches!(s, Shape::Sphere { .. }))
        else {
            unreachable!()
        };
        assert_eq!((*center, *radius), ([-0.8, 0.2, 1.0], 0.2));
        assert_eq!(scene.textures.len(), 1, "the checker is loaded once");
        assert_eq!(scene.lights.len(), 4);
        assert!(scene.shapes.iter().any(Shape::emits));
        let floor = &scene.materials["floor"];
        assert!(floor.two_sided && floor.pbr.as_ref().unwrap().textures.base_color.is_some());
        let mut warnings = imported.warnings.join("\n");
        for expected in [
            "all-features.xml:56:2: <bsdf type=\"mask\" id=\"leaf\">: the stochastic opacity 0.8",
            "all-features.xml:60:2: <bsdf type=\"bumpmap\" id=\"bumpy\">: bumpmap is ignored",
        ] {
            assert!(warnings.contains(expected), "{expected} in\n{warnings}");
            warnings = warnings.replacen(expected, "", 1);
        }
        assert_eq!(imported.warnings.len(), 2, "{:?}", imported.warnings);
        assert!(scene.materials["pane"].pbr.as_ref().unwrap().thin_walled);
        crate::pack::compile::CompiledScene::new(scene).unwrap();
    }

    #[test]
    fn version_0_5_names_import() {
        let imported = load(&data("version-0.5.xml")).unwrap();
        let scene = &imported.scene;
        assert_eq!(scene.integrator.max_path_length, 100);
        let Some(Shape::Mesh { normals, positions, .. }) = scene.shapes.first() else {
            panic!()
        };
        assert!(normals.is_none(), "faceNormals drops the normals");
        assert_eq!(positions[2], [2.0, 2.0, 0.0]);
        let Some(Shape::Mesh {
            positions,
            indices,
            emission,
            ..
        }) = scene.shapes.get(1)
        else {
            panic!()
        };
        let [a, b, c] = indices[0].map(|i| Vec3::from(positions[i as usize]));
        assert!((b - a).cross(c - a).z < 0.0, "flipNormals turns the emitter towards -Z");
        assert_eq!(*emission, Some([10.0; 3]));
        let camera = scene.camera.as_ref().unwrap();
        assert_eq!(camera.position, [0.0, 1.0, 4.0]);
        let w = imported.warnings.join("\n");
        assert!(
            w.contains("version-0.5.xml:4:2: <integrator type=\"path\">: an unlimited max_depth is capped at 100"),
            "{w}"
        );
        assert!(
            w.contains("version-0.5.xml:52:2: <medium type=\"homogeneous\" id=\"fog\">: no shape or sensor refers to this medium: ignored"),
            "{w}"
        );
        assert_eq!(
            imported.warnings.len(),
            2,
            "camelCase names and harmless film settings are read: {w}"
        );
    }

    #[test]
    fn references_and_errors_name_the_line_and_column() {
        let e = import_text("<scene version=\"3.0.0\">\n  <shape type=\"cube\"><ref id=\"nowhere\"/></shape></scene>")
            .unwrap_err();
        assert_eq!(e.at, Some((2, 22)));
        assert!(
            e.to_string()
                .starts_with("t.xml:2:22: <ref id=\"nowhere\">: no element has the id 'nowhere'"),
            "{e}"
        );
        let e = import_text("<scene version=\"3.0.0\">\n<shape type=\"cube\" x=1>").unwrap_err();
        assert!(e.to_string().starts_with("t.xml:2:"), "{e}");
        let e = import_text("<scene version=\"3.0.0\"><shape type=\"cube\"/></scene>").unwrap_err();
        assert!(e.message.contains("no light"), "{e}");
        let e = import_text("<mitsuba/>").unwrap_err();
        assert!(e.message.contains("must be <scene>"), "{e}");
        let e = import_text(
            "<scene version=\"3.0.0\"><bsdf type=\"diffuse\" id=\"a\"/><bsdf type=\"diffuse\" id=\"a\"/></scene>",
        )
        .unwrap_err();
        assert!(e.message.contains("used twice"), "{e}");
    }

    #[test]
    fn an_emitter_without_a_bsdf_is_black() {
        // Mitsuba 3 and 0.6 give a shape without a bsdf a diffuse of reflectance 0.5, but 0 on
        // an emitter: a light that reflected would brighten what it lights (by 0.25% in
        // bench/peers/fidelity's diffuse scene at depth 6).
        let scene = import_text(
            "<scene version=\"3.0.0\"><shape type=\"rectangle\"><emitter type=\"area\"/></shape>\
             <shape type=\"rectangle\"/></scene>",
        )
        .unwrap()
        .scene;
        let [light, plain] = [&scene.shapes[0], &scene.shapes[1]].map(|s| &scene.materials[s.material()]);
        assert_eq!(
            (scene.shapes[0].material(), light.diffuse),
            (materials::DEFAULT_EMITTER, [0.0; 3])
        );
        assert_eq!(
            (scene.shapes[1].material(), plain.diffuse),
            (materials::DEFAULT, [0.5; 3])
        );
    }

    #[test]
    fn defaults_shapes_without_bsdfs_and_unsupported_shapes() {
        let imported = import_text(
            "<scene version=\"2.1.0\">\n<default name=\"r\" value=\"0.25\"/>\n<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>\n\
             <shape type=\"hair\"/>\n<emitter type=\"constant\"/></scene>",
        )
        .unwrap();
        let scene = imported.scene;
        assert!(matches!(scene.shapes[..], [Shape::Sphere { radius: 0.25, .. }]));
        assert_eq!(scene.shapes[0].material(), materials::DEFAULT);
        assert!(matches!(scene.lights[..], [Light::Background { .. }]));
        assert_eq!(
            imported.warnings,
            [
                "t.xml:4:1: <shape type=\"hair\">: unsupported shape: ignored",
                "t.xml:1:1: <scene>: the scene has no sensor: a default camera frames its bounds"
            ]
        );
    }
}
