//! Graphs that extend graphs: a graph file with `extends: "graphs/ppm.ron"` starts from the
//! base graph's declaration (itself resolved the same way) and overrides it: maps merge by key,
//! `passes` and `layouts` are edits of the base's, every other field given replaces the base's.
//! Errors point into the file that declared the offending name: an edit's into the extending
//! file, a base's own into the base.

use crate::error::{Location, Result};
use crate::ir::{ExtendingFile, GraphFile, LayoutEdit, LayoutWritten, PassEdit, PassEntry};
use crate::load::{GraphSource, Sources, parse_ron};
use crate::vfs::Vfs;
use std::collections::BTreeMap;

/// Reads graph `file` (text `text`) and, when it extends another, its bases, merged into one
/// declaration.
pub fn resolve(vfs: &Vfs, file: &str, text: &str) -> Result<GraphSource> {
    let mut sources = Sources::default();
    let (g, entry_files) = resolve_in(vfs, file, text, &mut sources, &mut Vec::new())?;
    Ok(GraphSource {
        file: g,
        entry_files,
        sources,
    })
}

/// A graph file as written: a whole graph, or one extending another.
enum Written {
    Whole(Box<GraphFile>),
    Extending(Box<ExtendingFile>),
}

/// Parses `text` as a whole graph, or as one that extends another where it says `extends`.
fn parse_written(file: &str, text: &str) -> Result<Written> {
    match parse_ron::<GraphFile>(file, text) {
        Ok(g) => Ok(Written::Whole(Box::new(g))),
        Err(whole) => match parse_ron::<ExtendingFile>(file, text) {
            Ok(e) => Ok(Written::Extending(Box::new(e))),
            Err(extending) if whole.to_string().contains("`extends`") => Err(extending),
            Err(_) => Err(whole),
        },
    }
}

/// The declaration of `file` with its bases merged in, and the file of each `passes` entry;
/// `chain` holds the files that extend it, to refuse a cycle.
fn resolve_in(
    vfs: &Vfs,
    file: &str,
    text: &str,
    sources: &mut Sources,
    chain: &mut Vec<String>,
) -> Result<(GraphFile, Vec<String>)> {
    sources.add(file, text);
    let ext = match parse_written(file, text)? {
        Written::Whole(mut g) => {
            let files = vec![file.to_string(); g.passes.len()];
            likes(&mut g.layouts, file, sources)?;
            return Ok((*g, files));
        }
        Written::Extending(ext) => ext,
    };
    chain.push(file.to_string());
    if chain.contains(&ext.extends) {
        let cycle: Vec<&str> = chain
            .iter()
            .skip_while(|f| **f != ext.extends)
            .map(|f| f.as_str())
            .chain([ext.extends.as_str()])
            .collect();
        return Err(sources.at_name(
            file,
            &ext.extends,
            format!("extends closes a cycle: {}", cycle.join(" → ")),
        ));
    }
    let base_text = vfs
        .read(&ext.extends)
        .map_err(|e| sources.at_name(file, &ext.extends, format!("cannot read the base graph: {e}")))?;
    let (base, files) = resolve_in(vfs, &ext.extends, &base_text, sources, chain)?;
    sources.add_base(file, &ext.extends);
    apply(*ext, base, files, file, sources)
}

/// `base` (with the file of each of its entries) as `ext` (file `file`) overrides it.
fn apply(
    ext: ExtendingFile,
    mut base: GraphFile,
    files: Vec<String>,
    file: &str,
    sources: &Sources,
) -> Result<(GraphFile, Vec<String>)> {
    let mut entries: Vec<(PassEntry, String)> = std::mem::take(&mut base.passes).into_iter().zip(files).collect();
    for edit in ext.passes {
        edit_passes(&mut entries, edit, file, &ext.extends, sources)?;
    }
    let (passes, files): (Vec<PassEntry>, Vec<String>) = entries.into_iter().unzip();
    let layouts = edit_layouts(&base, ext.layouts, file, &ext.extends, sources)?;
    let g = GraphFile {
        name: ext.name.unwrap_or(base.name),
        description: ext.description.unwrap_or(base.description),
        include: ext.include.unwrap_or(base.include),
        library: ext.library.unwrap_or(base.library),
        catalogs: ext.catalogs.unwrap_or(base.catalogs),
        passes,
        resources: merged(base.resources, ext.resources),
        streams: merged(base.streams, ext.streams),
        counters: ext.counters.unwrap_or(base.counters),
        constants: merged(base.constants, ext.constants),
        parameters: merged(base.parameters, ext.parameters),
        derived: merged(base.derived, ext.derived),
        checks: merged(base.checks, ext.checks),
        outputs: ext.outputs.unwrap_or(base.outputs),
        measured: merged(base.measured, ext.measured),
        loop_bounds: ext.loop_bounds.unwrap_or(base.loop_bounds),
        layouts,
        default_layout: ext.default_layout.unwrap_or(base.default_layout),
        coverage: ext.coverage.unwrap_or(base.coverage),
        item_fields: appended(base.item_fields, ext.item_fields),
        hooks: merged(base.hooks, ext.hooks),
    };
    Ok((g, files))
}

