//! Embeds the graphs, pass catalogs, WGSL sources and scene files (and the density grids of
//! built-in scenes) in the binary, so the
//! tool runs from anywhere (the GPU machine gets only the binary). Files added to those
//! folders are picked up without Rust changes.

use std::fmt::Write;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, suffixes: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n == "src" || n == "target") {
                continue;
            }
            collect(&p, suffixes, out);
        } else if suffixes.iter().any(|s| p.to_string_lossy().ends_with(s)) {
            out.push(p);
        }
    }
}

/// The path of `f` below `root`, with `/` between its parts.
fn virtual_path(root: &Path, f: &Path) -> String {
    f.strip_prefix(root)
        .expect("collected below the root")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect::<Vec<_>>()
        .join("/")
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for (dir, suffixes) in [
        ("graphs", &[".ron"][..]),
        ("passes", &[".ron"]),
        ("shaders", &[".wgsl"]),
        ("scenes", &[".ron"]),
    ] {
        println!("cargo:rerun-if-changed={dir}");
        collect(&root.join(dir), suffixes, &mut files);
    }
    let mut code = String::from(
        "/// Files built into the binary: (virtual path, contents).\npub static FILES: &[(&str, &str)] = &[\n",
    );
    for f in &files {
        let _ = writeln!(
            code,
            "    ({:?}, include_str!({:?})),",
            virtual_path(&root, f),
            f.display().to_string()
        );
    }
    code.push_str("];\n");
    // Binary files of built-in scenes: density grids (`.vol`).
    let mut binaries = Vec::new();
    collect(&root.join("scenes"), &[".vol"], &mut binaries);
    code.push_str("/// Binary files built into the binary: (virtual path, bytes).\npub static BINARY_FILES: &[(&str, &[u8])] = &[\n");
    for f in &binaries {
        let _ = writeln!(
            code,
            "    ({:?}, include_bytes!({:?})),",
            virtual_path(&root, f),
            f.display().to_string()
        );
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("embedded.rs");
    std::fs::write(out, code).expect("writing embedded.rs");
}
