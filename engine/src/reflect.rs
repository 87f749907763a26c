//! The reflect stage: a planned graph's WGSL sources compiled together with naga, each live pass
//! function checked against its declaration (signature, resources, emits, no parameter
//! written), and reflection over naga's view of WGSL types: struct layouts from naga's
//! layouter, and the flattening of item structs into 32-bit words for state buffers and
//! queues ([`crate::access`] finds which of them each pass touches).

use crate::error::{Error, Result};
use crate::ir::Role;
use crate::plan::Plan;
use crate::wgsl::{ModuleSource, callees};
use naga::{Module, ScalarKind, TypeInner};
use std::collections::BTreeSet;

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

/// The module of every source of `plan` compiled together between `prelude` and `emits` (the
/// declarations and the emits that do nothing, as code generation writes them), after each
/// live pass function is checked against its declaration.
pub fn reflect(
    plan: &Plan,
    sources: &[(String, String)],
    prelude: &str,
    emits: &str,
    capabilities: naga::valid::Capabilities,
) -> Result<Module> {
    let mut reflection = ModuleSource::default();
    reflection.push("<generated prelude>", prelude);
    for (f, text) in sources {
        reflection.push(f, text);
    }
    reflection.push("<generated emits>", emits);
    let (module, info) = reflection.compile(capabilities)?;
    check_passes(plan, &module, &info)?;
    Ok(module)
}

/// Checks every live pass function against its declaration: signature, resource use,
/// emits; and that no pass writes a parameter.
fn check_passes(plan: &Plan, module: &naga::Module, info: &naga::valid::ModuleInfo) -> Result<()> {
    let g = &plan.graph;
    let find_fn = |name: &str| {
        module
            .functions
            .iter()
            .find(|(_, f)| f.name.as_deref() == Some(name))
            .map(|(h, _)| h)
    };
    let type_name = |ty: naga::Handle<naga::Type>| {
        module.types[ty]
            .name
            .clone()
            .unwrap_or_else(|| format!("{:?}", module.types[ty].inner))
    };
    for p in &g.passes {
        let d = &p.decl;
        let fname = p.function();
        let expected = match d.role {
            Role::Start { .. } => format!("fn {fname}(item: ptr<function, {}>, index: u32) -> bool", d.item),
            _ => format!("fn {fname}(item: ptr<function, {}>) -> bool", d.item),
        };
        let bad = |why: String| Error::Shader(format!("{}: pass '{}': {why}; expected `{expected}`", d.source, d.name));
        let h = find_fn(fname).ok_or_else(|| bad(format!("no function '{fname}' in {}", d.source)))?;
        let f = &module.functions[h];
        let want_args = if matches!(d.role, Role::Start { .. }) { 2 } else { 1 };
        if f.arguments.len() != want_args {
            return Err(bad(format!("it takes {} arguments", f.arguments.len())));
        }
        match &module.types[f.arguments[0].ty].inner {
            naga::TypeInner::Pointer {
                base,
                space: naga::AddressSpace::Function,
            } if type_name(*base) == d.item => {}
            _ => {
                return Err(bad(format!("its first argument is {}", type_name(f.arguments[0].ty))));
            }
        }
        if want_args == 2
            && !matches!(
                module.types[f.arguments[1].ty].inner,
                naga::TypeInner::Scalar(naga::Scalar::U32)
            )
        {
            return Err(bad("its second argument is not u32".into()));
        }
        match &f.result {
            Some(r) if matches!(module.types[r.ty].inner, naga::TypeInner::Scalar(naga::Scalar::BOOL)) => {}
            _ => return Err(bad("it does not return bool".into())),
        }
        let fi = &info[h];
        for (gh, var) in module.global_variables.iter() {
            let Some(name) = var.name.as_deref() else {
                continue;
            };
            let uses = fi[gh];
            if g.parameters.contains_key(name) && uses.contains(naga::valid::GlobalUse::WRITE) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' writes parameter '{name}'; parameters are set by the host ({})",
                    d.source, d.name, p.origin
                )));
            }
            let Some(r) = g.resource_id(name) else {
                continue;
            };
            if uses.contains(naga::valid::GlobalUse::WRITE) && !p.writes.contains(&r) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' writes resource '{name}' but does not declare it in `writes` ({})",
                    d.source, d.name, p.origin
                )));
            }
            if !uses.is_empty() && !p.reads.iter().chain(&p.writes).any(|&w| w == r) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' reads resource '{name}' but does not declare it in `reads` ({})",
                    d.source, d.name, p.origin
                )));
            }
        }
        let called: BTreeSet<String> = callees(module, vec![h])
            .iter()
            .filter_map(|&c| module.functions[c].name.clone())
            .collect();
        for id in g.stream_ids() {
            let s = &g.streams[id].name;
            if called.contains(&format!("emit_{s}")) && !p.emits.contains(&id) {
                return Err(Error::Shader(format!(
                    "{}: pass '{}' calls emit_{s} but does not declare `emits: [\"{s}\"]` ({})",
                    d.source, d.name, p.origin
                )));
            }
        }
    }
    Ok(())
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
