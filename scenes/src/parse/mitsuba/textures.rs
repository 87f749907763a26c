//! Mitsuba textures as [`Texture`]s and [`TextureRef`]s: `bitmap` (an image file, its wrap
//! mode, filter, `raw` flag and uv transform) and `checkerboard` (baked exactly into a 2 x 2
//! image of linear texels looked up nearest with repeat wrapping).

use super::transform;
use super::xml::{Color, Context, Props, Result};
use crate::model::texture::{Texture, TextureRef, Wrap};
use std::collections::HashMap;
use std::path::PathBuf;

/// The images textures refer to, each file loaded once.
#[derive(Default)]
pub struct Images {
    /// The textures [`TextureRef::texture`] indexes.
    pub textures: Vec<Texture>,
    by_path: HashMap<PathBuf, u32>,
}

impl Images {
    /// A `bitmap` texture: its image (loaded once per file), `wrap_mode`, `filter_type`
    /// (nearest, else bilinear: another filter is warned about), `raw` (linear colour) and uv
    /// transform ([`uv_transform`]).
    pub fn bitmap(&mut self, ctx: &mut Context, props: &Props) -> Result<TextureRef> {
        let node = props.node();
        let path = props.file(ctx, "a bitmap")?;
        let mut r = TextureRef::new(0);
        r.linear = props.boolean(ctx, "raw")? == Some(true);
        r.wrap = [wrap_mode(ctx, props)?; 2];
        r.nearest = match props.string(ctx, "filter_type")?.as_deref() {
            None | Some("bilinear") => false,
            Some("nearest") => true,
            Some(other) => {
                ctx.warn(node, format!("filter_type {other} is rendered bilinear"));
                false
            }
        };
        r.transform = uv_transform(ctx, props)?;
        r.texture = match self.by_path.get(&path) {
            Some(&i) => i,
            None => {
                let image = image::open(&path)
                    .map_err(|e| ctx.error(node, format!("{}: {e}", path.display())))?
                    .to_rgba8();
                let texels = image.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
                let i = self.push(Texture {
                    name: path.display().to_string(),
                    width: image.width(),
                    height: image.height(),
                    texels,
                });
                self.by_path.insert(path, i);
                i
            }
        };
        Ok(r)
    }

    /// A `checkerboard` texture: `color0` (default 0.4) where the fractional parts of u and v
    /// are both above or both at most 1/2, `color1` (0.2) elsewhere, after `to_uv`: 2 x 2
    /// linear texels looked up nearest with repeat wrapping, the colours exact on the GPU
    /// ([`TextureRef::checker`]; the image holds them in 8 bits); colours are clamped to
    /// [0, 1] and a textured colour is replaced by its default (both warned).
    pub fn checkerboard<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>) -> Result<TextureRef> {
        let colors = [
            checker_color(ctx, props, "color0", 0.4)?,
            checker_color(ctx, props, "color1", 0.2)?,
        ];
        let [texel0, texel1] = colors.map(|c| {
            let [r, g, b] = c.map(|v| (v * 255.0).round() as u32);
            r | g << 8 | b << 16 | 0xff << 24
        });
        let (line, column) = ctx.at(props.node());
        let texture = self.push(Texture {
            name: format!("checkerboard at {}:{line}:{column}", ctx.file),
            width: 2,
            height: 2,
            texels: vec![texel0, texel1, texel1, texel0],
        });
        Ok(TextureRef {
            transform: uv_transform(ctx, props)?,
            nearest: true,
            linear: true,
            checker: Some(colors),
            ..TextureRef::new(texture)
        })
    }

    /// Adds `t` and returns its index.
    fn push(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        self.textures.len() as u32 - 1
    }
}

/// A checkerboard colour `name`, linear RGB in [0, 1].
fn checker_color<'a, 'i>(
    ctx: &mut Context<'a, 'i>,
    props: &Props<'a, 'i>,
    name: &str,
    default: f32,
) -> Result<[f32; 3]> {
    let rgb = match props.color(ctx, name)? {
        None => [default; 3],
        Some(Color::Rgb(c)) => c,
        Some(Color::Texture(t)) => {
            ctx.warn(t, format!("a textured {name} is not supported: {default} is used"));
            [default; 3]
        }
    };
    if rgb.iter().any(|c| !(0.0..=1.0).contains(c)) {
        let node = props.get(name).unwrap_or(props.node());
        ctx.warn(node, format!("{name} {rgb:?} is clamped to [0, 1]"));
    }
    Ok(rgb.map(|c| c.clamp(0.0, 1.0)))
}

