//! Mitsuba BSDFs as lightgraph materials (the mapping is written down in docs/mitsuba.md):
//! `diffuse` as the SmallVCM Lambertian lobe (the [`Pbr`] model with an index of refraction
//! of 1, a bare Lambertian, when a bitmap gives the reflectance); dielectrics (`thindielectric`
//! thin-walled), conductors and plastics as [`Pbr`] materials; `twosided`, `mask` and `bumpmap` as wrappers.
//! Textures (`bitmap`, `checkerboard`) are made in [`super::textures`].

use super::textures::Images;
use super::xml::{Color, Context, Props, Result};
use crate::model::texture::{Texture, TextureRef};
use crate::model::{Conductor, Masking, Material, Microfacet, Pbr, Plastic};
use roxmltree::Node;

/// Named indices of refraction Mitsuba knows (its table's common entries).
const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// Conductors by Mitsuba's material name: RGB (eta, k) at about 650, 550 and 450 nm.
const CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Ag", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
    ("Al", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("Au", [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
    ("Cr", [4.370, 2.917, 1.655], [5.206, 4.231, 3.755]),
    ("Cu", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
];

/// Converts bsdf elements, each once, and the bitmaps they use, each once.
#[derive(Default)]
pub struct Materials {
    /// Materials by name: a bsdf's id, or `mitsuba:LINE:COLUMN` for an anonymous one.
    pub materials: std::collections::BTreeMap<String, Material>,
    /// The images of the textures materials use.
    pub images: Images,
}

/// The name of a diffuse grey (reflectance 0.5) that shapes without a bsdf get.
pub const DEFAULT: &str = "mitsuba:default";

/// The name of the black diffuse that emitting shapes without a bsdf get (Mitsuba's default
/// bsdf of an emitter: reflectance 0).
pub const DEFAULT_EMITTER: &str = "mitsuba:default-emitter";

/// The name of the index-matched boundary that Mitsuba 0.6 gives a shape with a medium and
/// no bsdf.
pub const NULL: &str = "mitsuba:null";

impl Materials {
    /// The name of the material of bsdf `node` (a `<bsdf>` element), converting it on first
    /// use.
    pub fn name_of<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<String> {
        let name = ctx.name(node);
        if !self.materials.contains_key(&name) {
            let material = self.bsdf(ctx, node, 0)?;
            self.materials.insert(name.clone(), material);
        }
        Ok(name)
    }

    /// The name of the material a shape without a bsdf gets, adding it on first use: as in
    /// Mitsuba, a diffuse grey, or black on a shape that emits (an emitter does not reflect).
    pub fn default_name(&mut self, emits: bool) -> String {
        let (name, reflectance) = if emits { (DEFAULT_EMITTER, 0.0) } else { (DEFAULT, 0.5) };
        self.materials.entry(name.to_string()).or_insert(Material {
            diffuse: [reflectance; 3],
            ..Default::default()
        });
        name.to_string()
    }

    /// The name of the index-matched boundary ([`NULL`]), adding it on first use.
    pub fn null_name(&mut self) -> String {
        self.materials.entry(NULL.to_string()).or_insert_with(null);
        NULL.to_string()
    }

    fn bsdf<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>, depth: u32) -> Result<Material> {
        if depth > 16 {
            return Err(ctx.error(node, "bsdfs nest more than 16 deep"));
        }
        let kind = ctx.plugin_type(node)?;
        let props = Props::new(node);
        let material = match kind.as_str() {
            "diffuse" => {
                let reflectance = props.color(ctx, "reflectance")?;
                self.diffuse(ctx, reflectance)?
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let ior = ratio_of_iors(ctx, &props, 1.5046)?;
                let (roughness, distribution) = roughness(ctx, &props, kind == "roughdielectric")?;
                let base_color = rgb_or_white(ctx, &props, "specular_transmittance", "transmittance")?;
                white_or_warn(ctx, &props, "specular_reflectance")?;
                pbr(Pbr {
                    base_color,
                    transmission: 1.0,
                    roughness,
                    distribution,
                    masking: Masking::Separable,
                    ior,
                    thin_walled: kind == "thindielectric",
                    ..Default::default()
                })
            }
            "conductor" | "roughconductor" => {
                let conductor = conductor_index(ctx, &props)?;
                let (tint, texture) = self.tint(ctx, &props, "specular_reflectance")?;
                let (roughness, distribution) = roughness(ctx, &props, kind == "roughconductor")?;
                let mut p = Pbr {
                    base_color: tint.map(|t| t.clamp(0.0, 1.0)),
                    metallic: 1.0,
                    roughness,
                    distribution,
                    masking: Masking::Separable,
                    conductor: Some(conductor),
                    ..Default::default()
                };
                p.textures.base_color = texture;
                pbr(p)
            }
            "plastic" | "roughplastic" => {
                let ior = ratio_of_iors(ctx, &props, 1.49)?;
                let (roughness, distribution) = roughness(ctx, &props, kind == "roughplastic")?;
                let nonlinear = props.boolean(ctx, "nonlinear")? == Some(true);
                white_or_warn(ctx, &props, "specular_reflectance")?;
                let reflectance = props.color(ctx, "diffuse_reflectance")?;
                let mut m = self.diffuse(ctx, reflectance)?;
                let p = as_pbr(&mut m);
                p.ior = ior;
                p.roughness = roughness;
                p.distribution = distribution;
                p.masking = Masking::Separable;
                p.plastic = Some(Plastic { nonlinear });
                m
            }
            "null" => null(),
            "twosided" => {
                let inner = props.nested(ctx, "bsdf")?;
                let Some(&first) = inner.first() else {
                    return Err(ctx.error(node, "twosided needs a nested bsdf"));
                };
                if inner.len() > 1 {
                    ctx.warn(
                        node,
                        "a different bsdf on the back side is not supported: the front one is used on both",
                    );
                }
                let mut m = self.bsdf(ctx, first, depth + 1)?;
                m.two_sided = true;
                m
            }
            "mask" => {
                let inner = self.nested_one(ctx, &props, depth)?;
                let mut m = inner;
                match props.color(ctx, "opacity")? {
                    Some(Color::Rgb(c)) => {
                        let alpha = (c[0] + c[1] + c[2]) / 3.0;
                        if alpha < 1.0 {
                            ctx.warn(
                                node,
                                format!("the stochastic opacity {alpha} is rendered as a cut-off at 0.5"),
                            );
                        }
                        let p = as_pbr(&mut m);
                        p.alpha = alpha;
                        p.alpha_cutoff = Some(0.5);
                    }
                    Some(Color::Texture(t)) => {
                        if let Some(r) = self.texture(ctx, t)? {
                            self.alpha_from(ctx, t, &mut m, r);
                        }
                    }
                    None => {}
                }
                m
            }
            "bumpmap" | "normalmap" => {
                ctx.warn(node, format!("{kind} is ignored: the nested bsdf is used unperturbed"));
                props.nested(ctx, "texture")?;
                props.get("normalmap");
                self.nested_one(ctx, &props, depth)?
            }
            _ => {
                ctx.warn(node, "unsupported bsdf: rendered as a grey diffuse (reflectance 0.5)");
                return Ok(Material {
                    diffuse: [0.5; 3],
                    ..Default::default()
                });
            }
        };
        props.finish(ctx);
        Ok(material)
    }

    /// The one nested bsdf of a wrapper.
    fn nested_one<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>, depth: u32) -> Result<Material> {
        let inner = props.nested(ctx, "bsdf")?;
        match inner[..] {
            [one] => self.bsdf(ctx, one, depth + 1),
            _ => Err(ctx.error(props.node(), "needs exactly one nested bsdf")),
        }
    }

    /// The colour property `name` as a factor and a texture multiplying it: white when absent,
    /// a constant 0.5 for an unsupported texture (warned).
    fn tint<'a, 'i>(
        &mut self,
        ctx: &mut Context<'a, 'i>,
        props: &Props<'a, 'i>,
        name: &str,
    ) -> Result<([f32; 3], Option<TextureRef>)> {
        Ok(match props.color(ctx, name)? {
            None => ([1.0; 3], None),
            Some(Color::Rgb(c)) => (c, None),
            Some(Color::Texture(t)) => match self.texture(ctx, t)? {
                Some(r) => ([1.0; 3], Some(r)),
                None => ([0.5; 3], None),
            },
        })
    }

    /// A Lambertian of `reflectance` (Mitsuba's default 0.5): the SmallVCM lobe, or a
    /// [`Pbr`] material of index of refraction 1 (no specular layer) with a bitmap.
    fn diffuse<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, reflectance: Option<Color<'a, 'i>>) -> Result<Material> {
        Ok(match reflectance {
            None => Material {
                diffuse: [0.5; 3],
                ..Default::default()
            },
            Some(Color::Rgb(c)) => Material {
                diffuse: c,
                ..Default::default()
            },
            Some(Color::Texture(t)) => {
                let mut p = Pbr {
                    ior: 1.0,
                    ..Default::default()
                };
                match self.texture(ctx, t)? {
                    Some(r) => p.textures.base_color = Some(r),
                    None => p.base_color = [0.5; 3],
                }
                pbr(p)
            }
        })
    }

    /// Makes the textured opacity `opacity` (bitmap `node`, its first channel) the alpha of
    /// material `m` with a cut-off at 0.5: a copy of its base colour texture with that alpha
    /// (white without one). A base colour texture of another size or transform keeps the
    /// surface opaque (warned).
    fn alpha_from(&mut self, ctx: &mut Context, node: Node, m: &mut Material, opacity: TextureRef) {
        let p = as_pbr(m);
        let textures = &mut self.images.textures;
        let alpha = &textures[opacity.texture as usize];
        let mut combined = match p.textures.base_color {
            Some(base) => {
                let t = &textures[base.texture as usize];
                if (t.width, t.height) != (alpha.width, alpha.height) || base.transform != opacity.transform {
                    ctx.warn(
                        node,
                        "an opacity bitmap of another size or uv transform than the base colour's is not supported: the surface is opaque",
                    );
                    return;
                }
                t.clone()
            }
            None => Texture {
                texels: vec![0x00ff_ffff; alpha.texels.len()],
                ..alpha.clone()
            },
        };
        // An opacity bitmap with an alpha channel (a texel not opaque) gives its alpha: the
        // cut-out painted in it (Bitterli's leaves, as Tungsten and the glTF conversions read
        // them); a grey or RGB one its first channel.
        let shift = if alpha.texels.iter().any(|t| t >> 24 != 0xff) {
            24
        } else {
            0
        };
        for (c, a) in combined.texels.iter_mut().zip(&alpha.texels) {
            *c = (*c & 0x00ff_ffff) | ((a >> shift) & 0xff) << 24;
        }
        combined.name = format!("{} with the alpha of {}", combined.name, alpha.name);
        textures.push(combined);
        let mut r = p.textures.base_color.unwrap_or(opacity);
        r.texture = textures.len() as u32 - 1;
        p.textures.base_color = Some(r);
        p.alpha_cutoff = Some(0.5);
    }

    /// The texture of a `<texture>` element: a `bitmap` or a `checkerboard` ([`Images`]);
    /// other texture types are warned about (`None`: the caller uses a constant).
    fn texture<'a, 'i>(&mut self, ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Option<TextureRef>> {
        let kind = ctx.plugin_type(node)?;
        let props = Props::new(node);
        let r = match kind.as_str() {
            "bitmap" => self.images.bitmap(ctx, &props)?,
            "checkerboard" => self.images.checkerboard(ctx, &props)?,
            _ => {
                ctx.warn(node, "unsupported texture: a constant 0.5 is used");
                return Ok(None);
            }
        };
        props.finish(ctx);
        Ok(Some(r))
    }
}

/// An index-matched boundary: no lobes, crossed without a path vertex.
fn null() -> Material {
    Material {
        null: true,
        ..Default::default()
    }
}

fn pbr(p: Pbr) -> Material {
    Material {
        pbr: Some(p),
        ..Default::default()
    }
}

/// The material's [`Pbr`] model, made from its SmallVCM Lambertian lobe (index of refraction
/// 1: a bare Lambertian) when it has none.
fn as_pbr(m: &mut Material) -> &mut Pbr {
    let diffuse = m.diffuse;
    m.diffuse = [0.0; 3];
    m.pbr.get_or_insert_with(|| Pbr {
        base_color: diffuse,
        ior: 1.0,
        ..Default::default()
    })
}

/// The colour property `name`: white when absent or textured (a texture, called `what` in
/// the warning, is unsupported).
fn rgb_or_white<'a, 'i>(ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>, name: &str, what: &str) -> Result<[f32; 3]> {
    Ok(match props.color(ctx, name)? {
        Some(Color::Rgb(c)) => c,
        None => [1.0; 3],
        Some(Color::Texture(t)) => {
            ctx.warn(t, format!("a textured {what} is not supported: white is used"));
            [1.0; 3]
        }
    })
}

/// Warns when the colour property `name` is given and is not white (the mapping ignores it).
fn white_or_warn<'a, 'i>(ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>, name: &str) -> Result<()> {
    match props.color(ctx, name)? {
        Some(Color::Rgb(c)) if c != [1.0; 3] => {
            let node = props.get(name).unwrap_or(props.node());
            ctx.warn(node, format!("{name} {c:?} is not supported: white is used"));
        }
        Some(Color::Texture(t)) => ctx.warn(t, format!("a textured {name} is not supported: white is used")),
        _ => {}
    }
    Ok(())
}

/// An index of refraction given by number or by Mitsuba's name.
fn ior(ctx: &Context, props: &Props, name: &str, default: f32) -> Result<f32> {
    let Some(node) = props.get(name) else {
        return Ok(default);
    };
    let text = ctx.attribute(node, "value")?;
    if let Ok(v) = text.trim().parse::<f32>()
        && v.is_finite()
        && v > 0.0
    {
        return Ok(v);
    }
    IORS.iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(text.trim()))
        .map(|(_, v)| *v)
        .ok_or_else(|| ctx.error(node, format!("'{text}' is not an index of refraction")))
}