/// `base` with `over`'s entries added, replacing those of the same key.
fn merged<T>(mut base: BTreeMap<String, T>, over: BTreeMap<String, T>) -> BTreeMap<String, T> {
    base.extend(over);
    base
}

/// `base`'s lists with `over`'s appended, key by key.
fn appended<T>(mut base: BTreeMap<String, Vec<T>>, over: BTreeMap<String, Vec<T>>) -> BTreeMap<String, Vec<T>> {
    for (key, more) in over {
        base.entry(key).or_default().extend(more);
    }
    base
}

/// Applies one edit of the extending `file` to the entries of its base `base_file`.
fn edit_passes(
    entries: &mut Vec<(PassEntry, String)>,
    edit: PassEdit,
    file: &str,
    base_file: &str,
    sources: &Sources,
) -> Result<()> {
    let (name, new, remove, offset) = match edit {
        PassEdit::Replace(name, new) => (name, new, true, 0),
        PassEdit::Before(name, new) => (name, new, false, 0),
        PassEdit::After(name, new) => (name, new, false, 1),
        PassEdit::Remove(name) => (name, Vec::new(), true, 0),
    };
    let Some(at) = entries.iter().position(|(e, _)| e.name() == name) else {
        let known: Vec<&str> = entries.iter().map(|(e, _)| e.name()).collect();
        return Err(sources.at_name(
            file,
            &name,
            format!(
                "passes: no entry '{name}' to edit in the graph it extends ({base_file}; entries: {})",
                known.join(", ")
            ),
        ));
    };
    let new = new.into_iter().map(|e| (e, file.to_string()));
    let range = if remove { at..at + 1 } else { at + offset..at + offset };
    entries.splice(range, new);
    Ok(())
}

/// The layouts of `file` (`layouts`, those of a base already resolved) that are `like` another
/// of `layouts`, given that one's fields where they give none; a layout may be like one that is
/// like a third.
fn likes(layouts: &mut BTreeMap<String, LayoutWritten>, file: &str, sources: &Sources) -> Result<()> {
    loop {
        let pending: Vec<(String, String)> = layouts
            .iter()
            .filter_map(|(name, l)| l.like.clone().map(|from| (name.clone(), from)))
            .collect();
        let Some((name, from)) = pending
            .iter()
            .find(|(_, from)| layouts.get(from).is_some_and(|l| l.like.is_none()))
        else {
            return match pending.first() {
                None => Ok(()),
                Some((name, from)) => Err(unresolved_like(layouts, name, from, file, sources)),
            };
        };
        let base = layouts[from].clone();
        let layout = layouts.get_mut(name).expect("a pending layout");
        *layout = std::mem::take(layout).over(&base);
    }
}

/// The error of layout `name`, like `from`: no layout, or the start of a cycle of likes.
fn unresolved_like(
    layouts: &BTreeMap<String, LayoutWritten>,
    name: &str,
    from: &str,
    file: &str,
    sources: &Sources,
) -> crate::error::Error {
    let message = if layouts.contains_key(from) {
        format!("layout '{name}': is like '{from}', and the likes from there go round a cycle")
    } else {
        let known: Vec<&str> = layouts.keys().map(|s| s.as_str()).collect();
        format!(
            "layout '{name}': is like '{from}', which is no layout of this graph (layouts: {})",
            known.join(", ")
        )
    };
    crate::error::Error::Invalid {
        at: Location::of_name_under_key(file, sources.text(file), name, from),
        message,
    }
}

/// The base's layouts as the extending `file`'s `edits` leave them, `like`s resolved before the
/// removals.
fn edit_layouts(
    base: &GraphFile,
    edits: BTreeMap<String, LayoutEdit>,
    file: &str,
    base_file: &str,
    sources: &Sources,
) -> Result<BTreeMap<String, LayoutWritten>> {
    let mut layouts = base.layouts.clone();
    let missing = |name: &str| {
        let known: Vec<&str> = base.layouts.keys().map(|s| s.as_str()).collect();
        sources.at_name(
            file,
            name,
            format!(
                "layouts: no layout '{name}' in the graph it extends ({base_file}; layouts: {})",
                known.join(", ")
            ),
        )
    };
    let mut removed = Vec::new();
    for (name, edit) in edits {
        match edit {
            LayoutEdit::Layout(decl) => {
                layouts.insert(name, decl);
            }
            LayoutEdit::From(from) => {
                let decl = base.layouts.get(&from).ok_or_else(|| missing(&from))?;
                layouts.insert(name, decl.clone());
            }
            LayoutEdit::Remove => removed.push(name),
        }
    }
    // A layout may be like one of the base's that this file removes.
    likes(&mut layouts, file, sources)?;
    for name in removed {
        layouts.remove(&name).ok_or_else(|| missing(&name))?;
    }
    Ok(layouts)
}
