//! Named hooks: WGSL functions of the shipped passes and libraries that a graph may replace by
//! name. A source declares a hook with a comment line `// Hook: what it decides` (more `//`
//! lines may follow) right above the function; a graph's `hooks: {"name": "file.wgsl"}` names
//! a file that defines a function of that name with the same parameter and return types.
//! With the hook replaced, the default's definition is renamed `lg_default_<name>` (nothing
//! calls it, so it leaves every kernel) and the file joins the sources. A graph without hooks
//! compiles exactly the sources it did before.

use crate::error::{Error, Location, Result};
use crate::load::Declared;
use crate::vfs::Vfs;
use crate::wgsl::function_definition;

/// The comment that declares the hook defined below it.
pub const MARKER: &str = "// Hook:";

/// A hook a WGSL source declares.
#[derive(Debug, Clone, PartialEq)]
pub struct HookDecl {
    /// The function's name, which graphs replace it by.
    pub name: String,
    /// The file (virtual path) that declares it and holds the default.
    pub file: String,
    /// The 1-based line of the default's `fn`.
    pub line: usize,
    /// The default's signature as written, `fn name(...) -> T`.
    pub signature: String,
    /// The declaration's comment, without the comment markers.
    pub doc: String,
}

/// The hooks that `text` (of `file`) declares, in order.
pub fn declared_in(file: &str, text: &str) -> Vec<HookDecl> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (n, line) in lines.iter().enumerate() {
        let Some(first) = line.trim_start().strip_prefix(MARKER) else {
            continue;
        };
        let mut doc = vec![first.trim()];
        let mut at = n + 1;
        while let Some(more) = lines.get(at).and_then(|l| l.trim_start().strip_prefix("//")) {
            doc.push(more.trim());
            at += 1;
        }
        let Some(def) = lines.get(at).filter(|l| l.starts_with("fn ")) else {
            continue;
        };
        let name: String = def[3..]
            .trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        let header: Vec<&str> = lines[at..]
            .iter()
            .map(|l| l.trim())
            .take_while(|l| !l.ends_with('{'))
            .chain(lines[at..].iter().map(|l| l.trim()).find(|l| l.ends_with('{')))
            .collect();
        let signature = header.join(" ").trim_end_matches('{').trim().to_string();
        out.push(HookDecl {
            name,
            file: file.to_string(),
            line: at + 1,
            signature,
            doc: doc.join(" ").trim().to_string(),
        });
    }
    out
}

/// Whether `text` (of `file`) declares the hook `name`.
pub fn declares(file: &str, text: &str, name: &str) -> bool {
    text.contains(MARKER) && declared_in(file, text).iter().any(|h| h.name == name)
}

/// The name a replaced hook's default is renamed to.
pub fn default_name(hook: &str) -> String {
    format!("lg_default_{hook}")
}

/// The name a replacement is given where it is compiled beside the default to compare them.
pub fn candidate_name(hook: &str) -> String {
    format!("lg_hook_{hook}")
}

/// `text` with the definition of function `name`, if it has one, renamed `to`.
pub fn renamed(text: &str, name: &str, to: &str) -> String {
    match function_definition(text, name) {
        Some(at) => format!("{}{to}{}", &text[..at], &text[at + name.len()..]),
        None => text.to_string(),
    }
}

/// The hooks the WGSL sources of `declared` declare (its library and its passes' files).
pub fn declared_hooks(declared: &Declared, vfs: &Vfs, file: &str) -> Result<Vec<HookDecl>> {
    let mut out = Vec::new();
    for source in declared.wgsl_files() {
        let text = vfs
            .read(&source)
            .map_err(|e| declared.sources.at_name(file, &source, e.to_string()))?;
        out.extend(declared_in(&source, &text));
    }
    Ok(out)
}

/// Checks the `hooks` of graph `file` before any WGSL is compiled: each names a hook its sources
/// declare, and its file can be read and defines the function. The signatures are compared by
/// [`check_compiled`], once the sources compile.
pub fn check(declared: &Declared, vfs: &Vfs, file: &str) -> Result<()> {
    if declared.file.hooks.is_empty() {
        return Ok(());
    }
    let known = declared_hooks(declared, vfs, file)?;
    for (name, path) in &declared.file.hooks {
        if !known.iter().any(|h| &h.name == name) {
            let names: Vec<&str> = known.iter().map(|h| h.name.as_str()).collect();
            let listed = if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            };
            return Err(declared.sources.at_key(
                file,
                name,
                format!("hooks: no hook '{name}' in this graph's sources (its hooks: {listed})"),
            ));
        }
        let text = vfs
            .read(path)
            .map_err(|e| declared.sources.at_key(file, name, format!("hook '{name}': {e}")))?;
        if function_definition(&text, name).is_none() {
            return Err(declared.sources.at_key(
                file,
                name,
                format!("hook '{name}': {path} defines no function '{name}'"),
            ));
        }
    }
    Ok(())
}

