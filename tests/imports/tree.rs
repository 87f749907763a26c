//! A crate's module tree as its source files declare it: each module's file, parent and
//! children, the names it defines and the imports (`use`) it declares.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use syn::{Item, UseTree};

/// Reads a source file (the disk, or a test's files).
pub type Read<'a> = &'a dyn Fn(&Path) -> Result<String, String>;

/// One module of a crate.
pub struct Module {
    /// Its path from the crate root (empty for the root).
    pub path: Vec<String>,
    /// The file that holds it.
    pub file: PathBuf,
    /// Its parent's index (None for the root).
    pub parent: Option<usize>,
    /// Its child modules' indices, by name.
    pub children: BTreeMap<String, usize>,
    /// Its own items (child modules' contents are their own).
    pub items: Vec<Item>,
    /// The names of the items it defines (other than modules).
    pub defined: BTreeSet<String>,
    /// Its imports: the name in scope and the path it imports.
    pub imports: BTreeMap<String, Vec<String>>,
    /// The paths of its glob imports (`use a::*`).
    pub globs: Vec<Vec<String>>,
}

/// The modules of one crate, the root first.
pub struct Crate {
    /// The crate's name in reports.
    pub name: String,
    /// Every module; index 0 is the root.
    pub modules: Vec<Module>,
}

/// What a `use` tree brings into scope.
pub enum Import {
    /// A name and the path it stands for.
    Name(String, Vec<String>),
    /// Everything below a path.
    Glob(Vec<String>),
}

/// The imports of `tree`, each path after `prefix`.
pub fn flatten_use(tree: &UseTree, prefix: &mut Vec<String>, out: &mut Vec<Import>) {
    let named = |prefix: &[String], ident: &syn::Ident| {
        let mut path = prefix.to_vec();
        if ident != "self" {
            path.push(ident.to_string());
        }
        path
    };
    match tree {
        UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            flatten_use(&p.tree, prefix, out);
            prefix.pop();
        }
        UseTree::Name(n) => {
            let path = named(prefix, &n.ident);
            if let Some(last) = path.last() {
                out.push(Import::Name(last.clone(), path));
            }
        }
        UseTree::Rename(r) => out.push(Import::Name(r.rename.to_string(), named(prefix, &r.ident))),
        UseTree::Glob(_) => out.push(Import::Glob(prefix.clone())),
        UseTree::Group(g) => g.items.iter().for_each(|t| flatten_use(t, prefix, out)),
    }
}

/// Whether `attrs` hold `#[cfg(test)]`: test code, which the check leaves out.
pub fn is_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| match &a.meta {
        syn::Meta::List(list) => list.path.is_ident("cfg") && list.tokens.to_string() == "test",
        _ => false,
    })
}

/// The attributes of an item.
fn attributes(item: &Item) -> &[syn::Attribute] {
    match item {
        Item::Const(i) => &i.attrs,
        Item::Enum(i) => &i.attrs,
        Item::ExternCrate(i) => &i.attrs,
        Item::Fn(i) => &i.attrs,
        Item::ForeignMod(i) => &i.attrs,
        Item::Impl(i) => &i.attrs,
        Item::Macro(i) => &i.attrs,
        Item::Mod(i) => &i.attrs,
        Item::Static(i) => &i.attrs,
        Item::Struct(i) => &i.attrs,
        Item::Trait(i) => &i.attrs,
        Item::TraitAlias(i) => &i.attrs,
        Item::Type(i) => &i.attrs,
        Item::Union(i) => &i.attrs,
        Item::Use(i) => &i.attrs,
        _ => &[],
    }
}

/// The name an item defines in its module's namespace, for items other than modules, `use`s
/// and `extern crate`s.
fn defined_name(item: &Item) -> Option<String> {
    let ident = match item {
        Item::Const(i) => &i.ident,
        Item::Enum(i) => &i.ident,
        Item::Fn(i) => &i.sig.ident,
        Item::Static(i) => &i.ident,
        Item::Struct(i) => &i.ident,
        Item::Trait(i) => &i.ident,
        Item::TraitAlias(i) => &i.ident,
        Item::Type(i) => &i.ident,
        Item::Union(i) => &i.ident,
        Item::Macro(i) => i.ident.as_ref()?,
        _ => return None,
    };
    Some(ident.to_string())
}

