//! Fields a graph adds to item structs (`item_fields: {"MergePath": [("caustic", "u32")]}`):
//! checked where the graph is loaded, then written into the struct's WGSL, so that naga's view
//! of the item, and with it every layout's packing (registers, AoS or SoA state, queues, split
//! chains), holds them like the struct's own. A constructor of the item with arguments
//! (`PhotonPath(light, 0.0, ...)`) gets the new fields' zero values (`u32()`), so the sources
//! that build it need no change. Lines keep their numbers: errors still point into the files.

use crate::error::{Error, Location, Result};
use crate::load::{Declared, is_identifier};
use crate::vfs::Vfs;
use crate::wgsl::{code_bytes, identifier_offsets};
use std::collections::BTreeMap;

/// Fields added to items: item → `(name, type)` in order.
pub type ItemFields = BTreeMap<String, Vec<(String, String)>>;

/// Checks the `item_fields` of graph `file`: each item is one a pass runs over or a stream
/// carries, each field a new WGSL identifier (not one of the struct's, not `lg_`-prefixed, not
/// given twice) of a type an item can hold between kernels.
pub fn check(declared: &Declared, vfs: &Vfs, file: &str) -> Result<()> {
    let fields = &declared.file.item_fields;
    if fields.is_empty() {
        return Ok(());
    }
    let mut items: Vec<&str> = declared.passes.iter().map(|p| p.decl.item.as_str()).collect();
    items.extend(declared.file.streams.values().map(|s| s.item.as_str()));
    items.sort();
    items.dedup();
    let texts = declared
        .wgsl_files()
        .into_iter()
        .map(|f| vfs.read(&f))
        .collect::<Result<Vec<String>>>()?;
    for (item, added) in fields {
        let at_item = |message: String| declared.sources.at_key(file, item, message);
        if !items.contains(&item.as_str()) {
            return Err(at_item(format!(
                "item_fields: '{item}' is no item of this graph (its items: {})",
                items.join(", ")
            )));
        }
        let own = texts.iter().find_map(|t| struct_members(t, item)).unwrap_or_default();
        let at_field = |field: &str, message: String| {
            let f = declared.sources.declaring(file, field);
            Error::Invalid {
                at: Location::of_name_under_key(f, declared.sources.text(f), item, field),
                message,
            }
        };
        for (n, (name, ty)) in added.iter().enumerate() {
            if !is_identifier(name) || name.starts_with("lg_") {
                return Err(at_field(
                    name,
                    format!(
                        "item_fields: '{name}' of '{item}' is not a WGSL identifier that does not start with `lg_`"
                    ),
                ));
            }
            if own.contains(name) || added[..n].iter().any(|(other, _)| other == name) {
                return Err(at_field(
                    name,
                    format!("item_fields: '{item}' already has a field '{name}'"),
                ));
            }
            if let Err(why) = storable(ty) {
                return Err(at_field(
                    name,
                    format!("item_fields: field '{name}' of '{item}' has type '{ty}': {why}"),
                ));
            }
        }
    }
    Ok(())
}

/// Whether an item may hold a field of WGSL type `ty`: 32-bit scalars, their vectors and
/// matrices, and fixed-size arrays of those.
fn storable(ty: &str) -> std::result::Result<(), String> {
    let ty = ty.trim();
    let scalars = ["f32", "u32", "i32"];
    if scalars.contains(&ty) {
        return Ok(());
    }
    if ty == "bool" {
        return Err("a bool cannot be stored between kernels; use u32".into());
    }
    let shorthand = ["vec2", "vec3", "vec4"]
        .iter()
        .any(|v| ["f", "u", "i"].iter().any(|s| ty == format!("{v}{s}")));
    if shorthand {
        return Ok(());
    }
    let generic = |prefixes: &[&str]| {
        prefixes.iter().find_map(|p| {
            ty.strip_prefix(p)
                .and_then(|r| r.strip_prefix('<'))
                .and_then(|r| r.strip_suffix('>'))
        })
    };
    if let Some(inner) = generic(&["vec2", "vec3", "vec4"]) {
        return scalars
            .contains(&inner.trim())
            .then_some(())
            .ok_or_else(|| format!("vectors hold f32, u32 or i32, not '{inner}'"));
    }
    let matrices: Vec<String> = (2..=4)
        .flat_map(|c| (2..=4).map(move |r| format!("mat{c}x{r}")))
        .collect();
    let matrices: Vec<&str> = matrices.iter().map(|s| s.as_str()).collect();
    if let Some(inner) = generic(&matrices) {
        return (inner.trim() == "f32")
            .then_some(())
            .ok_or_else(|| format!("matrices hold f32, not '{inner}'"));
    }
    if let Some(inner) = generic(&["array"]) {
        let (element, count) = inner
            .rsplit_once(',')
            .ok_or_else(|| "an array needs a fixed size, `array<T, N>`".to_string())?;
        let count = count.trim().trim_end_matches('u');
        if count.parse::<u32>().map_or(true, |n| n == 0) {
            return Err(format!("an array's size must be a positive number, not '{count}'"));
        }
        return storable(element);
    }
    Err("items hold f32, u32 or i32 scalars, their vectors and matrices, and fixed-size arrays of them".into())
}