/// The 2 x 3 uv transform of a texture: Mitsuba 0.5's `u_scale`/`v_scale` (or `uvscale`)
/// and `u_offset`/`v_offset`, then Mitsuba 3's `to_uv`, whose matrix maps the point (u, v, 1)
/// (a 3 x 3 `matrix` is a 2D homogeneous one; `translate`, `scale` and rotations about z act
/// on u and v).
pub fn uv_transform(ctx: &mut Context, props: &Props) -> Result<[[f32; 3]; 2]> {
    let scale = [props.float(ctx, "u_scale")?, props.float(ctx, "v_scale")?];
    let uvscale = props.float(ctx, "uvscale")?;
    let [su, sv] = scale.map(|s| s.or(uvscale).unwrap_or(1.0));
    let [ou, ov] = [props.float(ctx, "u_offset")?, props.float(ctx, "v_offset")?].map(|o| o.unwrap_or(0.0));
    let m = match props.get("to_uv") {
        Some(node) => transform::parse(ctx, node)?,
        None => glam::Mat4::IDENTITY,
    };
    // The rows of to_uv on (u, v, 1, 1), after the scale and offset.
    let row = |k: usize| {
        let (a, b, c) = (m.x_axis[k], m.y_axis[k], m.z_axis[k] + m.w_axis[k]);
        [a * su, b * sv, a * ou + b * ov + c]
    };
    Ok([row(0), row(1)])
}

