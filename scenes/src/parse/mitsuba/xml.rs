//! The XML layer of the Mitsuba importer: positions, warnings and errors; `<default>`
//! parameters and `$name` substitution; `id`s and `<ref>`s; and the properties of a plugin
//! element (`<float name=.. value=..>` and friends), with Mitsuba 0.5's camelCase names read
//! as Mitsuba 3's snake_case ones. Every property a converter does not read is reported as a
//! warning when the plugin is finished ([`Props::finish`]).

use crate::model::texture::srgb_to_linear;
use roxmltree::{Document, Node};
use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// An import error at a position of the scene file (1-based line and column).
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    /// Line and column.
    pub at: (usize, usize),
    /// What is wrong.
    pub message: String,
}

/// The result of an import step.
pub type Result<T> = std::result::Result<T, Error>;

/// What the converters share: the document, its defaults and ids, and the warnings so far.
pub struct Context<'a, 'input> {
    /// The scene file as messages name it.
    pub file: String,
    /// The folder relative file names start from.
    pub dir: PathBuf,
    doc: &'a Document<'input>,
    defaults: HashMap<String, String>,
    ids: HashMap<String, Node<'a, 'input>>,
    /// Warnings, each `file:line:column: <element>: message`.
    pub warnings: Vec<String>,
}

/// Property names nobody needs to read: output, filtering and sampling settings that do not
/// change the image's expected value.
const HARMLESS: &[&str] = &[
    "file_format",
    "pixel_format",
    "component_format",
    "banner",
    "high_quality_edges",
    "filter_type",
    "sample_count",
    "seed",
    "near_clip",
    "far_clip",
    "rfilter",
    "sampler",
    "cache",
    "max_anisotropy",
    "hide_emitters",
];

impl<'a, 'input> Context<'a, 'input> {
    /// A context for `doc`, the text of `file`, whose relative paths start at `dir`; collects
    /// the ids of all elements (an id used twice is an error).
    pub fn new(file: &str, dir: &Path, doc: &'a Document<'input>) -> Result<Self> {
        let mut ctx = Context {
            file: file.to_string(),
            dir: dir.to_path_buf(),
            doc,
            defaults: HashMap::new(),
            ids: HashMap::new(),
            warnings: Vec::new(),
        };
        for node in doc.descendants().filter(|n| n.is_element()) {
            if let Some(id) = node.attribute("id")
                && node.tag_name().name() != "ref"
                && ctx.ids.insert(id.to_string(), node).is_some()
            {
                return Err(ctx.error(node, format!("the id '{id}' is used twice")));
            }
        }
        Ok(ctx)
    }

    /// The 1-based line and column where `node` starts.
    pub fn at(&self, node: Node) -> (usize, usize) {
        let p = self.doc.text_pos_at(node.range().start);
        (p.row as usize, p.col as usize)
    }

    /// The name of the element `node` stands for: its id, or `mitsuba:LINE:COLUMN` when it has
    /// none.
    pub fn name(&self, node: Node) -> String {
        match node.attribute("id") {
            Some(id) => id.to_string(),
            None => {
                let (l, c) = self.at(node);
                format!("mitsuba:{l}:{c}")
            }
        }
    }

    /// An error at `node`.
    pub fn error(&self, node: Node, message: impl Into<String>) -> Error {
        Error {
            at: self.at(node),
            message: format!("{}: {}", describe(node), message.into()),
        }
    }

    /// Records a warning at `node`.
    pub fn warn(&mut self, node: Node, message: impl AsRef<str>) {
        let (line, column) = self.at(node);
        self.warnings.push(format!(
            "{}:{line}:{column}: {}: {}",
            self.file,
            describe(node),
            message.as_ref()
        ));
    }

    /// Records `<default name=.. value=..>` (a later one does not replace an earlier one).
    pub fn add_default(&mut self, node: Node) -> Result<()> {
        let name = self.raw_attribute(node, "name")?;
        let value = self.attribute(node, "value")?;
        self.defaults.entry(name).or_insert(value);
        Ok(())
    }

    /// An attribute that `$name` substitution does not touch; missing is an error.
    fn raw_attribute(&self, node: Node, name: &str) -> Result<String> {
        node.attribute(name)
            .map(String::from)
            .ok_or_else(|| self.error(node, format!("the attribute '{name}' is missing")))
    }

    /// An attribute with `$name` parameters substituted by their `<default>`s; missing is an
    /// error.
    pub fn attribute(&self, node: Node, name: &str) -> Result<String> {
        let raw = self.raw_attribute(node, name)?;
        self.substitute(node, &raw)
    }

