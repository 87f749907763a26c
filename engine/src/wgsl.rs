//! WGSL sources: a line-based preprocessor for specialisation flags, module assembly with
//! a source map, and naga parsing/validation whose errors name the original file and line.

use crate::error::{Error, Location, Result};
use std::collections::BTreeSet;

/// Resolves `#if FLAG`, `#if !FLAG`, `#else` and `#endif` lines against `flags`.
///
/// Removed lines and directives become empty lines, so line numbers stay those of the file.
pub fn preprocess(file: &str, text: &str, flags: &BTreeSet<String>) -> Result<String> {
    // Each open block: (is this branch active, was the enclosing region active).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let mut out = String::with_capacity(text.len());
    let directive_error = |line: usize, message: String| Error::Shader(format!("{file}:{}:1: {message}", line + 1));
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let active = stack.last().is_none_or(|(on, outer)| *on && *outer);
        if let Some(rest) = trimmed.strip_prefix("#if") {
            let cond = rest.trim();
            let (negate, name) = match cond.strip_prefix('!') {
                Some(name) => (true, name.trim()),
                None => (false, cond),
            };
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(directive_error(n, format!("'#if' needs one flag name, found '{cond}'")));
            }
            stack.push((flags.contains(name) != negate, active));
            out.push('\n');
        } else if trimmed.starts_with("#else") {
            let top = stack
                .last_mut()
                .ok_or_else(|| directive_error(n, "'#else' without '#if'".into()))?;
            top.0 = !top.0;
            out.push('\n');
        } else if trimmed.starts_with("#endif") {
            stack
                .pop()
                .ok_or_else(|| directive_error(n, "'#endif' without '#if'".into()))?;
            out.push('\n');
        } else if trimmed.starts_with('#') {
            return Err(directive_error(
                n,
                format!(
                    "unknown directive '{}'",
                    trimmed.split_whitespace().next().unwrap_or("#")
                ),
            ));
        } else {
            if active {
                out.push_str(line);
            }
            out.push('\n');
        }
    }
    if !stack.is_empty() {
        return Err(Error::Shader(format!("{file}: '#if' without '#endif'")));
    }
    Ok(out)
}

/// Whether each byte of `text` is code: false inside `//` and `/* */` comments.
pub fn code_bytes(text: &str) -> Vec<bool> {
    let b = text.as_bytes();
    let mut code = vec![true; b.len()];
    let mut i = 0;
    while i < b.len() {
        let end = match (b[i], b.get(i + 1)) {
            (b'/', Some(b'/')) => text[i..].find('\n').map_or(b.len(), |n| i + n),
            (b'/', Some(b'*')) => text[i + 2..].find("*/").map_or(b.len(), |n| i + 2 + n + 2),
            _ => {
                i += 1;
                continue;
            }
        };
        code[i..end].fill(false);
        i = end;
    }
    code
}

