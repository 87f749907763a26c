//! The command line's reference in Markdown (docs/reference/cli.md), written from clap's
//! description of [`Cli`](super::Cli): every command, its arguments and options with their
//! help, defaults, possible values and environment variables. `cargo xtask docs` writes it
//! and `cargo xtask docs --check` compares it with the committed file.

use clap::{Arg, ArgAction, Command, CommandFactory};
use std::fmt::Write;

/// The reference of the `lightgraph` command line.
pub fn markdown() -> String {
    command_markdown(super::Cli::command())
}

/// The reference of command `root` and its subcommands, in the order clap lists them.
pub fn command_markdown(mut root: Command) -> String {
    root.build();
    let name = root.get_name().to_string();
    let mut out = format!(
        "# The `{name}` command line\n\n<!-- Generated from the code by `cargo xtask docs`: edit the doc comments of the \
         options, not this file. -->\n\n"
    );
    if let Some(about) = root.get_long_about().or(root.get_about()) {
        writeln!(out, "{}\n", escape(&about.to_string())).unwrap();
    }
    out.push_str("Commands:\n\n");
    for sub in visible_subcommands(&root) {
        let path = format!("{name} {}", sub.get_name());
        let about = sub.get_about().map(|a| escape(&a.to_string())).unwrap_or_default();
        writeln!(out, "- [`{path}`](#{}): {about}", anchor(&path)).unwrap();
    }
    out.push('\n');
    for sub in visible_subcommands(&root) {
        section(&mut out, sub, &name);
    }
    out
}

/// The subcommands a user sees (not clap's `help`).
fn visible_subcommands(cmd: &Command) -> impl Iterator<Item = &Command> {
    cmd.get_subcommands()
        .filter(|s| !s.is_hide_set() && s.get_name() != "help")
}

/// The section of `cmd`, a subcommand of `parent` (the command path above it), and of its own
/// subcommands.
fn section(out: &mut String, cmd: &Command, parent: &str) {
    let path = format!("{parent} {}", cmd.get_name());
    writeln!(out, "## `{path}`\n").unwrap();
    if let Some(about) = cmd.get_long_about().or(cmd.get_about()) {
        writeln!(out, "{}\n", escape(&about.to_string())).unwrap();
    }
    let usage = cmd.clone().render_usage().to_string();
    let usage = usage.trim_start_matches("Usage: ");
    writeln!(out, "```text\n{usage}\n```\n").unwrap();
    let subs: Vec<&Command> = visible_subcommands(cmd).collect();
    if !subs.is_empty() {
        out.push_str("Commands:\n\n");
        for sub in &subs {
            let sub_path = format!("{path} {}", sub.get_name());
            let about = sub.get_about().map(|a| escape(&a.to_string())).unwrap_or_default();
            writeln!(out, "- [`{sub_path}`](#{}): {about}", anchor(&sub_path)).unwrap();
        }
        out.push('\n');
    }
    let args: Vec<&Arg> = cmd.get_arguments().filter(|a| shown(a)).collect();
    for (title, positional) in [("Arguments", true), ("Options", false)] {
        let group: Vec<&&Arg> = args.iter().filter(|a| a.is_positional() == positional).collect();
        if group.is_empty() {
            continue;
        }
        writeln!(out, "{title}:\n").unwrap();
        for arg in group {
            arg_item(out, arg);
        }
        out.push('\n');
    }
    for sub in subs {
        section(out, sub, &path);
    }
}

/// Whether `arg` is documented: not hidden, not clap's own `--help` and `--version`.
fn shown(arg: &Arg) -> bool {
    !arg.is_hide_set()
        && !matches!(
            arg.get_action(),
            ArgAction::Help | ArgAction::Version | ArgAction::HelpLong | ArgAction::HelpShort
        )
}

/// One list item: the argument as written, its help, default, possible values and variable.
fn arg_item(out: &mut String, arg: &Arg) {
    let value = arg
        .get_value_names()
        .and_then(|names| names.first())
        .map_or_else(|| arg.get_id().as_str().to_uppercase(), |n| n.to_string());
    let takes_value = arg.get_action().takes_values();
    let optional_value = arg.get_num_args().is_some_and(|n| n.min_values() == 0);
    let value = match (takes_value, optional_value) {
        (false, _) => String::new(),
        (true, false) => format!(" <{value}>"),
        (true, true) => format!(" [{value}]"),
    };
    let written = match (arg.get_long(), arg.get_short()) {
        (Some(long), Some(short)) => format!("-{short}, --{long}{value}"),
        (Some(long), None) => format!("--{long}{value}"),
        (None, Some(short)) => format!("-{short}{value}"),
        (None, None) => value.trim_start().to_string(),
    };
    let help = arg
        .get_long_help()
        .or(arg.get_help())
        .map(|h| h.to_string())
        .unwrap_or_default();
    write!(out, "- `{written}`").unwrap();
    if !help.is_empty() {
        write!(out, ": {}", indent(&sentence(&escape(&help)))).unwrap();
    }
    out.push('\n');
    let notes = notes(arg, takes_value);
    if !notes.is_empty() {
        writeln!(out, "  {}", notes.join(" ")).unwrap();
    }
}

