//! `cargo xtask docs [--check]`: the docs generated from the code, docs/reference/cli.md
//! (from clap's description of the command line, printed by the example `cli-reference`),
//! docs/reference/graph-file.md (from the doc comments of engine/src/ir.rs) and the declared
//! gaps on the pages of docs/estimators (from the graph files' `coverage:`); `--check` fails
//! when the committed files differ from them.

mod coverage;
mod estimator_pages;
mod gaps;
mod graph_file;
mod schema;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Each generated file (a path from the root) with its contents.
fn generated(root: &Path) -> Result<Vec<(String, String)>, String> {
    let source = "engine/src/ir.rs";
    let text = std::fs::read_to_string(root.join(source)).map_err(|e| format!("cannot read {source}: {e}"))?;
    let schema = schema::read(&text).map_err(|e| format!("{source}: {e}"))?;
    let graph_file = graph_file::markdown(&schema).map_err(|e| format!("{source}: {e}"))?;
    let mut docs = vec![
        ("docs/reference/cli.md".to_string(), cli_reference()?),
        ("docs/reference/graph-file.md".to_string(), graph_file),
    ];
    docs.extend(estimator_pages::generated(root)?);
    Ok(docs)
}

/// The output of the example `cli-reference`, built with the test suite's packages and profile
/// (so that nothing is built twice).
fn cli_reference() -> Result<String, String> {
    let built = crate::cargo_command()
        .args([
            "build",
            "--release",
            "--workspace",
            "--exclude",
            "lightgraph-python",
            "--example",
            "cli-reference",
        ])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !built.success() {
        return Err("building the example cli-reference failed".into());
    }
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root().join("target"), Into::into);
    let out = Command::new(target.join("release/examples/cli-reference"))
        .output()
        .map_err(|e| format!("cannot run the example cli-reference: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "the example cli-reference failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    String::from_utf8(out.stdout).map_err(|e| format!("the example cli-reference printed no UTF-8: {e}"))
}

/// The committed files under `root` that differ from `docs`, each with its first differing line,
/// as one error that says how to regenerate them.
fn check(root: &Path, docs: &[(String, String)]) -> Result<(), String> {
    let mut stale = Vec::new();
    for (path, want) in docs {
        let have = std::fs::read_to_string(root.join(path)).unwrap_or_default();
        if have == *want {
            continue;
        }
        let line = have.lines().zip(want.lines()).take_while(|(a, b)| a == b).count() + 1;
        stale.push(format!("  {path} (from line {line})"));
    }
    if stale.is_empty() {
        return Ok(());
    }
    Err(format!(
        "the committed docs differ from the code:\n{}\nregenerate them with `cargo xtask docs` and commit the result",
        stale.join("\n")
    ))
}

/// Runs `cargo xtask docs` with `args` (`--check` or nothing).
pub fn run(args: &[String]) -> ExitCode {
    let check_only = match args {
        [] => false,
        [a] if a == "--check" => true,
        _ => {
            eprintln!("usage: cargo xtask docs [--check]");
            return ExitCode::from(2);
        }
    };
    let root = root();
    let result = generated(&root).and_then(|docs| {
        if check_only {
            return check(&root, &docs);
        }
        for (path, text) in &docs {
            let file = root.join(path);
            if std::fs::read_to_string(&file).is_ok_and(|have| have == *text) {
                continue;
            }
            std::fs::create_dir_all(file.parent().unwrap())
                .and_then(|_| std::fs::write(&file, text))
                .map_err(|e| format!("cannot write {path}: {e}"))?;
            eprintln!("xtask: wrote {path}");
        }
        Ok(())
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask docs: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{check, estimator_pages, graph_file, root, schema};

    /// The check passes on files equal to the generated ones and fails on a stale or missing
    /// one, naming it, the line where it differs, and the command that regenerates it.
    #[test]
    fn the_check_finds_a_stale_reference() {
        let dir = std::env::temp_dir().join(format!("xtask-docs-check-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("docs/reference")).unwrap();
        let docs = vec![
            ("docs/reference/a.md".to_string(), "# A\n\nfirst\n".to_string()),
            ("docs/reference/b.md".to_string(), "# B\n".to_string()),
        ];
        std::fs::write(dir.join("docs/reference/a.md"), "# A\n\nfirst\n").unwrap();
        std::fs::write(dir.join("docs/reference/b.md"), "# B\n").unwrap();
        assert_eq!(check(&dir, &docs), Ok(()));
        std::fs::write(dir.join("docs/reference/a.md"), "# A\n\nold\n").unwrap();
        std::fs::remove_file(dir.join("docs/reference/b.md")).unwrap();
        let err = check(&dir, &docs).unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(err.contains("docs/reference/a.md (from line 3)"), "{err}");
        assert!(err.contains("docs/reference/b.md (from line 1)"), "{err}");
        assert!(err.contains("cargo xtask docs"), "{err}");
    }

    /// The committed graph-file reference is the one the doc comments of engine/src/ir.rs give
    /// (the CLI's needs the lightgraph binary's build: `cargo xtask docs --check`).
    #[test]
    fn the_graph_file_reference_is_current() {
        let root = root();
        let source = std::fs::read_to_string(root.join("engine/src/ir.rs")).unwrap();
        let md = graph_file::markdown(&schema::read(&source).unwrap()).unwrap();
        let docs = vec![("docs/reference/graph-file.md".to_string(), md)];
        check(&root, &docs).unwrap_or_else(|e| panic!("{e}"));
    }

    /// The declared gaps on the committed pages of docs/estimators are the graph files'.
    #[test]
    fn the_estimator_pages_are_current() {
        let root = root();
        let pages = estimator_pages::generated(&root).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            pages
                .iter()
                .any(|(page, _)| page == "docs/estimators/photon-mapping.md")
        );
        check(&root, &pages).unwrap_or_else(|e| panic!("{e}"));
    }
}