/// The offset just after `struct name {` in `text` (in code), and of its closing `}`.
fn struct_body(text: &str, name: &str) -> Option<(usize, usize)> {
    identifier_offsets(text, name).into_iter().find_map(|i| {
        let before = text[..i].trim_end();
        let is_struct = before.strip_suffix("struct").is_some_and(|b| {
            b.as_bytes()
                .last()
                .is_none_or(|c| !(c.is_ascii_alphanumeric() || *c == b'_'))
        });
        let rest = &text[i + name.len()..];
        let open = i + name.len() + rest.len() - rest.trim_start().len();
        // An unclosed body is left for naga to report at its line.
        let close = text[open..].find('}').map(|c| open + c);
        close
            .filter(|_| is_struct && text[open..].starts_with('{'))
            .map(|close| (open + 1, close))
    })
}

/// The member names of `struct name` in `text`, if `text` defines it.
fn struct_members(text: &str, name: &str) -> Option<Vec<String>> {
    let (start, end) = struct_body(text, name)?;
    let code = code_bytes(text);
    let body: String = text[start..end]
        .char_indices()
        .map(|(i, c)| if code[start + i] { c } else { ' ' })
        .collect();
    Some(
        body.split(',')
            .filter_map(|m| {
                m.split_once(':')
                    .map(|(n, _)| n.trim().rsplit(' ').next().unwrap_or("").to_string())
            })
            .filter(|n| !n.is_empty())
            .collect(),
    )
}

/// `text` with `fields` added: the fields at the end of each item struct it defines, and their
/// zero values at the end of each constructor of such an item with arguments.
pub fn added(text: &str, fields: &ItemFields) -> String {
    let mut text = text.to_string();
    for (item, extra) in fields {
        if let Some((start, end)) = struct_body(&text, item) {
            let code = code_bytes(&text);
            let last = text[start..end]
                .char_indices()
                .rev()
                .find(|(i, c)| code[start + i] && !c.is_whitespace())
                .map(|(_, c)| c);
            let sep = if matches!(last, None | Some(',')) { "" } else { ", " };
            let members: Vec<String> = extra.iter().map(|(n, t)| format!("{n}: {t},")).collect();
            text.insert_str(end, &format!("{sep}{} ", members.join(" ")));
        }
        let zeros: Vec<String> = extra.iter().map(|(_, t)| format!("{t}()")).collect();
        let zeros = zeros.join(", ");
        for call in identifier_offsets(&text, item).into_iter().rev() {
            let rest = &text[call + item.len()..];
            let open = call + item.len() + rest.len() - rest.trim_start().len();
            if !text[open..].starts_with('(') {
                continue;
            }
            let Some(close) = matching_paren(&text, open) else {
                continue;
            };
            if !text[open + 1..close].trim().is_empty() {
                text.insert_str(close, &format!(", {zeros}"));
            }
        }
    }
    text
}

/// The offset of the `)` that closes the `(` at `open`.
fn matching_paren(text: &str, open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (i, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(open + i);
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(item: &str, list: &[(&str, &str)]) -> ItemFields {
        let list = list.iter().map(|(n, t)| (n.to_string(), t.to_string())).collect();
        BTreeMap::from([(item.to_string(), list)])
    }

    #[test]
    fn fields_join_the_struct_and_its_constructors_on_the_same_lines() {
        let text = "struct P {\n    a: u32,\n    b: f32 // last\n}\nfn f() -> P {\n    let q = Pair(1u);\n    return P(1u,\n        g(2.0));\n}\nfn z() -> P { return P(); }\n";
        let out = added(text, &fields("P", &[("c", "u32"), ("d", "vec2<f32>")]));
        assert_eq!(out.lines().count(), text.lines().count());
        assert!(out.contains("b: f32 // last\n, c: u32, d: vec2<f32>, }"), "{out}");
        assert!(out.contains("g(2.0), u32(), vec2<f32>());"), "{out}");
        assert!(out.contains("Pair(1u);") && out.contains("return P();"), "{out}");
        assert_eq!(struct_members(&out, "P").unwrap(), ["a", "b", "c", "d"]);
    }

    #[test]
    fn only_storable_types_are_accepted() {
        for ok in ["u32", "vec3<f32>", "vec2u", "mat3x3<f32>", "array<vec4<f32>, 4>"] {
            assert_eq!(storable(ok), Ok(()), "{ok}");
        }
        for bad in ["bool", "f16", "vec3<bool>", "array<u32>", "array<u32, 0>", "MergePath"] {
            assert!(storable(bad).is_err(), "{bad}");
        }
    }
}