/// int_ior / ext_ior.
fn ratio_of_iors(ctx: &Context, props: &Props, int_default: f32) -> Result<f32> {
    Ok(ior(ctx, props, "int_ior", int_default)? / ior(ctx, props, "ext_ior", 1.000277)?)
}

/// The perceptual roughness of a microfacet bsdf (sqrt of Mitsuba's alpha, default 0.1), or
/// 0 for a smooth one, and its `distribution` (Mitsuba's default: Beckmann); anisotropic
/// roughness is approximated with a warning.
fn roughness(ctx: &mut Context, props: &Props, rough: bool) -> Result<(f32, Microfacet)> {
    if !rough {
        return Ok((0.0, Microfacet::Beckmann));
    }
    let distribution = match props.string(ctx, "distribution")?.as_deref() {
        None | Some("beckmann") => Microfacet::Beckmann,
        Some("ggx") => Microfacet::Ggx,
        Some(d) => {
            // Mitsuba 0.6's `phong` and `as` (Ashikhmin-Shirley) distributions.
            let node = props.get("distribution").unwrap_or(props.node());
            ctx.warn(
                node,
                format!("the {d} distribution is rendered as Beckmann of the same alpha"),
            );
            Microfacet::Beckmann
        }
    };
    let node = props.node();
    if let Some(t) = props
        .get("alpha")
        .filter(|a| a.has_tag_name("texture") || a.has_tag_name("ref"))
    {
        ctx.warn(t, "a textured roughness is not supported: alpha 0.1 is used");
        return Ok((0.1f32.sqrt(), distribution));
    }
    let alpha = match (
        props.float(ctx, "alpha")?,
        props.float(ctx, "alpha_u")?,
        props.float(ctx, "alpha_v")?,
    ) {
        (Some(a), ..) => a,
        (None, Some(u), Some(v)) => {
            ctx.warn(
                node,
                "anisotropic roughness is rendered isotropic (the mean of alpha_u and alpha_v)",
            );
            (u + v) / 2.0
        }
        _ => 0.1,
    };
    if !(0.0..=4.0).contains(&alpha) {
        return Err(ctx.error(node, format!("alpha {alpha} is not a roughness")));
    }
    Ok((alpha.sqrt().min(1.0), distribution))
}

