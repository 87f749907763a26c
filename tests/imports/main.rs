//! The import-circle check: `cargo test --release --test imports` (which `cargo xtask test`
//! runs, and `cargo xtask imports` with the report printed). Its test
//! `no_new_import_circle` fails on a circle not in [`ALLOWED`] and on an entry of it that is
//! no longer a circle.
//!
//! Granularity: sibling modules. Within each module that has child modules (the crate root
//! and every folder or inline `mod`), the children are the nodes of one graph; an edge a -> b
//! means that code in a, or in a module below a, names something defined in b or below b.
//! A dependency between a module and its own ancestor or descendant is no edge (a child using
//! its parent's items is how `use super::*` works). A circle is an elementary cycle of one such
//! graph, named `crate: a -> b -> a` with module paths from the crate root.
//!
//! What a module names: every `use` tree, every path of two or more segments in its code
//! (types, expressions, patterns, trait bounds) and every `a::b`
//! sequence in a macro body; each is resolved through the crate's modules and imports
//! (re-exports and globs followed) to the module that defines the item, so that a re-export in
//! the crate root does not hide who depends on whom. Paths to other crates are ignored.
//! Visibility paths (`pub(in ...)`), attributes and doc links are not dependencies, nor is test
//! code (items under `#[cfg(test)]`): a unit test may drive a later stage to check an earlier
//! one's output.

mod circles;
mod constructed;
mod edges;
mod roots;
mod tree;

use std::collections::BTreeSet;
use std::path::Path;

/// The crates checked: their names in reports and their root files (from the workspace root).
pub const CRATES: [(&str, &str); 7] = [
    ("lightgraph", "src/lib.rs"),
    ("lightgraph (bin)", "src/main.rs"),
    ("lightgraph-engine", "engine/src/lib.rs"),
    ("lightgraph-scenes", "scenes/src/lib.rs"),
    ("lightgraph-python", "python/src/lib.rs"),
    ("xtask", "xtask/src/main.rs"),
    ("integration tests", "tests/integration/main.rs"),
];

/// Circles known and being removed. The check fails on a circle not listed here and on an
/// entry that is no longer a circle, so that the list cannot go stale.
pub const ALLOWED: &[&str] = &[];

/// The circles of the crate whose root file is `root` (read with `read`), named with `name`.
pub fn crate_circles(name: &str, root: &Path, read: tree::Read) -> Result<Vec<circles::Circle>, String> {
    let mut krate = tree::Crate::load(name, root, read)?;
    let dependencies = krate.dependencies();
    Ok(circles::circles(&krate, &dependencies))
}

/// The circles of every crate of [`CRATES`] in the workspace, and a report listing them with
/// the paths that make each step.
pub fn workspace_circles() -> Result<(Vec<String>, String), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |path: &Path| std::fs::read_to_string(path).map_err(|e| e.to_string());
    let (mut names, mut report) = (Vec::new(), String::new());
    for (name, file) in CRATES {
        let found = crate_circles(name, Path::new(file), &|p| read(&root.join(p)))?;
        report += &match found.len() {
            0 => format!("{name}: no import circle\n"),
            n => format!("{name}: {n} import circle(s)\n"),
        };
        for circle in found {
            report += &format!("  {}\n", circle.name);
            for step in &circle.evidence {
                report += &format!("      {step}\n");
            }
            names.push(circle.name);
        }
    }
    Ok((names, report))
}

/// Fails naming each circle of `found` not in `allowed` and each entry of `allowed` not found.
pub fn check(found: &[String], allowed: &[&str]) -> Result<(), String> {
    let found: BTreeSet<&str> = found.iter().map(String::as_str).collect();
    let allowed: BTreeSet<&str> = allowed.iter().copied().collect();
    let new: Vec<&str> = found.difference(&allowed).copied().collect();
    let gone: Vec<&str> = allowed.difference(&found).copied().collect();
    let mut problems = Vec::new();
    if !new.is_empty() {
        problems.push(format!("new import circle(s):\n  {}", new.join("\n  ")));
    }
    if !gone.is_empty() {
        problems.push(format!(
            "allowed circle(s) no longer found: remove them from ALLOWED (tests/imports/main.rs):\n  {}",
            gone.join("\n  ")
        ));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n"))
    }
}

#[test]
fn no_new_import_circle() {
    let (found, report) = workspace_circles().unwrap();
    println!("{report}");
    assert!(
        report.contains("lightgraph-scenes:") && report.contains("lightgraph-engine:"),
        "{report}"
    );
    if let Err(e) = check(&found, ALLOWED) {
        panic!("{e}\n\n{report}");
    }
}
