//! The declared gaps of a list of graphs in Markdown: for each graph a line that links its file
//! and says which graph's `coverage:` holds for it, then a list of what it estimates (where not
//! radiance), the classes of paths it misses and those it samples with bias, in Heckbert's
//! notation, each with its condition and reason.

use super::coverage::{Claim, Coverage, Declared};

/// The width lines are wrapped to where words allow.
const WIDTH: usize = 96;

/// The gaps of `graphs` in Markdown, for a page `to_root` (e.g. `../../`) below the repository's
/// root; a graph that keeps a declaration shown above it points there instead of repeating it.
pub fn markdown(graphs: &[Declared], to_root: &str) -> String {
    let mut out = String::new();
    for (i, graph) in graphs.iter().enumerate() {
        let from = graph.declaring();
        let shown_above = graphs[..i]
            .iter()
            .any(|g| std::ptr::eq(g.declaring(), g) && g.file == from.file);
        let link = format!("`{}` ([{}]({to_root}{}))", graph.name, graph.file, graph.file);
        let head = match &graph.base {
            None => format!("{link}:"),
            Some(base) if std::ptr::eq(from, graph) => {
                format!("{link}, which extends `{}`, declares its own:", base.name)
            }
            Some(base) => {
                let whose = if base.file == from.file {
                    "its".to_string()
                } else {
                    format!("`{}`'s", from.name)
                };
                let end = if shown_above { " (above)." } else { ":" };
                format!("{link} extends `{}` and keeps {whose} declaration{end}", base.name)
            }
        };
        out.push_str(&wrap(&head, "", ""));
        out.push('\n');
        if !std::ptr::eq(from, graph) && shown_above {
            continue;
        }
        out.push_str(&items(&graph.coverage()));
        out.push('\n');
    }
    out
}

/// The list of what `coverage` declares.
fn items(coverage: &Coverage) -> String {
    let mut out = String::new();
    if let Some(quantity) = &coverage.estimates {
        out.push_str(&wrap(&format!("estimates {quantity}"), "- ", "  "));
    }
    for miss in &coverage.misses {
        out.push_str(&wrap(&claim("misses", miss), "- ", "  "));
    }
    for biased in &coverage.biased {
        out.push_str(&wrap(&claim("biased for", biased), "- ", "  "));
    }
    if coverage.misses.is_empty() && coverage.biased.is_empty() {
        out.push_str("- no gap declared: every path is held to an unbiased estimator's standard\n");
    }
    for feature in &coverage.handles {
        out.push_str(&wrap(
            &format!("handles {feature} (scenes with them are refused by graphs that do not)"),
            "- ",
            "  ",
        ));
    }
    out
}

/// One claim: `what`, the class, its condition and its reason.
fn claim(what: &str, claim: &Claim) -> String {
    let mut text = format!("{what} `{}`", claim.paths);
    if let Some(when) = &claim.when {
        text.push_str(&format!(" when `{when}`"));
    }
    if !claim.why.is_empty() {
        text.push_str(&format!(": {}", claim.why));
    }
    text
}

/// `text` in lines of at most `WIDTH` characters where its words allow, the first after
/// `first`, the others after `rest`: a code span stays on one line, and no line starts with a
/// word that would begin a Markdown block there (a list item, a heading, a quote).
fn wrap(text: &str, first: &str, rest: &str) -> String {
    let mut lines = vec![first.to_string()];
    for (i, word) in words(text).into_iter().enumerate() {
        let line = lines.last_mut().unwrap();
        if i > 0 && line.chars().count() + 1 + word.chars().count() > WIDTH && !starts_block(&word) {
            lines.push(format!("{rest}{word}"));
            continue;
        }
        if i > 0 {
            line.push(' ');
        }
        line.push_str(&word);
    }
    lines.join("\n") + "\n"
}

/// The words of `text`, each code span (between backticks) one word with its spaces.
fn words(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut in_span = false;
    for word in text.split([' ', '\n']) {
        match out.last_mut() {
            Some(last) if in_span => {
                last.push(' ');
                last.push_str(word);
            }
            _ if word.is_empty() => continue,
            _ => out.push(word.to_string()),
        }
        in_span ^= word.matches('`').count() % 2 == 1;
    }
    out
}