/// A conductor's complex index of refraction, from `eta` and `k` (over `ext_eta`) or its
/// `material` name (Mitsuba 3's default "none" is a perfect mirror: (0, 0)).
fn conductor_index<'a, 'i>(ctx: &mut Context<'a, 'i>, props: &Props<'a, 'i>) -> Result<Conductor> {
    const MIRROR: Conductor = Conductor {
        eta: [0.0; 3],
        k: [0.0; 3],
    };
    let rgb = |ctx: &mut Context<'a, 'i>, name: &str| -> Result<Option<[f32; 3]>> {
        match props.color(ctx, name)? {
            Some(Color::Rgb(c)) => Ok(Some(c)),
            Some(Color::Texture(t)) => Err(ctx.error(t, format!("a textured {name} is not supported"))),
            None => Ok(None),
        }
    };
    let (eta, k) = match (rgb(ctx, "eta")?, rgb(ctx, "k")?) {
        (Some(eta), Some(k)) => (eta, k),
        _ => {
            let name = props.string(ctx, "material")?.unwrap_or_else(|| "none".into());
            if name == "none" {
                return Ok(MIRROR);
            }
            match CONDUCTORS.iter().find(|(n, ..)| n.eq_ignore_ascii_case(&name)) {
                Some((_, eta, k)) => (*eta, *k),
                None => {
                    ctx.warn(
                        props.node(),
                        format!("the conductor '{name}' is not known: rendered as a perfect mirror"),
                    );
                    return Ok(MIRROR);
                }
            }
        }
    };
    let ext = ior(ctx, props, "ext_eta", 1.0)?;
    Ok(Conductor {
        eta: eta.map(|n| n / ext),
        k: k.map(|k| k / ext),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use roxmltree::Document;
    use std::path::Path;

    /// The material of the first bsdf of `xml` and the warnings.
    fn convert(xml: &str) -> (Result<Material>, Vec<String>) {
        let doc = Document::parse(xml).unwrap();
        let mut ctx = Context::new("m.xml", Path::new("."), &doc).unwrap();
        let node = doc.descendants().find(|n| n.has_tag_name("bsdf")).unwrap();
        let mut materials = Materials::default();
        let m = materials
            .name_of(&mut ctx, node)
            .map(|name| materials.materials[&name].clone());
        (m, ctx.warnings)
    }

    #[test]
    fn diffuse_maps_to_the_lambertian_lobe() {
        let (m, w) = convert("<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.2 0.3 0.4\"/></bsdf>");
        let m = m.unwrap();
        assert_eq!(
            (m.diffuse, m.pbr.is_none(), m.two_sided),
            ([0.2, 0.3, 0.4], true, false)
        );
        assert!(w.is_empty(), "{w:?}");
        let (m, _) = convert("<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf>");
        let m = m.unwrap();
        assert_eq!((m.diffuse, m.two_sided), ([0.5; 3], true));
    }

    #[test]
    fn dielectrics_conductors_and_plastics_map_to_pbr() {
        let (m, _) = convert(
            "<bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.5\"/><float name=\"extIOR\" value=\"1\"/></bsdf>",
        );
        let p = m.unwrap().pbr.unwrap();
        assert_eq!(
            (p.transmission, p.roughness, p.ior, p.metallic, p.thin_walled),
            (1.0, 0.0, 1.5, 0.0, false)
        );
        // Mitsuba's thin sheet (a slab's Fresnel, light unbent): thin-walled, without warning.
        let (m, w) = convert(
            "<bsdf type=\"thindielectric\"><float name=\"int_ior\" value=\"1.33\"/><float name=\"ext_ior\" value=\"1\"/></bsdf>",
        );
        let p = m.unwrap().pbr.unwrap();
        assert_eq!((p.transmission, p.ior, p.thin_walled), (1.0, 1.33, true));
        assert!(w.is_empty(), "{w:?}");
        let (m, _) = convert("<bsdf type=\"roughdielectric\"><string name=\"int_ior\" value=\"water\"/></bsdf>");
        let p = m.unwrap().pbr.unwrap();
        assert!((p.ior - 1.333 / 1.000277).abs() < 1e-5 && (p.roughness - 0.1f32.sqrt()).abs() < 1e-6);
        // Mitsuba's default distribution is Beckmann's.
        assert_eq!(p.distribution, Microfacet::Beckmann);
        // VeachBidir's lamp: eta and k as the file gives them (the exact conductor Fresnel,
        // white tint), Beckmann as the file says, without warning.
        let (m, w) = convert(
            "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.25\"/><string name=\"distribution\" value=\"beckmann\"/>\
             <rgb name=\"eta\" value=\"2.8656, 2.11918, 1.94008\"/><rgb name=\"k\" value=\"3.03233, 2.05611, 1.61629\"/></bsdf>",
        );
        let p = m.unwrap().pbr.unwrap();
        assert_eq!((p.metallic, p.roughness), (1.0, 0.5));
        assert_eq!(p.base_color, [1.0; 3]);
        let c = p.conductor.unwrap();
        assert_eq!((c.eta[0], c.k[2]), (2.8656, 1.61629));
        assert_eq!(p.distribution, Microfacet::Beckmann);
        assert!(w.is_empty(), "{w:?}");
        let (m, w) = convert("<bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"ggx\"/></bsdf>");
        assert_eq!(m.unwrap().pbr.unwrap().distribution, Microfacet::Ggx);
        assert!(w.is_empty(), "{w:?}");
        let (m, w) = convert("<bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"phong\"/></bsdf>");
        assert_eq!(m.unwrap().pbr.unwrap().distribution, Microfacet::Beckmann);
        assert!(w[0].contains("the phong distribution is rendered as Beckmann"), "{w:?}");
        let (m, _) = convert("<bsdf type=\"conductor\"/>");
        assert_eq!(m.unwrap().pbr.unwrap().base_color, [1.0; 3]);
        let (m, _) = convert("<bsdf type=\"roughplastic\"><rgb name=\"diffuseReflectance\" value=\"0.5\"/></bsdf>");
        let p = m.unwrap().pbr.unwrap();
        assert_eq!((p.base_color, p.metallic, p.transmission), ([0.5; 3], 0.0, 0.0));
        assert!((p.ior - 1.49 / 1.000277).abs() < 1e-5);
        assert_eq!(p.plastic, Some(Plastic { nonlinear: false }));
        let (m, _) = convert("<bsdf type=\"plastic\"><boolean name=\"nonlinear\" value=\"true\"/></bsdf>");
        assert_eq!(m.unwrap().pbr.unwrap().plastic, Some(Plastic { nonlinear: true }));
    }

    #[test]
    fn wrappers_and_unsupported_bsdfs_warn_with_their_line() {
        let (m, w) = convert(
            "<bsdf type=\"bumpmap\">\n <texture type=\"bitmap\"><string name=\"filename\" value=\"x.png\"/></texture>\n <bsdf type=\"diffuse\"/>\n</bsdf>",
        );
        assert_eq!(m.unwrap().diffuse, [0.5; 3]);
        assert_eq!(
            w,
            ["m.xml:1:1: <bsdf type=\"bumpmap\">: bumpmap is ignored: the nested bsdf is used unperturbed"]
        );
        let (m, w) = convert("<scene>\n\n  <bsdf type=\"hk\"/></scene>");
        assert_eq!(m.unwrap().diffuse, [0.5; 3]);
        assert!(
            w[0].starts_with("m.xml:3:3: <bsdf type=\"hk\">: unsupported bsdf"),
            "{w:?}"
        );
        let (m, w) =
            convert("<bsdf type=\"mask\"><float name=\"opacity\" value=\"0.3\"/><bsdf type=\"diffuse\"/></bsdf>");
        let p = m.unwrap().pbr.unwrap();
        assert_eq!((p.alpha, p.alpha_cutoff, p.ior), (0.3, Some(0.5), 1.0));
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn bad_values_are_errors_with_positions() {
        let (m, _) = convert("<bsdf type=\"dielectric\">\n<string name=\"int_ior\" value=\"unobtainium\"/></bsdf>");
        let e = m.unwrap_err();
        assert_eq!(e.at, (2, 1));
        assert!(e.message.contains("not an index of refraction"), "{}", e.message);
        let (m, _) = convert("<bsdf type=\"twosided\"/>");
        assert!(m.unwrap_err().message.contains("needs a nested bsdf"));
        let (m, _) = convert(
            "<bsdf type=\"diffuse\"><texture name=\"reflectance\" type=\"bitmap\"><string name=\"filename\" value=\"missing.png\"/></texture></bsdf>",
        );
        assert!(m.unwrap_err().message.contains("does not exist"));
    }
}
