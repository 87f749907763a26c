//! The engine's stages only look back: each module of `engine/src` refers (through `crate::`
//! paths: `use` lines, grouped uses and inline paths) only to modules of earlier stages and of
//! its own stage, and the modules of one stage import one another without a cycle. The stages
//! and their modules are the table in the doc comment of `engine/src/lib.rs`, which
//! `docs/graphs.md` repeats row for row.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The engine's source folder.
fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The rows of the stage table: the doc-comment lines of lib.rs that are table rows, without
/// the header and the rule, `//! ` cut off.
fn table_rows(lib: &str) -> Vec<String> {
    lib.lines()
        .filter_map(|l| l.strip_prefix("//! |"))
        .filter(|row| !row.starts_with("---") && !row.trim_start().starts_with("stage "))
        .map(|row| format!("|{row}"))
        .collect()
}

/// Each module's stage, numbered in the table's order: the first cell names the stage, the
/// second lists its modules in backquotes.
fn stages(rows: &[String]) -> BTreeMap<String, (usize, String)> {
    let mut out = BTreeMap::new();
    for (i, row) in rows.iter().enumerate() {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let stage = cells[1].to_string();
        for module in cells[2].split('`').skip(1).step_by(2) {
            assert!(
                out.insert(module.to_string(), (i, stage.clone())).is_none(),
                "module `{module}` stands twice in the stage table"
            );
        }
    }
    out
}

/// The Rust files under `dir`, with their paths relative to `root`.
fn rust_files(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            out.push((rel, std::fs::read_to_string(&path).unwrap()));
        }
    }
}

/// The top-level module a file of `src/` belongs to (`runtime/frames.rs` → `runtime`).
fn module_of(rel: &str) -> &str {
    let first = rel.split('/').next().unwrap();
    first.strip_suffix(".rs").unwrap_or(first)
}

/// One `crate::` reference: where it stands, the module it names, and its text.
#[derive(Debug, PartialEq)]
struct Reference {
    line: usize,
    module: String,
    text: String,
}

/// Where the identifier `s` starts with ends.
fn ident_end(s: &str) -> usize {
    s.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(s.len())
}

/// The path `s` starts with (`a::b::`), and the group after it up to its first `}`, without
/// white space: how a reference is shown.
fn shown(s: &str) -> String {
    let path_end = s
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(s.len());
    let (path, rest) = s.split_at(path_end);
    let group = if rest.starts_with('{') {
        rest.split_inclusive('}').next().unwrap_or("")
    } else {
        ""
    };
    format!("{path}{}", group.split_whitespace().collect::<String>())
}

/// The items of the group `s` starts with (`{a, b::{c, d}}`: `a` and `b::{c, d}`), each with
/// its offset in `s`.
fn group_items(s: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut depth = 0;
    let mut item_start = 1;
    for (i, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' | ',' if depth == 1 => {
                let item = s[item_start..i].trim_start();
                if !item.trim().is_empty() {
                    out.push((i - item.len(), item.trim_end()));
                }
                if c == '}' {
                    break;
                }
                item_start = i + 1;
            }
            '}' => depth -= 1,
            _ => {}
        }
    }
    out
}