/// A bitmap's `wrap_mode` (Mitsuba's default: repeat).
fn wrap_mode(ctx: &Context, props: &Props) -> Result<Wrap> {
    Ok(match props.string(ctx, "wrap_mode")?.as_deref() {
        None | Some("repeat") => Wrap::Repeat,
        Some("mirror") => Wrap::MirroredRepeat,
        Some("clamp") => Wrap::ClampToEdge,
        Some(other) => {
            return Err(ctx.error(
                props.node(),
                format!("wrap_mode '{other}' is not repeat, mirror or clamp"),
            ));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::materials::Materials;
    use super::*;
    use crate::model::Pbr;
    use roxmltree::Document;
    use std::path::Path;

    /// The Pbr model of the first bsdf of `xml` (files beside the test scenes), its images and
    /// the warnings.
    fn convert(xml: &str) -> (Pbr, Vec<Texture>, Vec<String>) {
        let doc = Document::parse(xml).unwrap();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mitsuba");
        let mut ctx = Context::new("t.xml", &dir, &doc).unwrap();
        let node = doc.descendants().find(|n| n.has_tag_name("bsdf")).unwrap();
        let mut materials = Materials::default();
        let name = materials.name_of(&mut ctx, node).unwrap();
        let pbr = materials.materials[&name].pbr.clone().unwrap();
        (pbr, materials.images.textures, ctx.warnings)
    }

    /// The linear value of channel 0 of reference `r` at `uv`, looked up nearest with repeat
    /// wrapping (what the shader does with TEXTURE_NEAREST).
    fn nearest(r: &TextureRef, textures: &[Texture], [u, v]: [f64; 2]) -> f64 {
        let t = &textures[r.texture as usize];
        let m = r.transform.map(|row| row.map(f64::from));
        let s = m[0][0] * u + m[0][1] * v + m[0][2];
        let w = m[1][0] * u + m[1][1] * v + m[1][2];
        let x = ((s * t.width as f64).floor() as i64).rem_euclid(t.width as i64);
        let y = ((w * t.height as f64).floor() as i64).rem_euclid(t.height as i64);
        (t.texels[(y * t.width as i64 + x) as usize] & 0xff) as f64 / 255.0
    }

    #[test]
    fn a_checkerboard_is_mitsubas_pattern_in_nearest_linear_texels() {
        // VeachAjar's to_uv, plus a translation.
        let (p, textures, warnings) = convert(
            "<bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">\
             <transform name=\"to_uv\"><scale x=\"20\" y=\"80\"/><translate x=\"0.3\" y=\"0.1\"/></transform>\
             </texture></bsdf>",
        );
        assert!(warnings.is_empty(), "{warnings:?}");
        let r = p.textures.base_color.unwrap();
        assert!(r.nearest && r.linear && r.wrap == [Wrap::Repeat; 2]);
        assert_eq!(p.base_color, [1.0; 3]);
        // Mitsuba 3's definition: color1 (0.2) where fract(u') > 1/2 and fract(v') > 1/2
        // differ, color0 (0.4) elsewhere, (u', v') = to_uv (u, v).
        let mut checked = 0;
        for i in 0..5000u32 {
            let u = (i as f64 * 0.618_034).fract() * 3.0 - 1.0;
            let v = (i as f64 * 0.754_878).fract() * 3.0 - 1.0;
            let (a, b) = (20.0 * u + 0.3, 80.0 * v + 0.1);
            // Away from the edges, where f32 and f64 could round to different cells.
            let edge = |x: f64| ((2.0 * x).round() - 2.0 * x).abs() < 1e-3;
            if edge(a) || edge(b) {
                continue;
            }
            let want = if (a - a.floor() > 0.5) != (b - b.floor() > 0.5) {
                0.2
            } else {
                0.4
            };
            let got = nearest(&r, &textures, [u, v]);
            assert!((got - want).abs() < 1e-7, "uv ({u}, {v}): {got} for {want}");
            checked += 1;
        }
        assert!(checked > 4000);
    }

    #[test]
    fn checkerboard_colours_are_read_clamped_and_textured_ones_warned() {
        let (p, textures, warnings) = convert(
            "<bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">\n\
             <rgb name=\"color0\" value=\"1, 0.5, 0\"/><rgb name=\"color1\" value=\"2\"/></texture></bsdf>",
        );
        let r = p.textures.base_color.unwrap();
        let t = &textures[r.texture as usize];
        assert_eq!((t.width, t.height), (2, 2));
        assert_eq!(t.texels, [0xff00_80ff, 0xffff_ffff, 0xffff_ffff, 0xff00_80ff]);
        // The GPU's colours: exact, clamped.
        assert_eq!(r.checker, Some([[1.0, 0.5, 0.0], [1.0; 3]]));
        assert_eq!(
            warnings,
            ["t.xml:2:39: <rgb name=\"color1\">: color1 [2.0, 2.0, 2.0] is clamped to [0, 1]"]
        );
        let (_, _, warnings) = convert(
            "<bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">\
             <texture type=\"checkerboard\" name=\"color0\"/></texture></bsdf>",
        );
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].contains("a textured color0 is not supported: 0.4 is used"),
            "{warnings:?}"
        );
    }

    #[test]
    fn a_textured_conductor_reflectance_tints_its_fresnel() {
        // VeachAjar's door handle: aluminium times a checkerboard.
        let (p, textures, warnings) = convert(
            "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.1\"/>\
             <texture name=\"specular_reflectance\" type=\"checkerboard\">\
             <rgb name=\"color1\" value=\"0.2, 0.2, 0.2\"/><rgb name=\"color0\" value=\"0.8, 0.8, 0.8\"/>\
             <transform name=\"to_uv\"><scale x=\"20\" y=\"80\"/></transform></texture>\
             <rgb name=\"eta\" value=\"1.65746, 0.880369, 0.521229\"/><rgb name=\"k\" value=\"9.22387, 6.26952, 4.837\"/></bsdf>",
        );
        assert!(warnings.is_empty(), "{warnings:?}");
        // The texture is the tint of the conductor's own Fresnel (Mitsuba multiplies the two):
        // a white factor, the complex index kept.
        assert_eq!(p.base_color, [1.0; 3]);
        let c = p.conductor.unwrap();
        assert_eq!((c.eta, c.k), ([1.65746, 0.880369, 0.521229], [9.22387, 6.26952, 4.837]));
        assert_eq!(p.metallic, 1.0);
        let r = p.textures.base_color.unwrap();
        assert_eq!(r.transform, [[20.0, 0.0, 0.0], [0.0, 80.0, 0.0]]);
        assert_eq!(textures[r.texture as usize].texels[..2], [0xffcc_cccc, 0xff33_3333]);
        // A texture type the importer does not know: a tint of 0.5 on Mitsuba 3's default
        // conductor, a perfect mirror, warned.
        let (p, _, warnings) =
            convert("<bsdf type=\"conductor\"><texture name=\"specular_reflectance\" type=\"voronoi\"/></bsdf>");
        assert_eq!((p.base_color, p.textures.base_color), ([0.5; 3], None));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
    }

    #[test]
    fn bitmaps_read_to_uv_raw_and_nearest_filtering() {
        let bitmap = |inner: &str| {
            convert(&format!(
                "<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\
                 <string name=\"filename\" value=\"textures/checker.png\"/>{inner}</texture></bsdf>"
            ))
        };
        let (p, _, warnings) = bitmap(
            "<transform name=\"to_uv\"><scale x=\"2\" y=\"3\"/><translate x=\"0.5\" y=\"0.25\"/></transform>\
             <boolean name=\"raw\" value=\"true\"/><string name=\"filter_type\" value=\"nearest\"/>",
        );
        assert!(warnings.is_empty(), "{warnings:?}");
        let r = p.textures.base_color.unwrap();
        assert_eq!(r.transform, [[2.0, 0.0, 0.5], [0.0, 3.0, 0.25]]);
        assert!(r.nearest && r.linear);
        // A 3 x 3 matrix is a 2D homogeneous one; Mitsuba 0.5's scale and offset come first.
        let (p, _, _) = bitmap(
            "<transform name=\"to_uv\"><matrix value=\"2 0 0.5  0 3 0.25  0 0 1\"/></transform>\
             <float name=\"uvscale\" value=\"2\"/><float name=\"u_offset\" value=\"1\"/>",
        );
        let r = p.textures.base_color.unwrap();
        assert_eq!(r.transform, [[4.0, 0.0, 2.5], [0.0, 6.0, 0.25]]);
        assert!(!r.nearest && !r.linear);
        let (_, _, warnings) = bitmap("<string name=\"filter_type\" value=\"ewa\"/>");
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].ends_with("filter_type ewa is rendered bilinear"),
            "{warnings:?}"
        );
    }
}
