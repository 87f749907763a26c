//! The Markdown the commands write (headings, paragraphs, lists, pipe tables, **bold** and
//! `code`), cut into blocks that the report's page lays out; the inline marks are left for
//! the page to draw.

use serde::Serialize;

/// One block of a Markdown text.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Block {
    /// `# text` at `level` (the number of `#`).
    Heading { level: usize, text: String },
    /// Lines of running text, joined by spaces.
    Paragraph { text: String },
    /// `- item` lines.
    List { items: Vec<String> },
    /// A pipe table: its header, which columns are right-aligned (`---:`) and its rows.
    Table {
        header: Vec<String>,
        right: Vec<bool>,
        rows: Vec<Vec<String>>,
    },
}

/// Cuts `text` into blocks: a blank line ends a paragraph, list or table.
pub fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    for chunk in text.split("\n\n") {
        let first = out.len();
        let mut table: Vec<Vec<String>> = Vec::new();
        for line in chunk.lines().map(str::trim).filter(|l| !l.is_empty()) {
            if line.starts_with('|') {
                table.push(cells(line));
            } else {
                add_line(&mut out, first, line);
            }
        }
        if !table.is_empty() {
            out.push(to_table(table));
        }
    }
    out
}

/// Adds a line that is not a table row: a heading, a list item or running text, which
/// continues a list or paragraph among the blocks from `first` on (those of its chunk).
fn add_line(out: &mut Vec<Block>, first: usize, line: &str) {
    let hashes = line.chars().take_while(|&c| c == '#').count();
    let last = out[first..].last_mut();
    if hashes > 0 && line[hashes..].starts_with(' ') {
        let text = line[hashes..].trim().to_string();
        out.push(Block::Heading { level: hashes, text });
    } else if let Some(item) = line.strip_prefix("- ") {
        match last {
            Some(Block::List { items }) => items.push(item.to_string()),
            _ => out.push(Block::List {
                items: vec![item.to_string()],
            }),
        }
    } else {
        match last {
            Some(Block::Paragraph { text }) => {
                text.push(' ');
                text.push_str(line);
            }
            _ => out.push(Block::Paragraph { text: line.to_string() }),
        }
    }
}

/// The cells of a table row `| a | b |`.
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim_matches('|');
    inner.split('|').map(|c| c.trim().to_string()).collect()
}

/// A table from its rows: the first is the header; a second of dashes gives the alignment.
fn to_table(mut rows: Vec<Vec<String>>) -> Block {
    let header = rows.remove(0);
    let is_rule = |r: &Vec<String>| r.iter().all(|c| !c.is_empty() && c.chars().all(|ch| "-:".contains(ch)));
    let right = match rows.first() {
        Some(r) if is_rule(r) => r.iter().map(|c| c.ends_with(':')).collect(),
        _ => vec![false; header.len()],
    };
    if rows.first().is_some_and(is_rule) {
        rows.remove(0);
    }
    Block::Table { header, right, rows }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_paragraphs_lists_and_tables() {
        let md =
            "# Title\n\nOne line\nand another.\n\n- a\n- b\n\n| x | y |\n|---|---:|\n| 1 | 2 |\n| 3 | 4 |\n\nEnd.\n";
        let b = blocks(md);
        assert_eq!(
            b,
            vec![
                Block::Heading {
                    level: 1,
                    text: "Title".into()
                },
                Block::Paragraph {
                    text: "One line and another.".into()
                },
                Block::List {
                    items: vec!["a".into(), "b".into()]
                },
                Block::Table {
                    header: vec!["x".into(), "y".into()],
                    right: vec![false, true],
                    rows: vec![vec!["1".into(), "2".into()], vec!["3".into(), "4".into()]]
                },
                Block::Paragraph { text: "End.".into() },
            ]
        );
    }
}