/// The `crate::` references of `text` outside comments: each path's first segment, and each
/// item's first segment in a grouped `crate::{a, b::c}` (which may span lines).
fn references(text: &str) -> Vec<Reference> {
    let code: String = text
        .lines()
        .map(|l| l.split_once("//").map_or(l, |(code, _)| code))
        .collect::<Vec<_>>()
        .join("\n");
    let line_at = |i: usize| code[..i].matches('\n').count() + 1;
    let mut out = Vec::new();
    for (at, prefix) in code.match_indices("crate::") {
        if code[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let start = at + prefix.len();
        let rest = &code[start..];
        let items = match rest.starts_with('{') {
            true => group_items(rest)
                .into_iter()
                .map(|(o, item)| (start + o, item))
                .collect(),
            false => vec![(at, rest)],
        };
        for (offset, item) in items {
            out.push(Reference {
                line: line_at(offset),
                module: item[..ident_end(item)].to_string(),
                text: format!("{prefix}{}", shown(item)),
            });
        }
    }
    out
}

/// Every way `files` (path under `src/`, text) break the stage order of `rows`, one message
/// each: a module in no stage, a reference to a later stage or to no module of the table, and
/// an import on a cycle between modules of one stage.
fn violations(rows: &[String], files: &[(String, String)]) -> Vec<String> {
    let stage = stages(rows);
    let mut errors = Vec::new();
    let modules: BTreeSet<&str> = files
        .iter()
        .map(|(rel, _)| module_of(rel))
        .filter(|m| *m != "lib")
        .collect();
    for m in &modules {
        if !stage.contains_key(*m) {
            errors.push(format!(
                "engine/src: module `{m}` stands in no stage of the table in lib.rs"
            ));
        }
    }
    for m in stage.keys().filter(|m| !modules.contains(m.as_str())) {
        errors.push(format!(
            "lib.rs: the stage table names `{m}`, which is no module of engine/src"
        ));
    }
    // Same-stage imports: (from, to) → where the first one stands.
    let mut same: BTreeMap<(String, String), String> = BTreeMap::new();
    for (rel, text) in files.iter().filter(|(rel, _)| rel != "lib.rs") {
        let from = module_of(rel);
        let Some((from_stage, from_name)) = stage.get(from) else {
            continue;
        };
        for r in references(text).into_iter().filter(|r| r.module != from) {
            let at = format!("engine/src/{rel}:{}: `{}`", r.line, r.text);
            match stage.get(&r.module) {
                None => errors.push(format!(
                    "{at}: `{}` is no module of the stage table (name the module that defines it)",
                    r.module
                )),
                Some((to_stage, to_name)) if to_stage > from_stage => errors.push(format!(
                    "{at}: `{from}` (stage {from_name}) imports `{}` of a later stage ({to_name})",
                    r.module
                )),
                Some((to_stage, _)) if to_stage == from_stage => {
                    same.entry((from.to_string(), r.module.clone())).or_insert(at);
                }
                Some(_) => {}
            }
        }
    }
    for ((from, to), at) in &same {
        if let Some(back) = path_between(&same, to, from) {
            let (_, name) = &stage[from];
            errors.push(format!(
                "{at}: `{from}` imports `{to}` of its own stage ({name}), which imports it back: {}",
                back.join(" → ")
            ));
        }
    }
    errors
}

/// The modules from `from` to `to` over the same-stage imports, if `to` is reachable.
fn path_between(edges: &BTreeMap<(String, String), String>, from: &str, to: &str) -> Option<Vec<String>> {
    let mut before: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = vec![from];
    while let Some(m) = queue.pop() {
        if m == to {
            let mut path = vec![to.to_string()];
            let mut at = to;
            while at != from {
                at = before[at];
                path.push(at.to_string());
            }
            path.reverse();
            return Some(path);
        }
        for ((a, b), _) in edges.iter().filter(|((a, _), _)| a == m) {
            if b != from && !before.contains_key(b.as_str()) {
                before.insert(b, a);
                queue.push(b);
            }
        }
    }
    None
}

#[test]
fn stages_only_look_back() {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let rows = table_rows(&lib);
    assert!(rows.len() > 5, "lib.rs has no stage table");
    let mut files = Vec::new();
    rust_files(&src(), &src(), &mut files);
    let errors = violations(&rows, &files);
    assert!(
        errors.is_empty(),
        "the engine's stages do not only look back:\n{}",
        errors.join("\n")
    );
}

#[test]
fn the_docs_list_the_same_stages() {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let docs_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/graphs.md");
    let docs = std::fs::read_to_string(docs_path).unwrap();
    let docs_rows: BTreeSet<&str> = docs.lines().collect();
    for row in table_rows(&lib) {
        assert!(
            docs_rows.contains(row.as_str()),
            "docs/graphs.md lacks the stage row of lib.rs:\n{row}"
        );
    }
}

#[test]
fn references_are_found_in_uses_groups_and_inline_paths() {
    let text =
        "use crate::a::b;\n// crate::comment\nuse crate::{c, d::{e, f},\n    g::h};\nfn x() { crate::i::j(); }\n";
    let found: Vec<(usize, String)> = references(text).into_iter().map(|r| (r.line, r.module)).collect();
    let want = [(1, "a"), (3, "c"), (3, "d"), (4, "g"), (5, "i")].map(|(l, m)| (l, m.to_string()));
    assert_eq!(found, want);
}

#[test]
fn a_later_stage_and_a_cycle_are_named() {
    let rows = ["| leaf | `ids` |", "| load | `load`, `graph` |", "| plan | `plan` |"].map(String::from);
    let files = [
        ("ids.rs", ""),
        ("load.rs", "use crate::ids::PassId;\nfn f() { crate::graph::g(); }\n"),
        ("graph.rs", "use crate::{load::declare, plan::Plan};\n"),
        ("plan.rs", "use crate::graph::Graph;\n"),
    ]
    .map(|(rel, text)| (rel.to_string(), text.to_string()));
    let errors = violations(&rows, &files);
    assert_eq!(
        errors,
        [
            "engine/src/graph.rs:1: `crate::plan::Plan`: `graph` (stage load) imports `plan` of a later stage (plan)",
            "engine/src/graph.rs:1: `crate::load::declare`: `graph` imports `load` of its own stage (load), which imports it back: load → graph",
            "engine/src/load.rs:2: `crate::graph::g`: `load` imports `graph` of its own stage (load), which imports it back: graph → load",
        ]
    );
}