/// The file of the module `name` declared without a body in a file whose child modules live
/// in `dir` (`#[path]` attributes are not followed: a crate that uses one is refused).
fn module_file(dir: &Path, name: &str, read: Read) -> Result<(PathBuf, String), String> {
    let flat = dir.join(format!("{name}.rs"));
    let nested = dir.join(name).join("mod.rs");
    read(&flat)
        .map(|text| (flat.clone(), text))
        .or_else(|_| read(&nested).map(|text| (nested.clone(), text)))
        .map_err(|e| {
            format!(
                "module {name}: neither {} nor {} can be read ({e})",
                flat.display(),
                nested.display()
            )
        })
}

impl Crate {
    /// Loads the crate whose root file is `root`, with every module it declares.
    pub fn load(name: &str, root: &Path, read: Read) -> Result<Crate, String> {
        let text = read(root)?;
        let file = syn::parse_file(&text).map_err(|e| format!("{}: {e}", root.display()))?;
        let dir = root.parent().unwrap_or(Path::new("")).to_path_buf();
        let mut krate = Crate {
            name: name.to_string(),
            modules: Vec::new(),
        };
        krate.add(Vec::new(), root.to_path_buf(), &dir, file.items, None, read)?;
        Ok(krate)
    }

    /// Adds the module at `path` in `file` with `items`, whose child modules' files are in
    /// `dir`, and its children; returns its index.
    fn add(
        &mut self,
        path: Vec<String>,
        file: PathBuf,
        dir: &Path,
        items: Vec<Item>,
        parent: Option<usize>,
        read: Read,
    ) -> Result<usize, String> {
        let index = self.modules.len();
        self.modules.push(Module {
            path: path.clone(),
            file: file.clone(),
            parent,
            children: BTreeMap::new(),
            items: Vec::new(),
            defined: BTreeSet::new(),
            imports: BTreeMap::new(),
            globs: Vec::new(),
        });
        let mut items: Vec<Item> = items.into_iter().filter(|i| !is_test(attributes(i))).collect();
        for item in &mut items {
            match item {
                Item::Mod(m) => {
                    if m.attrs.iter().any(|a| a.path().is_ident("path")) {
                        return Err(format!(
                            "{}: module {}: #[path] is not supported",
                            file.display(),
                            m.ident
                        ));
                    }
                    let name = m.ident.to_string();
                    let mut child_path = path.clone();
                    child_path.push(name.clone());
                    let child_dir = dir.join(&name);
                    let child = match m.content.take() {
                        Some((_, inline)) => {
                            self.add(child_path, file.clone(), &child_dir, inline, Some(index), read)?
                        }
                        None => {
                            let (child_file, text) = module_file(dir, &name, read)?;
                            let parsed =
                                syn::parse_file(&text).map_err(|e| format!("{}: {e}", child_file.display()))?;
                            self.add(child_path, child_file, &child_dir, parsed.items, Some(index), read)?
                        }
                    };
                    self.modules[index].children.insert(name, child);
                }
                Item::Use(u) if u.leading_colon.is_none() => {
                    let mut found = Vec::new();
                    flatten_use(&u.tree, &mut Vec::new(), &mut found);
                    let module = &mut self.modules[index];
                    for import in found {
                        match import {
                            Import::Name(name, target) => {
                                module.imports.insert(name, target);
                            }
                            Import::Glob(target) => module.globs.push(target),
                        }
                    }
                }
                other => {
                    if let Some(name) = defined_name(other) {
                        self.modules[index].defined.insert(name);
                    }
                }
            }
        }
        self.modules[index].items = items;
        Ok(index)
    }

    /// The module's path for reports: `a::b`, or `crate` for the root.
    pub fn display(&self, module: usize) -> String {
        let path = &self.modules[module].path;
        if path.is_empty() {
            "crate".to_string()
        } else {
            path.join("::")
        }
    }

    /// The module and its ancestors, the root first.
    pub fn ancestry(&self, module: usize) -> Vec<usize> {
        let mut chain = vec![module];
        while let Some(parent) = self.modules[*chain.last().unwrap_or(&0)].parent {
            chain.push(parent);
        }
        chain.reverse();
        chain
    }
}