    /// An optional attribute, substituted.
    pub fn optional_attribute(&self, node: Node, name: &str) -> Result<Option<String>> {
        node.attribute(name).map(|v| self.substitute(node, v)).transpose()
    }

    fn substitute(&self, node: Node, text: &str) -> Result<String> {
        let mut out = String::with_capacity(text.len());
        let mut rest = text;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..len];
            let value = self.defaults.get(name).ok_or_else(|| {
                self.error(
                    node,
                    format!("the parameter '${name}' has no value (add <default name=\"{name}\" value=\"..\"/>)"),
                )
            })?;
            out.push_str(value);
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    /// The plugin type of `node` (its `type` attribute).
    pub fn plugin_type(&self, node: Node) -> Result<String> {
        self.attribute(node, "type")
    }

    /// The element `<ref id=..>` points to, or `node` itself when it is no reference.
    pub fn resolve(&self, node: Node<'a, 'input>) -> Result<Node<'a, 'input>> {
        if node.tag_name().name() != "ref" {
            return Ok(node);
        }
        let id = self.attribute(node, "id")?;
        self.ids
            .get(&id)
            .copied()
            .ok_or_else(|| self.error(node, format!("no element has the id '{id}'")))
    }

    /// A path the scene names, relative to its folder; a missing file is an error at `node`.
    pub fn existing_file(&self, node: Node, name: &str) -> Result<PathBuf> {
        let path = self.dir.join(name);
        if !path.is_file() {
            return Err(self.error(node, format!("the file '{}' does not exist", path.display())));
        }
        Ok(path)
    }
}

/// `<tag type="..">` or `<tag id="..">` or `<tag name="..">`, as messages show an element.
pub fn describe(node: Node) -> String {
    let mut s = format!("<{}", node.tag_name().name());
    for key in ["type", "id", "name"] {
        if let Some(v) = node.attribute(key) {
            s.push_str(&format!(" {key}=\"{v}\""));
        }
    }
    s + ">"
}

/// Mitsuba 0.5's camelCase parameter names as Mitsuba 3's snake_case (`toWorld` is
/// `to_world`, `intIOR` is `int_ior`).
pub fn snake_case(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut previous_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && previous_lower {
            out.push('_');
        }
        previous_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// Parses a list of numbers separated by commas or white space.
pub fn numbers(text: &str) -> Option<Vec<f32>> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect()
}

/// An RGB value of a property, or a texture giving it.
#[derive(Debug, Clone, Copy)]
pub enum Color<'a, 'input> {
    /// A constant.
    Rgb([f32; 3]),
    /// A `<texture>` element (resolved from a `<ref>`).
    Texture(Node<'a, 'input>),
}

/// The properties of one plugin element: its child elements, by snake_case name, each
/// marked once a converter reads it.
pub struct Props<'a, 'input> {
    node: Node<'a, 'input>,
    children: Vec<(Option<String>, Node<'a, 'input>, Cell<bool>)>,
}

impl<'a, 'input> Props<'a, 'input> {
    /// The properties of `node`.
    pub fn new(node: Node<'a, 'input>) -> Self {
        let children = node
            .children()
            .filter(|c| c.is_element())
            .map(|c| (c.attribute("name").map(snake_case), c, Cell::new(false)))
            .collect();
        Props { node, children }
    }

    /// The plugin element.
    pub fn node(&self) -> Node<'a, 'input> {
        self.node
    }

    /// The property element of `name` (marked as read).
    pub fn get(&self, name: &str) -> Option<Node<'a, 'input>> {
        let (_, node, used) = self.children.iter().find(|(n, ..)| n.as_deref() == Some(name))?;
        used.set(true);
        Some(*node)
    }

    /// The child elements of `tag` (`<ref>`s resolved), marked as read; `tag` "bsdf" also
    /// gives the references to bsdfs.
    pub fn nested(&self, ctx: &Context<'a, 'input>, tag: &str) -> Result<Vec<Node<'a, 'input>>> {
        let mut out = Vec::new();
        for (_, node, used) in &self.children {
            let name = node.tag_name().name();
            let target = if name == "ref" { ctx.resolve(*node)? } else { *node };
            if target.tag_name().name() == tag && (name == tag || name == "ref") {
                used.set(true);
                out.push(target);
            }
        }
        Ok(out)
    }

    /// The value of the typed property `name` (`<float>`, `<integer>`, `<string>`,
    /// `<boolean>`), as text.
    fn value(&self, ctx: &Context, name: &str, kinds: &[&str]) -> Result<Option<(Node<'a, 'input>, String)>> {
        let Some(node) = self.get(name) else { return Ok(None) };
        if !kinds.contains(&node.tag_name().name()) {
            return Err(ctx.error(node, format!("expected {} for '{name}'", kinds.join(" or "))));
        }
        Ok(Some((node, ctx.attribute(node, "value")?)))
    }

