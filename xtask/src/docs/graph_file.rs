//! docs/reference/graph-file.md: the graph-file schema of engine/src/ir.rs in Markdown. Each
//! type reachable from the files' roots gets a section (in the order the roots reach them):
//! its doc comment, then each field with its RON type, whether it may be left out (and what it
//! then is) and its doc comment, or each variant with what it holds.

use super::schema::{Contents, Field, FieldDefault, Schema, Shape, TypeDecl};
use std::collections::BTreeSet;
use syn::{Expr, GenericArgument, Lit, PathArguments, Type};

/// The types a file is read as: a graph, a graph that extends another, a catalog.
const ROOTS: [&str; 3] = ["GraphFile", "ExtendingFile", "CatalogFile"];

/// The reference of `schema` (engine/src/ir.rs, read).
pub fn markdown(schema: &Schema) -> Result<String, String> {
    check_extending(schema)?;
    let order = reachable(schema)?;
    let mut out = String::from(
        "# The graph file\n\n<!-- Generated from the doc comments of engine/src/ir.rs by `cargo xtask docs`: edit \
         those, not this file. -->\n\nEvery field of a graph file, a graph that extends another and a pass catalog. How \
         passes, chains, layouts and frames work, with examples: [Writing frame graphs](../graphs.md).\n\n",
    );
    out.push_str(&text(schema, &order, &schema.doc, ""));
    out.push_str("\n\nTypes:\n\n");
    for name in &order {
        out.push_str(&format!("- [`{name}`](#{})\n", name.to_lowercase()));
    }
    for name in &order {
        section(&mut out, schema, &order, name)?;
    }
    Ok(out)
}

/// Every field of `GraphFile` has its override in `ExtendingFile`, which adds only `extends`.
fn check_extending(schema: &Schema) -> Result<(), String> {
    let names = |t: &str| -> Result<BTreeSet<String>, String> {
        match schema.types.get(t).map(|t| &t.shape) {
            Some(Shape::Struct(fields)) => Ok(fields.iter().map(|f| f.name.clone()).collect()),
            _ => Err(format!("no struct {t}")),
        }
    };
    let (whole, extending) = (names("GraphFile")?, names("ExtendingFile")?);
    let missing: Vec<_> = whole.difference(&extending).collect();
    let extra: Vec<_> = extending.difference(&whole).filter(|f| *f != "extends").collect();
    if missing.is_empty() && extra.is_empty() {
        return Ok(());
    }
    Err(format!(
        "ExtendingFile should have every field of GraphFile and `extends`: it lacks {missing:?} and adds {extra:?}"
    ))
}

/// The schema's types that the roots reach through fields and variants, depth first: each type
/// right after the first type that names it.
fn reachable(schema: &Schema) -> Result<Vec<String>, String> {
    let mut order = Vec::new();
    for root in ROOTS {
        visit(schema, root, &mut order)?;
    }
    Ok(order)
}

/// Adds `name` and, after it, the types it names that `order` lacks.
fn visit(schema: &Schema, name: &str, order: &mut Vec<String>) -> Result<(), String> {
    if order.iter().any(|n| n == name) {
        return Ok(());
    }
    let decl = schema.types.get(name).ok_or_else(|| format!("no type {name}"))?;
    order.push(name.to_string());
    let mut tys: Vec<&Type> = Vec::new();
    match &decl.shape {
        Shape::Struct(fields) => tys.extend(fields.iter().map(|f| &f.ty)),
        Shape::Enum(variants) => {
            for v in variants {
                match &v.contents {
                    Contents::Unit => {}
                    Contents::Tuple(t) => tys.extend(t),
                    Contents::Struct(fields) => tys.extend(fields.iter().map(|f| &f.ty)),
                }
            }
        }
    }
    let mut named = Vec::new();
    for ty in tys {
        named_types(ty, &mut named);
    }
    for n in named.iter().filter(|n| schema.types.contains_key(*n)) {
        visit(schema, n, order)?;
    }
    Ok(())
}

