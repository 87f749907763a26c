//! Reflection over naga's view of WGSL types: struct layouts from naga's layouter, and the
//! flattening of item structs into 32-bit words for state buffers and queues.

use naga::{Module, ScalarKind, TypeInner};

/// One 32-bit word of a flattened item: how to reach it and what it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Word {
    /// Access path from the item, e.g. `.origin.x` or `.vertices[2].y`.
    pub path: String,
    /// WGSL scalar type of the word: `f32`, `u32` or `i32`.
    pub scalar: &'static str,
}

/// Finds the type called `name`.
pub fn find_type(module: &Module, name: &str) -> Option<naga::Handle<naga::Type>> {
    module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .map(|(h, _)| h)
}

/// Flattens the struct `name` into words, in declaration order; bools, atomics, pointers
/// and runtime-sized arrays cannot be stored and give an error naming the field.
pub fn flatten(module: &Module, name: &str) -> Result<Vec<Word>, String> {
    let ty = find_type(module, name).ok_or_else(|| format!("item type '{name}' is not defined in the WGSL sources"))?;
    if !matches!(module.types[ty].inner, TypeInner::Struct { .. }) {
        return Err(format!("item type '{name}' is not a struct"));
    }
    let mut out = Vec::new();
    flatten_into(module, ty, String::new(), name, &mut out)?;
    Ok(out)
}

fn scalar_name(kind: ScalarKind, width: u8, field: &str, item: &str) -> Result<&'static str, String> {
    match (kind, width) {
        (ScalarKind::Float, 4) => Ok("f32"),
        (ScalarKind::Uint, 4) => Ok("u32"),
        (ScalarKind::Sint, 4) => Ok("i32"),
        (ScalarKind::Bool, _) => Err(format!(
            "field '{field}' of item '{item}' is a bool, which cannot be stored between kernels; use u32"
        )),
        _ => Err(format!(
            "field '{field}' of item '{item}' has a {width}-byte {kind:?} scalar; items hold 32-bit scalars"
        )),
    }
}

fn flatten_into(
    module: &Module,
    ty: naga::Handle<naga::Type>,
    path: String,
    item: &str,
    out: &mut Vec<Word>,
) -> Result<(), String> {
    const COMPONENTS: [&str; 4] = ["x", "y", "z", "w"];
    match &module.types[ty].inner {
        TypeInner::Scalar(s) => out.push(Word {
            scalar: scalar_name(s.kind, s.width, &path, item)?,
            path,
        }),
        TypeInner::Vector { size, scalar } => {
            let name = scalar_name(scalar.kind, scalar.width, &path, item)?;
            for c in COMPONENTS.iter().take(*size as usize) {
                out.push(Word {
                    path: format!("{path}.{c}"),
                    scalar: name,
                });
            }
        }
        TypeInner::Matrix { columns, rows, scalar } => {
            let name = scalar_name(scalar.kind, scalar.width, &path, item)?;
            for col in 0..*columns as usize {
                for c in COMPONENTS.iter().take(*rows as usize) {
                    out.push(Word {
                        path: format!("{path}[{col}].{c}"),
                        scalar: name,
                    });
                }
            }
        }
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => {
            for i in 0..n.get() {
                flatten_into(module, *base, format!("{path}[{i}]"), item, out)?;
            }
        }
        TypeInner::Struct { members, .. } => {
            for m in members {
                let field = m.name.clone().unwrap_or_default();
                flatten_into(module, m.ty, format!("{path}.{field}"), item, out)?;
            }
        }
        other => {
            return Err(format!(
                "field '{path}' of item '{item}' has type {other:?}, which cannot be stored between kernels"
            ));
        }
    }
    Ok(())
}

/// Byte size of one element of the global variable `name`: the array stride for an array,
/// the type's size otherwise.
pub fn element_size(module: &Module, name: &str) -> Option<u32> {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    let (_, var) = module
        .global_variables
        .iter()
        .find(|(_, v)| v.name.as_deref() == Some(name))?;
    Some(match &module.types[var.ty].inner {
        TypeInner::Array { stride, .. } => *stride,
        _ => layouter[var.ty].size,
    })
}

/// Byte size and per-member `(name, offset)` of the struct `name`, from naga's layouter.
pub fn struct_layout(module: &Module, name: &str) -> Option<(u32, Vec<(String, u32)>)> {
    let ty = find_type(module, name)?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    match &module.types[ty].inner {
        TypeInner::Struct { members, span } => Some((
            *span,
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flattens_nested_structs_vectors_and_arrays() {
        let m = naga::front::wgsl::parse_str(
            "struct Inner { a: vec2<f32>, b: array<u32, 2> }
             struct Item { p: vec3<f32>, n: i32, inner: Inner, m: mat2x2<f32> }",
        )
        .unwrap();
        let words = flatten(&m, "Item").unwrap();
        let paths: Vec<&str> = words.iter().map(|w| w.path.as_str()).collect();
        assert_eq!(
            paths,
            vec![
                ".p.x",
                ".p.y",
                ".p.z",
                ".n",
                ".inner.a.x",
                ".inner.a.y",
                ".inner.b[0]",
                ".inner.b[1]",
                ".m[0].x",
                ".m[0].y",
                ".m[1].x",
                ".m[1].y"
            ]
        );
        assert_eq!(words[3].scalar, "i32");
        let (size, members) = struct_layout(&m, "Item").unwrap();
        assert_eq!(members[1], ("n".to_string(), 12));
        assert_eq!(size, 48);
    }

    #[test]
    fn refuses_bools() {
        let m = naga::front::wgsl::parse_str("struct Item { alive: bool }").unwrap();
        let err = flatten(&m, "Item").unwrap_err();
        assert!(err.contains("alive") && err.contains("bool"), "{err}");
    }
}