    /// A `<float>` (or `<integer>`) property.
    pub fn float(&self, ctx: &Context, name: &str) -> Result<Option<f32>> {
        let Some((node, text)) = self.value(ctx, name, &["float", "integer"])? else {
            return Ok(None);
        };
        match numbers(&text).as_deref() {
            Some([v]) => Ok(Some(*v)),
            _ => Err(ctx.error(node, format!("'{text}' is not a number"))),
        }
    }

    /// An `<integer>` property.
    pub fn integer(&self, ctx: &Context, name: &str) -> Result<Option<i64>> {
        let Some((node, text)) = self.value(ctx, name, &["integer"])? else {
            return Ok(None);
        };
        text.trim()
            .parse()
            .map(Some)
            .map_err(|_| ctx.error(node, format!("'{text}' is not an integer")))
    }

    /// A `<boolean>` property.
    pub fn boolean(&self, ctx: &Context, name: &str) -> Result<Option<bool>> {
        let Some((node, text)) = self.value(ctx, name, &["boolean"])? else {
            return Ok(None);
        };
        match text.trim() {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            _ => Err(ctx.error(node, format!("'{text}' is neither true nor false"))),
        }
    }

    /// The existing file named by the `filename` property (relative to the scene's folder);
    /// absent, an error "`what` needs a filename".
    pub fn file(&self, ctx: &Context, what: &str) -> Result<PathBuf> {
        let name = self
            .string(ctx, "filename")?
            .ok_or_else(|| ctx.error(self.node, format!("{what} needs a filename")))?;
        ctx.existing_file(self.node, &name)
    }

    /// A `<string>` property.
    pub fn string(&self, ctx: &Context, name: &str) -> Result<Option<String>> {
        Ok(self.value(ctx, name, &["string"])?.map(|(_, text)| text))
    }

    /// A `<point>` or `<vector>` property: `x`, `y`, `z` attributes or a `value` of three
    /// numbers.
    pub fn point(&self, ctx: &Context, name: &str) -> Result<Option<[f32; 3]>> {
        let Some(node) = self.get(name) else { return Ok(None) };
        point_of(ctx, node, 0.0).map(Some)
    }

    /// A colour property (`<rgb>`, `<srgb>`, `<spectrum>`, `<float>`) or a texture;
    /// spectra that are not constant are rendered as their mean, with a warning.
    pub fn color(&self, ctx: &mut Context<'a, 'input>, name: &str) -> Result<Option<Color<'a, 'input>>> {
        let Some(node) = self.get(name) else { return Ok(None) };
        let node = ctx.resolve(node)?;
        let kind = node.tag_name().name();
        if kind == "texture" {
            return Ok(Some(Color::Texture(node)));
        }
        let text = ctx.attribute(node, "value")?;
        let bad = |ctx: &Context| ctx.error(node, format!("'{text}' is not a colour"));
        let rgb = match kind {
            "rgb" | "srgb" | "float" | "color" => {
                let v = numbers(&text).ok_or_else(|| bad(ctx))?;
                let rgb = match v[..] {
                    [g] => [g; 3],
                    [r, g, b] => [r, g, b],
                    _ => return Err(bad(ctx)),
                };
                if kind == "srgb" { rgb.map(srgb_to_linear) } else { rgb }
            }
            "spectrum" if text.contains(':') => {
                let mut values = Vec::new();
                for pair in text.split(',') {
                    let v = pair.split(':').nth(1).and_then(|v| v.trim().parse::<f32>().ok());
                    values.push(v.filter(|v| v.is_finite()).ok_or_else(|| bad(ctx))?);
                }
                let mean = values.iter().sum::<f32>() / values.len() as f32;
                ctx.warn(node, format!("a spectrum is rendered as its mean value {mean}"));
                [mean; 3]
            }
            "spectrum" => match numbers(&text).as_deref() {
                Some([v]) => [*v; 3],
                _ => return Err(bad(ctx)),
            },
            _ => return Err(ctx.error(node, format!("expected a colour or a texture for '{name}'"))),
        };
        Ok(Some(Color::Rgb(rgb)))
    }

    /// Warns about every property no converter read, except [`HARMLESS`] ones.
    pub fn finish(&self, ctx: &mut Context) {
        for (name, node, used) in &self.children {
            let harmless = name.as_deref().is_some_and(|n| HARMLESS.contains(&n))
                || ["sampler", "rfilter"].contains(&node.tag_name().name());
            if !used.get() && !harmless {
                ctx.warn(*node, format!("ignored (not supported in {})", describe(self.node)));
            }
        }
    }
}