/// Whether `c` may be part of a WGSL identifier.
fn is_ident_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Byte offsets in `text` where the identifier `name` stands in code (not in a comment, not
/// part of a longer identifier).
pub fn identifier_offsets(text: &str, name: &str) -> Vec<usize> {
    let code = code_bytes(text);
    let b = text.as_bytes();
    text.match_indices(name)
        .map(|(i, _)| i)
        .filter(|&i| code[i])
        .filter(|&i| i == 0 || !is_ident_byte(b[i - 1]))
        .filter(|&i| b.get(i + name.len()).is_none_or(|c| !is_ident_byte(*c)))
        .collect()
}

/// The offset of the name in the definition `fn name(` in `text`, if `text` defines `name`.
pub fn function_definition(text: &str, name: &str) -> Option<usize> {
    identifier_offsets(text, name).into_iter().find(|&i| {
        text[..i]
            .trim_end()
            .strip_suffix("fn")
            .is_some_and(|before| before.as_bytes().last().is_none_or(|c| !is_ident_byte(*c)))
            && text[i + name.len()..].trim_start().starts_with('(')
    })
}

/// One WGSL module assembled from several files, remembering where each line came from.
#[derive(Debug, Clone, Default)]
pub struct ModuleSource {
    text: String,
    /// (file, first line of the chunk in `text`, 0-based).
    chunks: Vec<(String, usize)>,
    lines: usize,
}

impl ModuleSource {
    /// Appends `text` as coming from `file`.
    pub fn push(&mut self, file: &str, text: &str) {
        self.chunks.push((file.to_string(), self.lines));
        self.text.push_str(text);
        if !text.ends_with('\n') {
            self.text.push('\n');
        }
        self.lines = self.text.matches('\n').count();
    }

    /// The assembled text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Maps a 1-based line and column of the assembled text to the file it came from.
    pub fn locate(&self, line: usize, column: usize) -> Location {
        let zero = line.saturating_sub(1);
        let (file, first) = self
            .chunks
            .iter()
            .rev()
            .find(|(_, first)| *first <= zero)
            .cloned()
            .unwrap_or_default();
        Location {
            file,
            line: zero - first + 1,
            column,
        }
    }

    /// The module without the functions its entry points never call: culled passes and
    /// library functions no live pass uses leave the text (as blank lines, so lines keep
    /// their numbers). Fails as [`ModuleSource::compile`] does when the text does not parse.
    pub fn shaken(&self) -> Result<ModuleSource> {
        let module = naga::front::wgsl::parse_str(&self.text).map_err(|e| self.parse_error(&e))?;
        let mut reachable = BTreeSet::new();
        for ep in &module.entry_points {
            let mut roots = Vec::new();
            direct_calls(&ep.function.body, &mut roots);
            reachable.extend(callees(&module, roots));
        }
        let mut bytes = self.text.clone().into_bytes();
        for (h, _) in module.functions.iter() {
            if reachable.contains(&h) {
                continue;
            }
            if let Some(range) = module.functions.get_span(h).to_range() {
                for b in &mut bytes[range] {
                    if *b != b'\n' {
                        *b = b' ';
                    }
                }
            }
        }
        Ok(ModuleSource {
            text: String::from_utf8(bytes).expect("blanking keeps UTF-8 (whole functions of ASCII boundaries)"),
            chunks: self.chunks.clone(),
            lines: self.lines,
        })
    }

    /// The files the module is assembled from, naming errors that naga cannot place.
    fn files(&self) -> String {
        let files: Vec<&str> = self.chunks.iter().map(|(f, _)| f.as_str()).collect();
        format!("in one of {}", files.join(", "))
    }

    fn locate_span(&self, span: naga::Span) -> Option<Location> {
        if !span.is_defined() {
            return None;
        }
        let loc = span.location(&self.text);
        Some(self.locate(loc.line_number as usize, loc.line_position as usize))
    }

    /// A parse error placed in the original files.
    fn parse_error(&self, e: &naga::front::wgsl::ParseError) -> Error {
        let mut msg = String::new();
        let labels: Vec<_> = e.labels().collect();
        let primary = labels.first().and_then(|(span, _)| self.locate_span(*span));
        match primary {
            Some(at) => msg.push_str(&format!("{at}: error: {}", e.message())),
            None => msg.push_str(&format!("{}: error: {}", self.files(), e.message())),
        }
        for (span, label) in labels.iter() {
            if let Some(at) = self.locate_span(*span)
                && !label.is_empty()
            {
                msg.push_str(&format!("\n  {at}: {label}"));
            }
        }
        for note in e.notes() {
            msg.push_str(&format!("\n  note: {note}"));
        }
        Error::Shader(msg)
    }

    /// Parses and validates the module with naga.
    pub fn compile(&self, capabilities: naga::valid::Capabilities) -> Result<(naga::Module, naga::valid::ModuleInfo)> {
        let module = naga::front::wgsl::parse_str(&self.text).map_err(|e| self.parse_error(&e))?;
        let mut validator = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities);
        let info = validator.validate(&module).map_err(|e| {
            let mut spans = e.spans();
            let at = spans.next().and_then(|(span, _)| self.locate_span(*span));
            let mut msg = match at {
                Some(at) => format!("{at}: error: {}", e.as_inner()),
                None => format!("{}: error: {}", self.files(), e.as_inner()),
            };
            for (span, label) in e.spans() {
                if let Some(at) = self.locate_span(*span) {
                    msg.push_str(&format!("\n  {at}: {label}"));
                }
            }
            let mut source: Option<&dyn std::error::Error> = std::error::Error::source(e.as_inner());
            while let Some(s) = source {
                msg.push_str(&format!("\n  caused by: {s}"));
                source = s.source();
            }
            Error::Shader(msg)
        })?;
        Ok((module, info))
    }
}

