//! Prints the command line's reference (docs/reference/cli.md): `cargo xtask docs` runs it.

fn main() {
    print!("{}", lightgraph::cli::docs::markdown());
}