/// The point of `<point>`, `<vector>`, `<translate>` or `<scale>`: `x`, `y`, `z` attributes
/// (missing ones are `missing`) or a `value` of one or three numbers.
pub fn point_of(ctx: &Context, node: Node, missing: f32) -> Result<[f32; 3]> {
    if let Some(text) = ctx.optional_attribute(node, "value")? {
        return match numbers(&text).as_deref() {
            Some([v]) => Ok([*v; 3]),
            Some([x, y, z]) => Ok([*x, *y, *z]),
            _ => Err(ctx.error(node, format!("'{text}' is not one or three numbers"))),
        };
    }
    let mut p = [missing; 3];
    for (v, key) in p.iter_mut().zip(["x", "y", "z"]) {
        if let Some(text) = ctx.optional_attribute(node, key)? {
            *v = match numbers(&text).as_deref() {
                Some([x]) => *x,
                _ => return Err(ctx.error(node, format!("{key}='{text}' is not a number"))),
            };
        }
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_names_read_as_snake_case() {
        assert_eq!(snake_case("toWorld"), "to_world");
        assert_eq!(snake_case("intIOR"), "int_ior");
        assert_eq!(snake_case("diffuseReflectance"), "diffuse_reflectance");
        assert_eq!(snake_case("to_world"), "to_world");
        assert_eq!(snake_case("fovAxis"), "fov_axis");
    }

    #[test]
    fn numbers_split_on_commas_and_spaces() {
        assert_eq!(numbers("1, 2 3,4"), Some(vec![1.0, 2.0, 3.0, 4.0]));
        assert_eq!(numbers("1, x"), None);
        assert_eq!(numbers("nan"), None);
    }

    #[test]
    fn defaults_substitute_and_missing_parameters_are_errors_with_a_position() {
        let text = "<scene version=\"3.0.0\">\n<default name=\"w\" value=\"64\"/>\n<float name=\"a\" value=\"$w.5$x\"/></scene>";
        let doc = Document::parse(text).unwrap();
        let mut ctx = Context::new("s.xml", Path::new("."), &doc).unwrap();
        let nodes: Vec<Node> = doc.root_element().children().filter(|n| n.is_element()).collect();
        ctx.add_default(nodes[0]).unwrap();
        let e = ctx.attribute(nodes[1], "value").unwrap_err();
        assert_eq!(e.at, (3, 1));
        assert!(e.message.contains("'$x' has no value"), "{}", e.message);
        ctx.defaults.insert("x".into(), "7".into());
        assert_eq!(ctx.attribute(nodes[1], "value").unwrap(), "64.57");
    }

    #[test]
    fn unread_properties_are_warned_about_with_their_line() {
        let text = "<bsdf type=\"diffuse\">\n  <float name=\"alpha\" value=\"1\"/>\n  <string name=\"fileFormat\" value=\"exr\"/>\n</bsdf>";
        let doc = Document::parse(text).unwrap();
        let mut ctx = Context::new("s.xml", Path::new("."), &doc).unwrap();
        let props = Props::new(doc.root_element());
        props.finish(&mut ctx);
        assert_eq!(
            ctx.warnings,
            ["s.xml:2:3: <float name=\"alpha\">: ignored (not supported in <bsdf type=\"diffuse\">)"]
        );
    }

    #[test]
    fn colours_parse_from_rgb_srgb_and_spectra() {
        let text = "<b><rgb name=\"a\" value=\"0.1, 0.2, 0.3\"/><srgb name=\"b\" value=\"1\"/><spectrum name=\"c\" value=\"400:1, 500:3\"/><rgb name=\"d\" value=\"1 2\"/></b>";
        let doc = Document::parse(text).unwrap();
        let mut ctx = Context::new("s.xml", Path::new("."), &doc).unwrap();
        let props = Props::new(doc.root_element());
        let rgb = |c: Option<Color>| match c {
            Some(Color::Rgb(v)) => v,
            _ => panic!("not a constant"),
        };
        assert_eq!(rgb(props.color(&mut ctx, "a").unwrap()), [0.1, 0.2, 0.3]);
        assert_eq!(rgb(props.color(&mut ctx, "b").unwrap()), [1.0; 3]);
        assert_eq!(rgb(props.color(&mut ctx, "c").unwrap()), [2.0; 3]);
        assert_eq!(ctx.warnings.len(), 1);
        assert!(props.color(&mut ctx, "d").unwrap_err().message.contains("not a colour"));
    }
}
