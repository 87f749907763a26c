//! The `coverage:` declarations of the graph files (what a graph estimates, the classes of
//! paths it cannot sample and those it samples with bias), read as the engine reads them
//! (engine/src/ir.rs, `Coverage`): a graph that extends another keeps its base's declaration
//! unless it declares its own.

use serde::Deserialize;
use std::path::Path;

/// The fields of a graph file the declaration needs; the others are skipped.
#[derive(Deserialize)]
struct Written {
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    extends: Option<String>,
    #[serde(default)]
    coverage: Option<Coverage>,
}

/// A graph's `coverage:`, as engine/src/ir.rs's `Coverage` (a field this one lacks is an error,
/// so that a new one is not left out of the pages unseen).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coverage {
    /// The quantity the graph estimates (radiance when absent).
    #[serde(default)]
    pub estimates: Option<String>,
    /// The classes of paths the graph cannot sample.
    #[serde(default)]
    pub misses: Vec<Claim>,
    /// The classes of paths whose estimate is biased at a finite budget.
    #[serde(default)]
    pub biased: Vec<Claim>,
    /// The scene features the graph declares it handles (lightgraph's `media`).
    #[serde(default)]
    pub handles: Vec<String>,
}

/// One class of paths a graph misses or samples with bias (`MissDecl`, `BiasDecl`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// The class, in Heckbert's notation.
    pub paths: String,
    /// The constant expression under which the claim holds (always without it).
    #[serde(default)]
    pub when: Option<String>,
    /// Why.
    #[serde(default)]
    pub why: String,
}

/// A graph file's declaration, with the graphs it extends.
#[derive(Debug)]
pub struct Declared {
    /// The file, from the repository's root, e.g. `graphs/sppm.ron`.
    pub file: String,
    /// The graph's name (its own, or its base's).
    pub name: String,
    /// The graph it extends.
    pub base: Option<Box<Declared>>,
    /// Its own `coverage:`, if it declares one.
    pub own: Option<Coverage>,
}

impl Declared {
    /// The graph whose `coverage:` holds for this one: itself, or the nearest base that declares
    /// one, or the first graph of the chain (whose absent declaration is the default).
    pub fn declaring(&self) -> &Declared {
        match (&self.own, &self.base) {
            (None, Some(base)) => base.declaring(),
            _ => self,
        }
    }

    /// The declaration that holds for this graph.
    pub fn coverage(&self) -> Coverage {
        self.declaring().own.clone().unwrap_or_default()
    }
}

/// Reads graph `file` (a path from `root`) and the graphs it extends.
pub fn read(root: &Path, file: &str) -> Result<Declared, String> {
    read_chain(root, file, &mut Vec::new())
}

/// Reads `file`; `chain` holds the files that extend it, to refuse a cycle.
fn read_chain(root: &Path, file: &str, chain: &mut Vec<String>) -> Result<Declared, String> {
    if chain.iter().any(|f| f == file) {
        return Err(format!("{}: extends closes a cycle at {file}", chain[0]));
    }
    let text = std::fs::read_to_string(root.join(file)).map_err(|e| format!("cannot read {file}: {e}"))?;
    let written = parse(file, &text)?;
    chain.push(file.to_string());
    let base = match &written.extends {
        Some(base) => Some(Box::new(read_chain(root, base, chain)?)),
        None => None,
    };
    let name = match (written.name, &base) {
        (Some(name), _) => name,
        (None, Some(base)) => base.name.clone(),
        (None, None) => return Err(format!("{file}: no `name`")),
    };
    Ok(Declared {
        file: file.to_string(),
        name,
        base,
        own: written.coverage,
    })
}

/// Parses graph file `file` (text `text`) with the engine's RON extensions.
fn parse(file: &str, text: &str) -> Result<Written, String> {
    ron::Options::default()
        .with_default_extension(
            ron::extensions::Extensions::IMPLICIT_SOME | ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES,
        )
        .from_str(text)
        .map_err(|e| format!("{file}:{}:{}: {}", e.span.start.line, e.span.start.col, e.code))
}

#[cfg(test)]
pub(super) mod tests {
    use super::read;

    /// Writes `files` (path, text) under a fresh folder and returns it.
    pub(in crate::docs) fn tree(test: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("xtask-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (path, text) in files {
            let file = dir.join(path);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(file, text).unwrap();
        }
        dir
    }

    /// A graph that extends another keeps the nearest declaration along the chain, skipping
    /// the fields the pages do not need (enum values included).
    #[test]
    fn an_extending_graph_keeps_its_bases_declaration() {
        let dir = tree(
            "coverage-chain",
            &[
                (
                    "graphs/a.ron",
                    r#"(name: "a", passes: [Use("x"), Count(name: "c", over: "N")],
                        constants: {"K": Bool(true)},
                        coverage: (biased: [(paths: "L X* D X* E", when: "K", why: "blur")]))"#,
                ),
                ("graphs/b.ron", r#"(extends: "graphs/a.ron", name: "b")"#),
                ("graphs/c.ron", r#"(extends: "graphs/b.ron")"#),
                (
                    "graphs/d.ron",
                    r#"(extends: "graphs/a.ron", name: "d", coverage: (misses: [(paths: "La E")]))"#,
                ),
            ],
        );
        let c = read(&dir, "graphs/c.ron").unwrap();
        let d = read(&dir, "graphs/d.ron").unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((c.name.as_str(), c.declaring().file.as_str()), ("b", "graphs/a.ron"));
        let biased = &c.coverage().biased;
        assert_eq!(biased.len(), 1);
        assert_eq!((biased[0].when.as_deref(), biased[0].why.as_str()), (Some("K"), "blur"));
        assert_eq!(d.declaring().file, "graphs/d.ron");
        assert_eq!(
            (d.coverage().misses[0].paths.as_str(), d.coverage().biased.len()),
            ("La E", 0)
        );
    }

    /// A cycle of `extends`, a field `coverage:` does not have and a missing file are errors
    /// that name the file.
    #[test]
    fn bad_graph_files_are_errors_naming_the_file() {
        let dir = tree(
            "coverage-errors",
            &[
                ("graphs/a.ron", r#"(extends: "graphs/b.ron", name: "a")"#),
                ("graphs/b.ron", r#"(extends: "graphs/a.ron", name: "b")"#),
                ("graphs/c.ron", r#"(name: "c", coverage: (misses: [], exact: true))"#),
            ],
        );
        let cycle = read(&dir, "graphs/a.ron").unwrap_err();
        let unknown = read(&dir, "graphs/c.ron").unwrap_err();
        let missing = read(&dir, "graphs/none.ron").unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(cycle.contains("graphs/a.ron: extends closes a cycle"), "{cycle}");
        assert!(
            unknown.starts_with("graphs/c.ron:1:") && unknown.contains("exact"),
            "{unknown}"
        );
        assert!(missing.contains("cannot read graphs/none.ron"), "{missing}");
    }
}
