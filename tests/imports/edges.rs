//! The dependencies between a crate's modules: every path a module's code names (`use` trees,
//! paths in types, expressions and patterns, `a::b` sequences in macro bodies), resolved
//! through the module tree and its imports (re-exports and globs followed) to the module that
//! defines what it names.

use super::tree::{Crate, Import, flatten_use, is_test};
use proc_macro2::{TokenStream, TokenTree};
use syn::visit_mut::{self, VisitMut};

/// Imports followed before a path is given up (a loop of re-exports).
const MAX_DEPTH: usize = 32;

/// One module naming something another module defines.
pub struct Dependency {
    /// The module whose code names it.
    pub from: usize,
    /// The module that defines it.
    pub to: usize,
    /// The path as written.
    pub via: String,
}

/// The crate paths named by a module's code (its child modules excluded).
#[derive(Default)]
struct Paths(Vec<Vec<String>>);

impl VisitMut for Paths {
    fn visit_item_mod_mut(&mut self, _: &mut syn::ItemMod) {}
    fn visit_visibility_mut(&mut self, _: &mut syn::Visibility) {}
    fn visit_attribute_mut(&mut self, _: &mut syn::Attribute) {}

    fn visit_item_fn_mut(&mut self, f: &mut syn::ItemFn) {
        if !is_test(&f.attrs) {
            visit_mut::visit_item_fn_mut(self, f);
        }
    }

    fn visit_item_impl_mut(&mut self, i: &mut syn::ItemImpl) {
        if !is_test(&i.attrs) {
            visit_mut::visit_item_impl_mut(self, i);
        }
    }

    fn visit_impl_item_fn_mut(&mut self, f: &mut syn::ImplItemFn) {
        if !is_test(&f.attrs) {
            visit_mut::visit_impl_item_fn_mut(self, f);
        }
    }

    fn visit_item_use_mut(&mut self, u: &mut syn::ItemUse) {
        if u.leading_colon.is_some() {
            return;
        }
        let mut found = Vec::new();
        flatten_use(&u.tree, &mut Vec::new(), &mut found);
        self.0.extend(found.into_iter().map(|i| match i {
            Import::Name(_, path) | Import::Glob(path) => path,
        }));
    }

    fn visit_path_mut(&mut self, p: &mut syn::Path) {
        if p.leading_colon.is_none() && p.segments.len() > 1 {
            self.0.push(p.segments.iter().map(|s| s.ident.to_string()).collect());
        }
        visit_mut::visit_path_mut(self, p);
    }

    fn visit_macro_mut(&mut self, m: &mut syn::Macro) {
        visit_mut::visit_macro_mut(self, m);
        macro_paths(m.tokens.clone(), &mut self.0);
    }
}

/// The `a::b::c` sequences of a macro body (its groups included): macro bodies are tokens,
/// not syntax trees.
fn macro_paths(tokens: TokenStream, out: &mut Vec<Vec<String>>) {
    let tokens: Vec<TokenTree> = tokens.into_iter().collect();
    let mut i = 0;
    while i < tokens.len() {
        match &tokens[i] {
            TokenTree::Group(g) => macro_paths(g.stream(), out),
            TokenTree::Ident(first) => {
                let mut path = vec![first.to_string()];
                while let [TokenTree::Punct(a), TokenTree::Punct(b), TokenTree::Ident(next), ..] = &tokens[i + 1..] {
                    if a.as_char() != ':' || b.as_char() != ':' {
                        break;
                    }
                    path.push(next.to_string());
                    i += 3;
                }
                if path.len() > 1 {
                    out.push(path);
                }
            }
            _ => {}
        }
        i += 1;
    }
}

impl Crate {
    /// Every dependency of every module on another module of the crate.
    pub fn dependencies(&mut self) -> Vec<Dependency> {
        let mut out = Vec::new();
        for from in 0..self.modules.len() {
            let mut paths = Paths::default();
            for item in &mut self.modules[from].items {
                paths.visit_item_mut(item);
            }
            for path in paths.0 {
                if let Some(to) = self.resolve(from, &path, 0)
                    && to != from
                {
                    out.push(Dependency {
                        from,
                        to,
                        via: path.join("::"),
                    });
                }
            }
        }
        out
    }

    /// The module that defines what `path`, named in module `from`, names; None for what is
    /// not the crate's (other crates, locals, generic parameters).
    pub fn resolve(&self, from: usize, path: &[String], depth: usize) -> Option<usize> {
        if depth > MAX_DEPTH {
            return None;
        }
        let (mut at, mut rest) = (from, path);
        match rest.first().map(String::as_str) {
            Some("crate") => (at, rest) = (0, &rest[1..]),
            Some("self") => rest = &rest[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    at = self.modules[at].parent?;
                    rest = &rest[1..];
                }
            }
            Some(_) => return self.walk(at, rest, true, depth),
            None => return None,
        }
        self.walk(at, rest, false, depth)
    }

    /// Follows `rest` down from module `at`. A first segment not in scope names nothing of the
    /// crate when `in_scope` (the first segment of a relative path); later segments not found
    /// stop at the module reached (enum variants, items a macro defines).
    fn walk(&self, mut at: usize, rest: &[String], in_scope: bool, depth: usize) -> Option<usize> {
        for (k, segment) in rest.iter().enumerate() {
            let module = &self.modules[at];
            if let Some(&child) = module.children.get(segment) {
                at = child;
                continue;
            }
            if module.defined.contains(segment) {
                return Some(at);
            }
            let tail = &rest[k + 1..];
            if let Some(target) = module.imports.get(segment) {
                return self.resolve(at, &[target.as_slice(), tail].concat(), depth + 1);
            }
            if let Some(found) = self.through_glob(at, segment, tail, depth) {
                return Some(found);
            }
            return if k == 0 && in_scope { None } else { Some(at) };
        }
        Some(at)
    }

    /// `segment` and `tail` resolved through the glob imports of module `at` that hold
    /// `segment`.
    fn through_glob(&self, at: usize, segment: &String, tail: &[String], depth: usize) -> Option<usize> {
        self.modules[at].globs.iter().find_map(|glob| {
            let source = self.resolve(at, glob, depth + 1)?;
            self.has_name(source, segment, depth + 1)
                .then(|| {
                    self.walk(
                        source,
                        &[std::slice::from_ref(segment), tail].concat(),
                        false,
                        depth + 1,
                    )
                })
                .flatten()
        })
    }

    /// Whether `name` is in the namespace of module `at` (its globs followed).
    fn has_name(&self, at: usize, name: &String, depth: usize) -> bool {
        let m = &self.modules[at];
        if m.children.contains_key(name) || m.defined.contains(name) || m.imports.contains_key(name) {
            return true;
        }
        depth < MAX_DEPTH
            && m.globs.iter().any(|g| {
                self.resolve(at, g, depth + 1)
                    .is_some_and(|s| self.has_name(s, name, depth + 1))
            })
    }
}