/// What clap knows of `arg` beside its help, a sentence each: its default and possible values
/// (where it takes a value), its environment variable, whether it is required.
fn notes(arg: &Arg, takes_value: bool) -> Vec<String> {
    let mut notes = Vec::new();
    let defaults: Vec<String> = arg
        .get_default_values()
        .iter()
        .map(|v| format!("`{}`", v.to_string_lossy()))
        .collect();
    if !defaults.is_empty() && takes_value {
        notes.push(format!("Default: {}.", defaults.join(", ")));
    }
    let possible: Vec<String> = arg
        .get_possible_values()
        .iter()
        .filter(|v| !v.is_hide_set())
        .map(|v| match v.get_help() {
            Some(h) => format!("`{}` ({})", v.get_name(), escape(&h.to_string())),
            None => format!("`{}`", v.get_name()),
        })
        .collect();
    if !possible.is_empty() && takes_value {
        notes.push(format!("One of: {}.", possible.join(", ")));
    }
    if let Some(env) = arg.get_env() {
        notes.push(format!("Environment variable: `{}`.", env.to_string_lossy()));
    }
    if arg.is_required_set() && !arg.is_positional() {
        notes.push("Required.".to_string());
    }
    notes
}

/// `text` ending in a full stop (clap drops the last one of a one-paragraph doc comment).
fn sentence(text: &str) -> String {
    let text = text.trim_end();
    match text.chars().last() {
        Some('.' | '!' | '?' | ':') | None => text.to_string(),
        Some(_) => format!("{text}."),
    }
}

/// The anchor GitHub gives a heading of `text` in backticks.
fn anchor(text: &str) -> String {
    text.chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c.to_ascii_lowercase()),
            _ => None,
        })
        .collect()
}

/// Help text with its lines after the first indented into a list item.
fn indent(text: &str) -> String {
    text.trim_end().replace('\n', "\n  ").replace("\n  \n", "\n\n")
}

/// Help text with `<` escaped outside code spans, so that `<NAME>` is not read as HTML.
fn escape(text: &str) -> String {
    text.split('`')
        .enumerate()
        .map(|(i, part)| {
            if i % 2 == 0 {
                part.replace('<', "\\<")
            } else {
                part.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("`")
}

#[cfg(test)]
mod tests {
    use super::command_markdown;
    use clap::{Arg, ArgAction, Command};

    /// Each piece of an option reaches the reference: help, default, possible values, variable,
    /// and a subcommand's own subcommands.
    #[test]
    fn the_reference_shows_what_an_option_says() {
        let cli = Command::new("tool").about("A tool.").subcommand(
            Command::new("run")
                .about("Runs <it>, `<not this>`.")
                .arg(Arg::new("file").help("The input."))
                .arg(
                    Arg::new("mode")
                        .long("mode")
                        .help("How.\n\nMore on how.")
                        .default_value("fast")
                        .value_parser(["fast", "slow"]),
                )
                .arg(Arg::new("root").long("root").env("TOOL_ROOT").help("Where."))
                .arg(Arg::new("quiet").short('q').long("quiet").action(ArgAction::SetTrue))
                .subcommand(Command::new("again").about("Runs it again.")),
        );
        let md = command_markdown(cli);
        for expected in [
            "# The `tool` command line",
            "- [`tool run`](#tool-run): Runs \\<it>, `<not this>`.",
            "## `tool run`",
            "tool run [OPTIONS] [file] [COMMAND]",
            "- `<FILE>`: The input.",
            "- `--mode <MODE>`: How.\n\n  More on how.\n  Default: `fast`. One of: `fast`, `slow`.",
            "- `--root <ROOT>`: Where.\n  Environment variable: `TOOL_ROOT`.",
            "- `-q, --quiet`\n",
            "## `tool run again`",
        ] {
            assert!(md.contains(expected), "missing {expected:?} in:\n{md}");
        }
        assert!(!md.contains("--help"), "clap's own --help is not documented:\n{md}");
    }
}
