//! The check on small constructed crates: circles found and named, what is no circle.

use super::*;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The circles of a crate made of `files` (path, text), its root `lib.rs`.
fn circles_of(files: &[(&str, &str)]) -> Vec<String> {
    let files: BTreeMap<PathBuf, String> = files.iter().map(|(p, t)| (PathBuf::from(p), t.to_string())).collect();
    let read = |p: &Path| files.get(p).cloned().ok_or_else(|| format!("no file {}", p.display()));
    let found = crate_circles("t", Path::new("lib.rs"), &read).unwrap();
    found.into_iter().map(|c| c.name).collect()
}

#[test]
fn two_modules_naming_each_other_are_a_circle() {
    let files = [
        ("lib.rs", "mod a; mod b;"),
        ("a.rs", "use crate::b::B; pub struct A;"),
        ("b.rs", "pub struct B(super::a::A);"),
    ];
    assert_eq!(circles_of(&files), ["t: a -> b -> a"]);
}

#[test]
fn a_circle_of_submodules_is_named_with_their_paths() {
    let files = [
        ("lib.rs", "mod p;"),
        ("p/mod.rs", "mod x; mod y; mod z;"),
        ("p/x.rs", "pub fn f() { super::y::g() }"),
        ("p/y.rs", "pub fn g() { crate::p::z::h() }"),
        ("p/z.rs", "pub fn h() { let _ = format!(\"{:?}\", super::x::f()); }"),
    ];
    assert_eq!(circles_of(&files), ["t: p::x -> p::y -> p::z -> p::x"]);
}

#[test]
fn re_exports_and_globs_are_followed() {
    let files = [
        ("lib.rs", "mod a; mod b; pub use a::A;"),
        ("a.rs", "use crate::b::*; pub struct A(B);"),
        ("b.rs", "pub struct B; fn f(_: crate::A) {}"),
    ];
    assert_eq!(circles_of(&files), ["t: a -> b -> a"]);
}

#[test]
fn a_module_may_use_its_parent_and_children_and_other_crates_and_test_code_anything() {
    let files = [
        ("lib.rs", "pub struct R; mod a; mod b; mod gltf; fn f() { a::g(); }"),
        (
            "a.rs",
            "use super::*; mod inner { pub fn h() { super::g() } } pub fn g() { inner::h(); let _ = R; } \
             #[cfg(test)] mod tests { use crate::b::k; }",
        ),
        // `gltf` here is the other crate of that name, not the sibling module.
        ("b.rs", "use gltf::Document; pub fn k() { crate::a::g() }"),
        ("gltf.rs", "pub fn x() {}"),
    ];
    assert!(circles_of(&files).is_empty());
}

#[test]
fn the_check_fails_on_new_and_on_stale_circles() {
    let found = vec!["t: a -> b -> a".to_string()];
    assert!(check(&found, &["t: a -> b -> a"]).is_ok());
    let new = check(&found, &[]).unwrap_err();
    assert!(
        new.contains("new import circle") && new.contains("t: a -> b -> a"),
        "{new}"
    );
    let stale = check(&[], &["t: a -> b -> a"]).unwrap_err();
    assert!(
        stale.contains("no longer found") && stale.contains("t: a -> b -> a"),
        "{stale}"
    );
}
