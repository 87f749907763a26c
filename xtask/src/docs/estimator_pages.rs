//! The declared gaps on the pages of docs/estimators: a page holds, where they go, the lines
//! `<!-- generated: cargo xtask docs (coverage of graphs/a.ron, graphs/b.ron) -->` and
//! `<!-- end generated -->`, and what lies between them is rewritten from the named graph files'
//! `coverage:` declarations. Every graph of graphs/ that estimates radiance must be named on a
//! page.

use super::coverage::{self, Declared};
use super::gaps;
use std::collections::BTreeSet;
use std::path::Path;

/// The folder of the pages, from the root.
const PAGES: &str = "docs/estimators";
/// The folder of the graph files, from the root.
const GRAPHS: &str = "graphs";
/// A block's first line, before the graph files.
const START: &str = "<!-- generated: cargo xtask docs (coverage of ";
/// A block's first line, after the graph files.
const START_TAIL: &str = ") -->";
/// A block's last line.
const END: &str = "<!-- end generated -->";

/// Each page of docs/estimators under `root` (a path from the root) with its blocks rewritten;
/// an error where a graph of graphs/ that estimates radiance is on no page.
pub fn generated(root: &Path) -> Result<Vec<(String, String)>, String> {
    let mut pages = Vec::new();
    let mut named = BTreeSet::new();
    for page in files(root, PAGES, "md")? {
        let text = std::fs::read_to_string(root.join(&page)).map_err(|e| format!("cannot read {page}: {e}"))?;
        let (rewritten, graphs) = rewrite(root, &page, &text)?;
        named.extend(graphs);
        pages.push((page, rewritten));
    }
    for file in files(root, GRAPHS, "ron")? {
        let graph = coverage::read(root, &file)?;
        if graph.coverage().estimates.is_none() && !named.contains(&file) {
            return Err(format!(
                "{file} estimates radiance but no page of {PAGES} names it: add it to a page's `{START}...{START_TAIL}` line"
            ));
        }
    }
    Ok(pages)
}

/// The files of `dir` (from `root`) that end in `.{ext}`, as paths from the root, in name order.
fn files(root: &Path, dir: &str, ext: &str) -> Result<Vec<String>, String> {
    let entries = std::fs::read_dir(root.join(dir)).map_err(|e| format!("cannot list {dir}: {e}"))?;
    let mut names = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| format!("cannot list {dir}: {e}"))?.path();
        if path.extension().is_some_and(|x| x == ext) {
            names.push(format!("{dir}/{}", path.file_name().unwrap().to_string_lossy()));
        }
    }
    names.sort();
    Ok(names)
}

/// `text` of `page` with each block rewritten, and the graph files the blocks name.
fn rewrite(root: &Path, page: &str, text: &str) -> Result<(String, Vec<String>), String> {
    let to_root = "../".repeat(page.matches('/').count());
    let mut out = String::new();
    let mut named = Vec::new();
    let mut lines = text.split_inclusive('\n').enumerate();
    while let Some((i, line)) = lines.next() {
        out.push_str(line);
        let at = |e: String| format!("{page}:{}: {e}", i + 1);
        let Some(list) = block_start(line).map_err(at)? else {
            continue;
        };
        let files: Vec<String> = list.split(',').map(|f| f.trim().to_string()).collect();
        let graphs = files
            .iter()
            .map(|f| coverage::read(root, f))
            .collect::<Result<Vec<Declared>, String>>()
            .map_err(at)?;
        if !lines.any(|(_, l)| l.trim_end() == END) {
            return Err(at(format!("no `{END}` line after this block's start")));
        }
        out.push('\n');
        out.push_str(&gaps::markdown(&graphs, &to_root));
        out.push_str(END);
        out.push('\n');
        named.extend(files);
    }
    Ok((out, named))
}