/// The last path segment of each type named in `ty`, its arguments' included.
fn named_types(ty: &Type, out: &mut Vec<String>) {
    match ty {
        Type::Path(p) => {
            for seg in &p.path.segments {
                out.push(seg.ident.to_string());
                if let PathArguments::AngleBracketed(args) = &seg.arguments {
                    for arg in &args.args {
                        if let GenericArgument::Type(t) = arg {
                            named_types(t, out);
                        }
                    }
                }
            }
        }
        Type::Tuple(t) => t.elems.iter().for_each(|t| named_types(t, out)),
        _ => {}
    }
}

/// The section of type `name`.
fn section(out: &mut String, schema: &Schema, order: &[String], name: &str) -> Result<(), String> {
    let decl = &schema.types[name];
    out.push_str(&format!("\n## `{name}`\n\n"));
    if !decl.doc.is_empty() {
        out.push_str(&text(schema, order, &decl.doc, ""));
        out.push_str("\n\n");
    }
    match &decl.shape {
        Shape::Struct(fields) => {
            out.push_str("Fields:\n\n");
            for f in fields {
                field_item(out, schema, order, f, "").map_err(|e| format!("{name}::{}: {e}", f.name))?;
            }
        }
        Shape::Enum(variants) => {
            out.push_str(if decl.untagged {
                "Written as one of:\n\n"
            } else {
                "One of:\n\n"
            });
            for v in variants {
                let head = match &v.contents {
                    Contents::Unit => format!("`{}`", v.name),
                    Contents::Tuple(tys) if decl.untagged => {
                        tys.iter().map(|t| ron_type(schema, t)).collect::<Vec<_>>().join(", ")
                    }
                    Contents::Tuple(tys) => match tys.as_slice() {
                        [Type::Path(p)] if is_struct(schema, &last_ident(p)) => {
                            let inner = last_ident(p);
                            format!(
                                "`{}(...)` with the fields of [`{inner}`](#{})",
                                v.name,
                                inner.to_lowercase()
                            )
                        }
                        _ => {
                            let mut parts = vec![Part::Plain(format!("{}(", v.name))];
                            for (i, t) in tys.iter().enumerate() {
                                if i > 0 {
                                    parts.push(Part::Plain(", ".into()));
                                }
                                type_parts(schema, t, &mut parts);
                            }
                            parts.push(Part::Plain(")".into()));
                            spans(parts)
                        }
                    },
                    Contents::Struct(fields) => {
                        let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
                        format!("`{}({})`", v.name, names.join(", "))
                    }
                };
                let default = if v.is_default { " (the default)" } else { "" };
                let doc = text(schema, order, &v.doc, "  ");
                out.push_str(&format!("- {head}{default}: {doc}\n"));
                if let Contents::Struct(fields) = &v.contents {
                    for f in fields {
                        field_item(out, schema, order, f, "  ").map_err(|e| format!("{name}::{}: {e}", v.name))?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// One list item for field `f`, indented by `indent`: name, RON type, default, doc comment. A
/// field whose doc comment is only a link to another type's field (`[`T::f`]`) is described
/// by that field's doc comment and default.
fn field_item(out: &mut String, schema: &Schema, order: &[String], f: &Field, indent: &str) -> Result<(), String> {
    let (doc, default) = match linked_field(schema, &f.doc) {
        Some(target) => (target.doc.as_str(), default_of(schema, &target.ty, &target.default)?),
        None => (f.doc.as_str(), default_of(schema, &f.ty, &f.default)?),
    };
    let ty = ron_type(schema, &f.ty);
    let doc = text(schema, order, doc, &format!("{indent}  "));
    out.push_str(&format!("{indent}- `{}` ({ty}, {default}): {doc}\n", f.name));
    Ok(())
}

/// The field `doc` consists of a link to (`[`T::f`]`), if any.
fn linked_field<'a>(schema: &'a Schema, doc: &str) -> Option<&'a Field> {
    let (t, f) = doc.strip_prefix("[`")?.strip_suffix("`].")?.split_once("::")?;
    match &schema.types.get(t)?.shape {
        Shape::Struct(fields) => fields.iter().find(|x| x.name == f),
        Shape::Enum(_) => None,
    }
}

/// "required", "optional", or "default `V`": what a field of type `ty` that a file leaves out is.
fn default_of(schema: &Schema, ty: &Type, default: &FieldDefault) -> Result<String, String> {
    let Type::Path(p) = ty else {
        return match default {
            FieldDefault::Required => Ok("required".into()),
            _ => Err("a default of a type that is not a path".into()),
        };
    };
    let name = last_ident(p);
    match default {
        FieldDefault::Required if name == "Option" => Ok("optional".into()),
        FieldDefault::Required => Ok("required".into()),
        FieldDefault::Function(f) => {
            let expr = schema
                .functions
                .get(f)
                .ok_or_else(|| format!("no one-expression function {f}"))?;
            Ok(format!("default `{}`", ron_value(schema, expr)?))
        }
        FieldDefault::TypeDefault => {
            let value = match name.as_str() {
                "Option" => return Ok("optional".into()),
                "Vec" => "[]".to_string(),
                "BTreeMap" | "HashMap" => "{}".to_string(),
                "String" => "\"\"".to_string(),
                "bool" => "false".to_string(),
                "u32" | "u64" | "i32" | "usize" => "0".to_string(),
                "f32" | "f64" => "0.0".to_string(),
                _ => match schema.types.get(&name) {
                    Some(TypeDecl {
                        shape: Shape::Enum(variants),
                        ..
                    }) => variants
                        .iter()
                        .find(|v| v.is_default)
                        .map(|v| v.name.clone())
                        .ok_or_else(|| format!("{name} has no #[default] variant"))?,
                    Some(TypeDecl { has_default: true, .. }) => {
                        return Ok("optional: each of its fields' defaults".into());
                    }
                    _ => return Err(format!("no default known for {name}")),
                },
            };
            Ok(format!("default `{value}`"))
        }
    }
}

/// A default function's expression as a file writes the value: a literal, or a variant with its
/// arguments (only the arguments for an untagged enum's).
fn ron_value(schema: &Schema, expr: &Expr) -> Result<String, String> {
    match expr {
        Expr::Lit(l) => match &l.lit {
            Lit::Int(i) => Ok(i.base10_digits().to_string()),
            Lit::Float(f) => Ok(f.base10_digits().to_string()),
            Lit::Bool(b) => Ok(b.value.to_string()),
            Lit::Str(s) => Ok(format!("{:?}", s.value())),
            _ => Err("a literal the reference cannot write".into()),
        },
        Expr::Call(call) => {
            let Expr::Path(path) = &*call.func else {
                return Err("a call of something other than a variant".into());
            };
            let segments: Vec<String> = path.path.segments.iter().map(|s| s.ident.to_string()).collect();
            let args = call
                .args
                .iter()
                .map(|a| ron_value(schema, a))
                .collect::<Result<Vec<_>, _>>()?
                .join(", ");
            let untagged = segments.len() >= 2
                && schema
                    .types
                    .get(&segments[segments.len() - 2])
                    .is_some_and(|t| t.untagged);
            Ok(if untagged {
                args
            } else {
                format!("{}({args})", segments.last().unwrap())
            })
        }
        Expr::Path(path) => Ok(path
            .path
            .segments
            .last()
            .map(|s| s.ident.to_string())
            .unwrap_or_default()),
        _ => Err("a default function that is not a literal or a variant".into()),
    }
}

/// A type as a RON file writes it, in Markdown: `[T]` for a list, `{K: V}` for a map, `(A, B)`
/// for a tuple, `T` for an `Option<T>`, the schema's types linked to their sections.
fn ron_type(schema: &Schema, ty: &Type) -> String {
    let mut parts = Vec::new();
    type_parts(schema, ty, &mut parts);
    spans(parts)
}

/// `parts` in Markdown: runs of plain text as one code span, each linked type a code span of
/// its own.
fn spans(parts: Vec<Part>) -> String {
    // Runs of plain text become one code span; each linked type is a code span of its own.
    let mut out = String::new();
    let mut plain = String::new();
    for part in parts {
        match part {
            Part::Plain(s) => plain.push_str(&s),
            Part::Link(name) => {
                if !plain.is_empty() {
                    out.push_str(&format!("`{plain}`"));
                    plain.clear();
                }
                out.push_str(&format!("[`{name}`](#{})", name.to_lowercase()));
            }
        }
    }
    if !plain.is_empty() {
        out.push_str(&format!("`{plain}`"));
    }
    out
}

/// A piece of a written type.
enum Part {
    Plain(String),
    Link(String),
}

fn type_parts(schema: &Schema, ty: &Type, out: &mut Vec<Part>) {
    match ty {
        Type::Path(p) => {
            let name = last_ident(p);
            let args: Vec<&Type> = match &p.path.segments.last().unwrap().arguments {
                PathArguments::AngleBracketed(a) => a
                    .args
                    .iter()
                    .filter_map(|a| match a {
                        GenericArgument::Type(t) => Some(t),
                        _ => None,
                    })
                    .collect(),
                _ => Vec::new(),
            };
            match (name.as_str(), args.as_slice()) {
                ("Option" | "Box", [t]) => type_parts(schema, t, out),
                ("Vec", [t]) => {
                    out.push(Part::Plain("[".into()));
                    type_parts(schema, t, out);
                    out.push(Part::Plain("]".into()));
                }
                ("BTreeMap" | "HashMap", [k, v]) => {
                    out.push(Part::Plain("{".into()));
                    type_parts(schema, k, out);
                    out.push(Part::Plain(": ".into()));
                    type_parts(schema, v, out);
                    out.push(Part::Plain("}".into()));
                }
                _ if schema.types.contains_key(&name) => out.push(Part::Link(name)),
                _ => out.push(Part::Plain(name)),
            }
        }
        Type::Tuple(t) => {
            out.push(Part::Plain("(".into()));
            for (i, e) in t.elems.iter().enumerate() {
                if i > 0 {
                    out.push(Part::Plain(", ".into()));
                }
                type_parts(schema, e, out);
            }
            out.push(Part::Plain(")".into()));
        }
        _ => out.push(Part::Plain("?".into())),
    }
}

fn last_ident(p: &syn::TypePath) -> String {
    p.path.segments.last().map(|s| s.ident.to_string()).unwrap_or_default()
}

fn has_field(schema: &Schema, ty: &str, field: &str) -> bool {
    matches!(&schema.types[ty].shape, Shape::Struct(fields) if fields.iter().any(|f| f.name == field))
}

fn is_struct(schema: &Schema, name: &str) -> bool {
    schema
        .types
        .get(name)
        .is_some_and(|t| matches!(t.shape, Shape::Struct(_)))
}

/// A doc comment as Markdown: rustdoc's links to the types in `order` and their fields
/// (`[`T`]`, `[`T::f`]`) made links to their sections, other rustdoc links plain code; lines
/// after the first indented by `indent` (inside a list item).
fn text(schema: &Schema, order: &[String], doc: &str, indent: &str) -> String {
    let mut out = String::new();
    let mut rest = doc;
    while let Some(start) = rest.find("[`") {
        let Some(len) = rest[start..].find("`]") else { break };
        let target = &rest[start + 2..start + len];
        let after = &rest[start + len + 2..];
        out.push_str(&rest[..start]);
        if after.starts_with('(') {
            // Already a Markdown link.
            out.push_str(&rest[start..start + len + 2]);
        } else {
            let ty = target.split("::").next().unwrap_or(target);
            let field = target.split("::").nth(1);
            let documented = order.iter().any(|t| t == ty) && field.is_none_or(|f| has_field(schema, ty, f));
            if documented {
                out.push_str(&format!("[`{target}`](#{})", ty.to_lowercase()));
            } else {
                out.push_str(&format!("`{target}`"));
            }
        }
        rest = after;
    }
    out.push_str(rest);
    out.replace('\n', &format!("\n{indent}"))
        .replace(&format!("\n{indent}\n"), "\n\n")
}

#[cfg(test)]
mod tests {
    use super::markdown;
    use crate::docs::schema::read;

    /// A schema of the three roots with the types they name.
    fn schema(extending_fields: &str) -> String {
        format!(
            r#"
            //! Graph files.
            /// A graph.
            pub struct GraphFile {{
                /// Its name.
                pub name: String,
                /// Its passes, see [`Pass`].
                #[serde(default)]
                pub passes: Vec<Pass>,
                /// Its layout.
                #[serde(default)]
                pub layout: LayoutWritten,
            }}
            /// Extends.
            pub struct ExtendingFile {{
                /// The base.
                pub extends: String,
                {extending_fields}
            }}
            /// A catalog.
            pub struct CatalogFile {{
                /// Constants.
                #[serde(default)]
                pub constants: BTreeMap<String, Value>,
            }}
            /// A pass.
            pub enum Pass {{
                /// By name.
                Use(String),
                /// Inline.
                Inline(CatalogFile),
                /// Counted.
                Start {{
                    /// Over.
                    over: String,
                }},
            }}
            /// A value.
            #[serde(untagged)]
            pub enum Value {{ /// A number.
            Number(u32), /// An expression.
            Expr(String) }}
            /// The layout.
            pub struct LayoutDecl {{
                /// Threads per workgroup.
                #[serde(default = "sixty_four")]
                pub workgroup_size: u32,
            }}
            /// As written.
            #[derive(Default)]
            #[serde(default)]
            pub struct LayoutWritten {{
                /// [`LayoutDecl::workgroup_size`].
                pub workgroup_size: Option<u32>,
                /// The value.
                #[serde(default = "one")]
                pub value: Value,
            }}
            fn sixty_four() -> u32 {{ 64 }}
            fn one() -> Value {{ Value::Number(1) }}
            "#
        )
    }

    #[test]
    fn sections_show_types_defaults_and_docs() {
        let s = read(&schema(
            "/// Name.\n pub name: Option<String>, /// Passes.\n pub passes: Vec<u32>, /// Layout.\n pub layout: Option<LayoutWritten>,",
        ))
        .unwrap();
        let md = markdown(&s).unwrap();
        for expected in [
            "Graph files.\n\nTypes:\n\n- [`GraphFile`](#graphfile)\n- [`Pass`](#pass)\n- [`CatalogFile`](#catalogfile)\n- [`Value`](#value)\n- [`LayoutWritten`](#layoutwritten)\n- [`ExtendingFile`](#extendingfile)\n",
            "- `name` (`String`, required): Its name.",
            "- `passes` (`[`[`Pass`](#pass)`]`, default `[]`): Its passes, see [`Pass`](#pass).",
            "- `layout` ([`LayoutWritten`](#layoutwritten), optional: each of its fields' defaults): Its layout.",
            "- `constants` (`{String: `[`Value`](#value)`}`, default `{}`): Constants.",
            "- `Use(String)`: By name.",
            "- `Inline(...)` with the fields of [`CatalogFile`](#catalogfile): Inline.",
            "- `Start(over)`: Counted.\n  - `over` (`String`, required): Over.",
            "Written as one of:\n\n- `u32`: A number.",
            "- `workgroup_size` (`u32`, default `64`): Threads per workgroup.",
            "- `value` ([`Value`](#value), default `1`): The value.",
        ] {
            assert!(md.contains(expected), "missing {expected:?} in:\n{md}");
        }
        assert!(
            !md.contains("## `LayoutDecl`"),
            "a type only linked to gets no section:\n{md}"
        );
    }

    #[test]
    fn an_extending_file_without_a_graph_field_is_an_error() {
        let s = read(&schema("/// Name.\n pub name: Option<String>,")).unwrap();
        let err = markdown(&s).unwrap_err();
        assert!(err.contains("lacks [\"layout\", \"passes\"]"), "{err}");
    }
}
