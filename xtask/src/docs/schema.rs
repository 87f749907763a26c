//! The graph-file schema as engine/src/ir.rs declares it, read with `syn`: each struct's and
//! enum's doc comment, and each field's name (as serde reads it), type, default and doc
//! comment.

use std::collections::BTreeMap;
use syn::{Attribute, Expr, Fields, Item, Lit, Type};

/// The declarations of one source file, by type name, and the file's own doc comment.
pub struct Schema {
    /// The file's `//!` comment.
    pub doc: String,
    /// Structs and enums by name.
    pub types: BTreeMap<String, TypeDecl>,
    /// The body of each free function that is one expression, by name (serde's
    /// `default = "f"` functions).
    pub functions: BTreeMap<String, Expr>,
}

/// A struct or an enum.
pub struct TypeDecl {
    /// Its doc comment.
    pub doc: String,
    /// Its fields or variants.
    pub shape: Shape,
    /// `#[serde(untagged)]`: a value is written as one of the variants' contents.
    pub untagged: bool,
    /// It implements `Default` (derived or written).
    pub has_default: bool,
}

/// What a type is made of.
pub enum Shape {
    /// A struct's fields as serde reads them.
    Struct(Vec<Field>),
    /// An enum's variants.
    Enum(Vec<Variant>),
}

/// A field of a struct or of a struct variant.
pub struct Field {
    /// The name a file writes (serde's `rename` applied).
    pub name: String,
    /// Its Rust type.
    pub ty: Type,
    /// Its doc comment.
    pub doc: String,
    /// What an absent field is.
    pub default: FieldDefault,
}

/// What serde makes of a field a file leaves out.
#[derive(Clone, PartialEq, Debug)]
pub enum FieldDefault {
    /// An error: the field is required.
    Required,
    /// The type's `Default` (`#[serde(default)]`, on the field or the struct).
    TypeDefault,
    /// The value of a function (`#[serde(default = "f")]`).
    Function(String),
}

/// An enum variant.
pub struct Variant {
    /// Its name.
    pub name: String,
    /// Its doc comment.
    pub doc: String,
    /// What it holds.
    pub contents: Contents,
    /// It is the enum's `#[default]`.
    pub is_default: bool,
}

/// What a variant holds.
pub enum Contents {
    /// Nothing.
    Unit,
    /// Values in order.
    Tuple(Vec<Type>),
    /// Named fields.
    Struct(Vec<Field>),
}

/// Reads the declarations of `source` (the text of a Rust file).
pub fn read(source: &str) -> Result<Schema, String> {
    let file = syn::parse_file(source).map_err(|e| format!("cannot parse: {e}"))?;
    let mut types = BTreeMap::new();
    let mut functions = BTreeMap::new();
    let mut defaults = Vec::new();
    for item in file.items {
        match item {
            Item::Struct(s) => {
                let serde = serde_flags(&s.attrs)?;
                let shape = Shape::Struct(fields(&s.fields, serde.default)?);
                types.insert(s.ident.to_string(), type_decl(&s.attrs, &serde, shape));
            }
            Item::Enum(e) => {
                let serde = serde_flags(&e.attrs)?;
                let variants = e.variants.iter().map(variant).collect::<Result<Vec<_>, String>>()?;
                types.insert(e.ident.to_string(), type_decl(&e.attrs, &serde, Shape::Enum(variants)));
            }
            Item::Fn(f) => {
                if let [syn::Stmt::Expr(expr, None)] = f.block.stmts.as_slice() {
                    functions.insert(f.sig.ident.to_string(), expr.clone());
                }
            }
            Item::Impl(i) if i.trait_.as_ref().is_some_and(|(p, _)| p.is_ident("Default")) => {
                if let Type::Path(p) = &*i.self_ty {
                    defaults.extend(p.path.get_ident().map(|id| id.to_string()));
                }
            }
            _ => {}
        }
    }
    for name in defaults {
        if let Some(t) = types.get_mut(&name) {
            t.has_default = true;
        }
    }
    Ok(Schema {
        doc: doc(&file.attrs),
        types,
        functions,
    })
}

/// A struct or enum with attributes `attrs` (`serde` read from them) made of `shape`.
fn type_decl(attrs: &[Attribute], serde: &SerdeFlags, shape: Shape) -> TypeDecl {
    TypeDecl {
        doc: doc(attrs),
        shape,
        untagged: serde.untagged,
        has_default: derives(attrs, "Default"),
    }
}

/// An enum variant as a file writes it.
fn variant(v: &syn::Variant) -> Result<Variant, String> {
    let contents = match &v.fields {
        Fields::Unit => Contents::Unit,
        Fields::Unnamed(f) => Contents::Tuple(f.unnamed.iter().map(|f| f.ty.clone()).collect()),
        named => Contents::Struct(fields(named, false)?),
    };
    Ok(Variant {
        name: v.ident.to_string(),
        doc: doc(&v.attrs),
        contents,
        is_default: v.attrs.iter().any(|a| a.path().is_ident("default")),
    })
}

/// The serde attributes of a struct or enum that change how it is written.
#[derive(Default)]
struct SerdeFlags {
    /// `default`: every absent field takes its type's default.
    default: bool,
    /// `untagged`.
    untagged: bool,
}