/// The graph files a block's first line names (`None` on any other line); an error on a line
/// that starts like one but is not.
fn block_start(line: &str) -> Result<Option<&str>, String> {
    let line = line.trim_end();
    if !line.starts_with("<!-- generated") {
        return Ok(None);
    }
    match line.strip_prefix(START).and_then(|l| l.strip_suffix(START_TAIL)) {
        Some(list) if !list.trim().is_empty() => Ok(Some(list)),
        _ => Err(format!(
            "a generated block starts `{START}graphs/NAME.ron, ...{START_TAIL}`, not `{line}`"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::generated;
    use crate::docs::check;
    use crate::docs::coverage::tests::tree;

    const PPM: &str = r#"(name: "ppm", passes: [Use("a")],
        coverage: (biased: [(paths: "L X* (D|G) X* E", why: "merges blur")]))"#;
    const PAGE: &str = "# Photon mapping\n\n## Declared gaps\n\nIntro.\n\n\
        <!-- generated: cargo xtask docs (coverage of graphs/ppm.ron, graphs/sppm.ron) -->\n\
        ```ron\ncoverage: (biased: (why: \"old\")),\n```\n<!-- end generated -->\n\n## Outline\n";

    /// A block is rewritten from the graph files it names; after a graph file changes, the
    /// check fails on the page, naming the line where it differs and the command to run.
    #[test]
    fn a_block_is_generated_and_the_check_fails_when_a_graph_changes() {
        let dir = tree(
            "estimator-pages",
            &[
                ("graphs/ppm.ron", PPM),
                ("graphs/sppm.ron", r#"(extends: "graphs/ppm.ron", name: "sppm")"#),
                (
                    "graphs/ao.ron",
                    r#"(name: "ao", coverage: (estimates: "ambient occlusion"))"#,
                ),
                ("docs/estimators/photon-mapping.md", PAGE),
                ("docs/estimators/README.md", "# Estimators\n"),
            ],
        );
        let pages = generated(&dir).unwrap();
        let page = &pages[1].1;
        assert_eq!(
            pages[0],
            ("docs/estimators/README.md".to_string(), "# Estimators\n".to_string())
        );
        assert_eq!(pages[1].0, "docs/estimators/photon-mapping.md");
        let want = "<!-- generated: cargo xtask docs (coverage of graphs/ppm.ron, graphs/sppm.ron) -->\n\n\
            `ppm` ([graphs/ppm.ron](../../graphs/ppm.ron)):\n\n\
            - biased for `L X* (D|G) X* E`: merges blur\n\n\
            `sppm` ([graphs/sppm.ron](../../graphs/sppm.ron)) extends `ppm` and keeps its declaration\n(above).\n\n\
            <!-- end generated -->\n\n## Outline\n";
        assert!(
            page.starts_with("# Photon mapping\n\n## Declared gaps\n\nIntro.\n\n"),
            "{page}"
        );
        assert!(page.ends_with(want), "{page}");
        assert!(check(&dir, &pages).is_err(), "the stale page passes the check");
        std::fs::write(dir.join("docs/estimators/photon-mapping.md"), page).unwrap();
        assert_eq!(check(&dir, &generated(&dir).unwrap()), Ok(()));

        std::fs::write(
            dir.join("graphs/ppm.ron"),
            PPM.replace("merges blur", "merges blur by r_i"),
        )
        .unwrap();
        let stale = check(&dir, &generated(&dir).unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
        let err = stale.unwrap_err();
        assert!(
            err.contains("docs/estimators/photon-mapping.md (from line 11)"),
            "{err}"
        );
        assert!(err.contains("cargo xtask docs"), "{err}");
    }

    /// A graph of radiance no page names, a block without its end, a malformed first line and
    /// a graph file that does not exist are errors naming the file (and the page's line).
    #[test]
    fn bad_pages_are_errors_naming_the_page_and_line() {
        let cases = [
            (
                PAGE.replace(", graphs/sppm.ron", ""),
                "graphs/sppm.ron estimates radiance but no page",
            ),
            (
                PAGE.replace("<!-- end generated -->", ""),
                "photon-mapping.md:7: no `<!-- end generated -->`",
            ),
            (
                PAGE.replace("(coverage of", "(gaps of"),
                "photon-mapping.md:7: a generated block starts",
            ),
            (
                PAGE.replace("sppm.ron)", "spm.ron)"),
                "photon-mapping.md:7: cannot read graphs/spm.ron",
            ),
        ];
        for (i, (page, want)) in cases.into_iter().enumerate() {
            let dir = tree(
                &format!("estimator-pages-bad-{i}"),
                &[
                    ("graphs/ppm.ron", PPM),
                    ("graphs/sppm.ron", r#"(extends: "graphs/ppm.ron")"#),
                    ("docs/estimators/photon-mapping.md", &page),
                ],
            );
            let err = generated(&dir).unwrap_err();
            std::fs::remove_dir_all(&dir).unwrap();
            assert!(err.contains(want), "{err}");
        }
    }
}