/// A hook a graph replaces: its name, the replacement's file and that file's text.
pub struct Replaced {
    /// The hook.
    pub name: String,
    /// The replacement's file (virtual path).
    pub file: String,
    /// The replacement file's text.
    pub text: String,
}

/// Checks each hook of `replaced` against `module`, where the replacements are compiled as
/// [`candidate_name`] beside the defaults: some function of `passes` (the graph's pass
/// functions) calls the default, and the replacement takes the same parameter types in order
/// and returns the same type. A signature that differs is an error at the replacement's
/// definition naming the expected one; `unused` makes the error of a hook no pass calls.
pub fn check_compiled(
    module: &naga::Module,
    passes: &[&str],
    replaced: &[Replaced],
    known: &[HookDecl],
    unused: impl Fn(&str, String) -> Error,
) -> Result<()> {
    let function = |name: &str| module.functions.iter().find(|(_, f)| f.name.as_deref() == Some(name));
    let roots = passes.iter().filter_map(|p| function(p)).map(|(h, _)| h).collect();
    let reached = crate::wgsl::callees(module, roots);
    for Replaced { name, file, text } in replaced {
        let decl = known.iter().find(|h| &h.name == name);
        let where_declared = decl.map_or(String::new(), |h| format!(" ({}:{})", h.file, h.line));
        let Some((default_handle, default)) = function(name) else {
            continue;
        };
        if !reached.contains(&default_handle) {
            return Err(unused(
                name,
                format!("hook '{name}'{where_declared}: no pass of this graph calls it"),
            ));
        }
        let Some((_, candidate)) = function(&candidate_name(name)) else {
            continue;
        };
        let types = |f: &naga::Function| -> (Vec<String>, String) {
            let params = f.arguments.iter().map(|a| type_text(module, a.ty)).collect();
            let result = f.result.as_ref().map_or("()".to_string(), |r| type_text(module, r.ty));
            (params, result)
        };
        let (want, got) = (types(default), types(candidate));
        if want == got {
            continue;
        }
        let expected = decl.map_or(String::new(), |h| format!("`{}`", h.signature));
        let offset = function_definition(text, name).unwrap_or(0);
        return Err(Error::Invalid {
            at: Location::at_offset(file, text, offset),
            message: format!(
                "hook '{name}': takes ({}) and returns {}, but the hook is {expected}{where_declared}",
                got.0.join(", "),
                got.1
            ),
        });
    }
    Ok(())
}

/// A type as WGSL names it (named types by name).
fn type_text(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    use naga::TypeInner;
    let t = &module.types[ty];
    if let Some(name) = &t.name {
        return name.clone();
    }
    let scalar = |s: &naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => "f32".to_string(),
        (naga::ScalarKind::Uint, 4) => "u32".to_string(),
        (naga::ScalarKind::Sint, 4) => "i32".to_string(),
        (naga::ScalarKind::Bool, _) => "bool".to_string(),
        (kind, width) => format!("{kind:?}{}", width * 8),
    };
    match &t.inner {
        TypeInner::Scalar(s) => scalar(s),
        TypeInner::Vector { size, scalar: s } => format!("vec{}<{}>", *size as u8, scalar(s)),
        TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => format!("mat{}x{}<{}>", *columns as u8, *rows as u8, scalar(s)),
        TypeInner::Pointer { base, space } => {
            format!(
                "ptr<{}, {}>",
                format!("{space:?}").to_lowercase(),
                type_text(module, *base)
            )
        }
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => format!("array<{}, {n}>", type_text(module, *base)),
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_marker_declares_the_function_below_it() {
        let text = "fn other() {}\n// Hook: whether to keep it.\n// Default: always.\nfn keep(p: ptr<function, P>,\n        a: u32) -> bool {\n    return true;\n}\n";
        let hooks = declared_in("lib.wgsl", text);
        assert_eq!(hooks.len(), 1);
        assert_eq!(hooks[0].name, "keep");
        assert_eq!(hooks[0].line, 4);
        assert_eq!(hooks[0].signature, "fn keep(p: ptr<function, P>, a: u32) -> bool");
        assert_eq!(hooks[0].doc, "whether to keep it. Default: always.");
    }

    #[test]
    fn renaming_touches_the_definition_only() {
        let text =
            "// fn keep( in a comment\nfn keep_all() -> bool { return keep(); }\nfn keep() -> bool { return true; }\n";
        let out = renamed(text, "keep", "lg_default_keep");
        assert_eq!(
            out.lines().nth(2),
            Some("fn lg_default_keep() -> bool { return true; }")
        );
        assert_eq!(out.lines().nth(1), Some("fn keep_all() -> bool { return keep(); }"));
        assert_eq!(out.lines().next(), Some("// fn keep( in a comment"));
    }
}