fn serde_flags(attrs: &[Attribute]) -> Result<SerdeFlags, String> {
    let mut flags = SerdeFlags::default();
    for attr in attrs.iter().filter(|a| a.path().is_ident("serde")) {
        attr.parse_nested_meta(|meta| {
            if meta.path.is_ident("default") {
                flags.default = true;
            } else if meta.path.is_ident("untagged") {
                flags.untagged = true;
            } else if !meta.path.is_ident("deny_unknown_fields") {
                return Err(meta.error("a serde attribute the reference does not know"));
            }
            Ok(())
        })
        .map_err(|e| e.to_string())?;
    }
    Ok(flags)
}

/// The fields a file may write (those serde skips left out), each absent one taking its type's
/// default when `all_default`.
fn fields(fields: &Fields, all_default: bool) -> Result<Vec<Field>, String> {
    let mut out = Vec::new();
    for f in fields {
        let mut name = f.ident.as_ref().map(|i| i.to_string()).unwrap_or_default();
        let mut default = if all_default {
            FieldDefault::TypeDefault
        } else {
            FieldDefault::Required
        };
        let mut skip = false;
        for attr in f.attrs.iter().filter(|a| a.path().is_ident("serde")) {
            attr.parse_nested_meta(|meta| {
                if meta.path.is_ident("default") {
                    default = match meta.value() {
                        Ok(v) => FieldDefault::Function(v.parse::<syn::LitStr>()?.value()),
                        Err(_) => FieldDefault::TypeDefault,
                    };
                } else if meta.path.is_ident("rename") {
                    name = meta.value()?.parse::<syn::LitStr>()?.value();
                } else if meta.path.is_ident("skip") {
                    skip = true;
                } else {
                    return Err(meta.error("a serde attribute the reference does not know"));
                }
                Ok(())
            })
            .map_err(|e| format!("field `{name}`: {e}"))?;
        }
        if !skip {
            out.push(Field {
                name,
                ty: f.ty.clone(),
                doc: doc(&f.attrs),
                default,
            });
        }
    }
    Ok(out)
}

/// The doc comment of an item: its `///` (or `//!`) lines without the one leading space each
/// has, joined by newlines.
fn doc(attrs: &[Attribute]) -> String {
    let lines: Vec<String> = attrs
        .iter()
        .filter(|a| a.path().is_ident("doc"))
        .filter_map(|a| match &a.meta {
            syn::Meta::NameValue(nv) => match &nv.value {
                Expr::Lit(syn::ExprLit { lit: Lit::Str(s), .. }) => Some(s.value()),
                _ => None,
            },
            _ => None,
        })
        .map(|l| l.strip_prefix(' ').unwrap_or(&l).trim_end().to_string())
        .collect();
    lines.join("\n").trim().to_string()
}

/// Whether `#[derive(...)]` names `name`.
fn derives(attrs: &[Attribute], name: &str) -> bool {
    attrs.iter().filter(|a| a.path().is_ident("derive")).any(|a| {
        let mut found = false;
        let _ = a.parse_nested_meta(|meta| {
            found |= meta.path.is_ident(name);
            Ok(())
        });
        found
    })
}

#[cfg(test)]
mod tests {
    use super::{Contents, FieldDefault, Shape, read};

    #[test]
    fn fields_carry_serde_names_defaults_and_docs() {
        let schema = read(
            r#"
            //! The file.
            /// A thing.
            #[derive(Deserialize)]
            #[serde(deny_unknown_fields)]
            pub struct Thing {
                /// Its name.
                pub name: String,
                /// Listed.
                #[serde(default, rename = "reads")]
                pub listed: Option<Vec<String>>,
                #[serde(skip)]
                pub reads: Vec<String>,
                /// Size.
                #[serde(default = "four")]
                pub size: u32,
            }
            fn four() -> u32 { 4 }
            /// A kind.
            #[derive(Default)]
            pub enum Kind { /// A.
            #[default] A, B(u32), C { x: f32 } }
            "#,
        )
        .unwrap();
        assert_eq!(schema.doc, "The file.");
        let Shape::Struct(fields) = &schema.types["Thing"].shape else {
            panic!()
        };
        let names: Vec<_> = fields.iter().map(|f| (f.name.as_str(), f.default.clone())).collect();
        assert_eq!(
            names,
            [
                ("name", FieldDefault::Required),
                ("reads", FieldDefault::TypeDefault),
                ("size", FieldDefault::Function("four".into()))
            ]
        );
        assert_eq!(fields[1].doc, "Listed.");
        assert!(schema.functions.contains_key("four"));
        let kind = &schema.types["Kind"];
        assert!(kind.has_default);
        let Shape::Enum(variants) = &kind.shape else { panic!() };
        assert!(variants[0].is_default && variants[0].doc == "A.");
        assert!(matches!(variants[1].contents, Contents::Tuple(ref t) if t.len() == 1));
        assert!(matches!(variants[2].contents, Contents::Struct(ref f) if f[0].name == "x"));
    }

    #[test]
    fn an_unknown_serde_attribute_is_an_error() {
        let err = read("struct A { #[serde(flatten)] b: B }").err().unwrap();
        assert!(err.contains("`b`") && err.contains("does not know"), "{err}");
    }
}