/// Whether a line that starts with `word` would start a Markdown block (in a list item too).
fn starts_block(word: &str) -> bool {
    let digits = word.trim_start_matches(|c: char| c.is_ascii_digit());
    word.starts_with(['-', '+', '*', '>', '#', '=', '|'])
        || (digits.len() < word.len() && digits.starts_with(['.', ')']))
}

#[cfg(test)]
mod tests {
    use super::{WIDTH, markdown, wrap};
    use crate::docs::coverage::{Claim, Coverage, Declared};

    fn graph(name: &str, base: Option<Declared>, own: Option<Coverage>) -> Declared {
        Declared {
            file: format!("graphs/{name}.ron"),
            name: name.to_string(),
            base: base.map(Box::new),
            own,
        }
    }

    fn biased() -> Coverage {
        Coverage {
            biased: vec![Claim {
                paths: "L X* (D|G) X* E".into(),
                when: Some("MERGE".into()),
                why: "merges blur by the radius r_i = PM_RADIUS i^((PM_ALPHA - 1) / 2), which shrinks".into(),
            }],
            ..Coverage::default()
        }
    }

    /// Each graph links its file; one that keeps a declaration shown above points to it, one
    /// whose base is not on the page shows the kept declaration, one with its own shows that.
    #[test]
    fn graphs_show_their_own_or_the_kept_declaration() {
        let base = || graph("ppm", None, Some(biased()));
        let misses = Coverage {
            misses: vec![Claim {
                paths: "Ld S X* E".into(),
                when: None,
                why: String::new(),
            }],
            ..Coverage::default()
        };
        let graphs = [
            base(),
            graph("sppm", Some(base()), None),
            graph("own", Some(base()), Some(misses)),
        ];
        let md = markdown(&graphs, "../../");
        let want = "`ppm` ([graphs/ppm.ron](../../graphs/ppm.ron)):\n\n\
            - biased for `L X* (D|G) X* E` when `MERGE`: merges blur by the radius r_i = PM_RADIUS\n  \
            i^((PM_ALPHA - 1) / 2), which shrinks\n\n\
            `sppm` ([graphs/sppm.ron](../../graphs/sppm.ron)) extends `ppm` and keeps its declaration\n(above).\n\n\
            `own` ([graphs/own.ron](../../graphs/own.ron)), which extends `ppm`, declares its own:\n\n\
            - misses `Ld S X* E`\n\n";
        assert_eq!(md, want);
        let alone = markdown(&[graph("sppm", Some(base()), None)], "../");
        assert!(
            alone.contains("(../graphs/sppm.ron)) extends `ppm` and keeps its declaration:\n\n- biased for"),
            "{alone}"
        );
        let chain = markdown(&[graph("c", Some(graph("sppm", Some(base()), None)), None)], "");
        assert!(
            chain.contains(" extends `sppm` and keeps `ppm`'s declaration:\n\n- biased for"),
            "{chain}"
        );
        let none = markdown(&[graph("pt", None, None)], "");
        assert!(
            none.ends_with(":\n\n- no gap declared: every path is held to an unbiased estimator's standard\n\n"),
            "{none}"
        );
    }

    /// Long text wraps at word ends, keeps code spans whole, and starts no line with what would
    /// begin a Markdown block (the `- 1)` of a formula would start a list).
    #[test]
    fn wrapping_keeps_code_spans_and_starts_no_block() {
        let filler = "a".repeat(WIDTH - 5);
        let text = format!("{filler} x - 1) and `L X* E` {filler} `Ld S+ ((D|G) S+)+ E` end");
        let wrapped = wrap(&text, "- ", "  ");
        let lines: Vec<&str> = wrapped.lines().collect();
        assert!(lines.len() > 2, "{wrapped}");
        for line in &lines[1..] {
            let first = line.trim_start().split(' ').next().unwrap();
            assert!(!["-", "1)", "+"].contains(&first), "{wrapped}");
            assert_eq!(line.matches('`').count() % 2, 0, "{wrapped}");
        }
        assert!(wrapped.contains("`Ld S+ ((D|G) S+)+ E`"), "{wrapped}");
        assert_eq!(
            wrapped.split_whitespace().collect::<Vec<_>>(),
            ["-"].into_iter().chain(text.split(' ')).collect::<Vec<_>>()
        );
    }
}