/// Functions `block` calls directly.
fn direct_calls(block: &naga::Block, out: &mut Vec<naga::Handle<naga::Function>>) {
    for st in block.iter() {
        match st {
            naga::Statement::Call { function, .. } => out.push(*function),
            naga::Statement::Block(b) => direct_calls(b, out),
            naga::Statement::If { accept, reject, .. } => {
                direct_calls(accept, out);
                direct_calls(reject, out);
            }
            naga::Statement::Switch { cases, .. } => cases.iter().for_each(|c| direct_calls(&c.body, out)),
            naga::Statement::Loop { body, continuing, .. } => {
                direct_calls(body, out);
                direct_calls(continuing, out);
            }
            _ => {}
        }
    }
}

/// Functions called (transitively) from `roots`, the roots included.
pub fn callees(
    module: &naga::Module,
    roots: Vec<naga::Handle<naga::Function>>,
) -> BTreeSet<naga::Handle<naga::Function>> {
    let mut seen = BTreeSet::new();
    let mut stack = roots;
    while let Some(h) = stack.pop() {
        if seen.insert(h) {
            direct_calls(&module.functions[h].body, &mut stack);
        }
    }
    seen
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(names: &[&str]) -> BTreeSet<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn preprocessor_keeps_line_numbers() {
        let src = "a\n#if X\nb\n#else\nc\n#endif\n#if !X\nd\n#endif\ne\n";
        assert_eq!(preprocess("f", src, &flags(&["X"])).unwrap(), "a\n\nb\n\n\n\n\n\n\ne\n");
        assert_eq!(preprocess("f", src, &flags(&[])).unwrap(), "a\n\n\n\nc\n\n\nd\n\ne\n");
    }

    #[test]
    fn nested_blocks_inside_inactive_regions_stay_inactive() {
        let src = "#if A\n#if B\nx\n#else\ny\n#endif\n#endif\n";
        assert_eq!(preprocess("f", src, &flags(&[])).unwrap().trim(), "");
        assert_eq!(preprocess("f", src, &flags(&["A"])).unwrap().trim(), "y");
    }

    #[test]
    fn preprocessor_errors_name_the_line() {
        let err = preprocess("s.wgsl", "x\n#endif\n", &flags(&[]))
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("s.wgsl:2:1"), "{err}");
        assert!(preprocess("s.wgsl", "#if A\n", &flags(&[])).is_err());
        assert!(preprocess("s.wgsl", "#include x\n", &flags(&[])).is_err());
    }

    #[test]
    fn naga_errors_point_into_the_original_file() {
        let mut m = ModuleSource::default();
        m.push("gen", "const A: u32 = 1u;\n");
        m.push("shaders/x.wgsl", "fn f() -> u32 {\n  return A + undefined_name;\n}\n");
        let err = m.compile(naga::valid::Capabilities::default()).unwrap_err().to_string();
        assert!(err.contains("shaders/x.wgsl:2:"), "{err}");
    }

    #[test]
    fn shaking_removes_uncalled_functions_and_keeps_lines() {
        let mut m = ModuleSource::default();
        m.push(
            "lib.wgsl",
            "fn used() -> u32 { return helper(); }\nfn helper() -> u32 {\n    return 1u;\n}\nfn unused() -> u32 {\n    return 2u;\n}\n",
        );
        m.push("gen", "@compute @workgroup_size(1)\nfn main() { let x = used(); }\n");
        let shaken = m.shaken().unwrap();
        let text = shaken.text();
        assert!(
            text.contains("fn used") && text.contains("fn helper") && !text.contains("unused"),
            "{text}"
        );
        assert_eq!(text.lines().count(), m.text().lines().count());
        assert!(shaken.compile(naga::valid::Capabilities::default()).is_ok());
    }

    #[test]
    fn errors_without_a_span_name_the_files() {
        let mut m = ModuleSource::default();
        m.push(
            "shaders/deep.wgsl",
            &format!("fn f() -> u32 {{ return {}1u; }}\n", "(".repeat(1000)),
        );
        let err = m.compile(naga::valid::Capabilities::default()).unwrap_err().to_string();
        assert!(err.starts_with("in one of shaders/deep.wgsl: error:"), "{err}");
    }
}
