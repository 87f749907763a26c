//! Every relative link of README.md, docs/**/*.md and bench/**/*.md (which name the
//! measurement log's entries) leads somewhere: to a file of the repository and, with
//! `#anchor`, to a heading of that Markdown file (GitHub's anchors).

use std::collections::HashSet;
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// README.md and every Markdown file below docs/ and bench/.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![Path::new(ROOT).join("README.md")];
    let mut dirs = vec![Path::new(ROOT).join("docs"), Path::new(ROOT).join("bench")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files
}

/// The lines of a Markdown file outside fenced code blocks, with their numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fenced = false;
    let mut lines = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced {
            lines.push((i + 1, line));
        }
    }
    lines
}

/// A line without its inline code spans (`...`), where `](x)` is not a link.
fn without_code_spans(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join(" ")
}

/// GitHub's anchor of a heading: lower case, link syntax and punctuation but `-` and `_`
/// dropped, spaces as `-`.
fn anchor(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading.trim();
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find("](").map(|c| c + open) else {
            break;
        };
        let Some(end) = rest[close..].find(')').map(|e| e + close) else {
            break;
        };
        text.push_str(&rest[..open]);
        text.push_str(&rest[open + 1..close]);
        rest = &rest[end + 1..];
    }
    text.push_str(rest);
    text.to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings (a repeated one gets `-1`, `-2`, ...).
fn anchors(path: &Path) -> HashSet<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut seen = HashSet::new();
    for (_, line) in prose_lines(&text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let base = anchor(&line[hashes + 1..]);
            let mut name = base.clone();
            let mut n = 0;
            while !seen.insert(name.clone()) {
                n += 1;
                name = format!("{base}-{n}");
            }
        }
    }
    seen
}

/// The targets of the inline links `[text](target)` and images on a line.
fn link_targets(line: &str) -> Vec<String> {
    let line = without_code_spans(line);
    let mut targets = Vec::new();
    let mut rest = line.as_str();
    while let Some(start) = rest.find("](") {
        let after = &rest[start + 2..];
        let end = after.find(')').unwrap_or(after.len());
        targets.push(after[..end].trim().to_string());
        rest = &after[end..];
    }
    targets
}

/// Why a link of `file` does not resolve, or None when it does.
fn broken(file: &Path, target: &str) -> Option<String> {
    if target.contains("://") || target.starts_with("mailto:") || target.is_empty() {
        return None;
    }
    let (path, fragment) = target.split_once('#').unwrap_or((target, ""));
    let resolved = if path.is_empty() {
        file.to_path_buf()
    } else {
        file.parent().unwrap().join(path)
    };
    if !resolved.exists() {
        return Some(format!("{target}: no file {}", resolved.display()));
    }
    let is_markdown = resolved.extension().is_some_and(|e| e == "md");
    if !fragment.is_empty() && is_markdown && !anchors(&resolved).contains(fragment) {
        return Some(format!("{target}: no heading with the anchor #{fragment}"));
    }
    None
}

#[test]
fn every_relative_link_of_the_docs_resolves() {
    let mut problems = Vec::new();
    let mut links = 0;
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        for (number, line) in prose_lines(&text) {
            for target in link_targets(line) {
                links += 1;
                if let Some(why) = broken(&file, &target) {
                    let name = file.strip_prefix(ROOT).unwrap_or(&file).display().to_string();
                    problems.push(format!("{name}:{number}: {why}"));
                }
            }
        }
    }
    assert!(
        links > 100,
        "only {links} links found in README.md, docs/ and bench/: the scan is broken"
    );
    assert!(
        problems.is_empty(),
        "{} broken links:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn a_broken_link_and_a_missing_anchor_are_found() {
    let readme = Path::new(ROOT).join("README.md");
    assert_eq!(broken(&readme, "docs/performance.md"), None);
    assert!(broken(&readme, "docs/no-such-page.md").is_some());
    assert!(broken(&readme, "docs/performance.md#no-such-heading").is_some());
    assert_eq!(broken(&readme, "#two-commands"), None);
    assert_eq!(anchor("`--layout auto`"), "--layout-auto");
    assert_eq!(
        anchor("Which BVH in which layout (issue 16, item 4)"),
        "which-bvh-in-which-layout-issue-16-item-4"
    );
    assert_eq!(
        link_targets("see [a](x.md) and `[b](y.md)` and ![c](z.png)"),
        ["x.md", "z.png"]
    );
}

/// Every knob and scene layout of the built-in tuning profiles links to the measurement that
/// chose it: a heading of the repository's docs.
#[test]
fn every_tuning_knob_links_to_its_measurement() {
    let root = Path::new(ROOT).join("README.md");
    let mut problems = Vec::new();
    let mut links = 0;
    for p in lightgraph::tuning::built_in() {
        let knobs = p
            .layouts
            .iter()
            .flat_map(|(g, l)| l.iter().map(move |(l, k)| (format!("{g} {l}"), &k.why)));
        let scenes = p.scenes.iter().map(|s| (format!("{} on {}", s.graph, s.scene), &s.why));
        for (what, why) in knobs.chain(scenes) {
            links += 1;
            let problem = match why.starts_with("docs/") && why.contains('#') {
                true => broken(&root, why),
                false => Some(format!("'{why}' is no docs/...#anchor link")),
            };
            if let Some(problem) = problem {
                problems.push(format!("data/tuning/{}.ron, {what}: {problem}", p.name));
            }
        }
    }
    assert!(links >= 30, "only {links} knobs found in the built-in profiles");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
