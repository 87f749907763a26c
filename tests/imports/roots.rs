//! The library crates whose root only declares modules and re-exports: the code is in modules
//! whose names say what it does, and the import check sees each of its dependencies.

use std::path::Path;

/// The crate roots held to it (from the workspace root).
const DECLARING_ROOTS: [&str; 2] = ["engine/src/lib.rs", "scenes/src/lib.rs"];

/// The items of the root file `text` other than `mod` and `use`, by their start.
fn code_items(text: &str) -> Result<Vec<String>, String> {
    let file = syn::parse_file(text).map_err(|e| e.to_string())?;
    Ok(file
        .items
        .iter()
        .filter(|i| !matches!(i, syn::Item::Mod(_) | syn::Item::Use(_)))
        .map(describe)
        .collect())
}

/// An item's kind and name, for a message.
fn describe(item: &syn::Item) -> String {
    let named = |kind: &str, ident: &syn::Ident| format!("{kind} {ident}");
    match item {
        syn::Item::Fn(i) => named("fn", &i.sig.ident),
        syn::Item::Struct(i) => named("struct", &i.ident),
        syn::Item::Enum(i) => named("enum", &i.ident),
        syn::Item::Const(i) => named("const", &i.ident),
        syn::Item::Static(i) => named("static", &i.ident),
        syn::Item::Trait(i) => named("trait", &i.ident),
        syn::Item::Type(i) => named("type", &i.ident),
        syn::Item::Impl(_) => "an impl block".to_string(),
        _ => "an item".to_string(),
    }
}

#[test]
fn library_roots_only_declare_modules_and_re_export() {
    for root in DECLARING_ROOTS {
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(root)).unwrap();
        let code = code_items(&text).unwrap();
        assert!(code.is_empty(), "{root}: move these into a module: {code:?}");
    }
}

#[test]
fn a_root_with_a_function_is_refused() {
    let code = code_items("pub mod a;\npub use a::X;\npub fn helper() {}").unwrap();
    assert_eq!(code, ["fn helper"]);
}
