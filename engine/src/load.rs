//! Reading a graph file with its catalogs and included declaration files: what each used pass
//! brings along, merged with the graph's own declarations, and every name checked. Errors
//! name the file, line and column of the offending name.

use crate::error::{Error, Location, Result};
use crate::expr::Expr;
use crate::ids::{PassId, ResourceId, StreamId, indexes};
use crate::ir::{CatalogFile, ConstValue, GraphFile, PassDecl, PassEntry, PerCall, ResourceDecl, Role, Scope};
use crate::operator::{OpKind, Operator, is_u32_word, summed_type};
use crate::vfs::Vfs;
use std::collections::BTreeMap;

/// Parses RON text of `file` into `T`, with the parser's position on error.
pub fn parse_ron<T: serde::de::DeserializeOwned>(file: &str, text: &str) -> Result<T> {
    ron::Options::default()
        .with_default_extension(
            ron::extensions::Extensions::IMPLICIT_SOME | ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES,
        )
        .from_str(text)
        .map_err(|e| Error::Parse {
            at: Location {
                file: file.to_string(),
                line: e.span.start.line,
                column: e.span.start.col,
            },
            message: e.code.to_string(),
        })
}

/// Whether `name` is a WGSL identifier.
pub fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The texts of the files a graph was read from, to place errors.
#[derive(Debug, Clone, Default)]
pub struct Sources {
    texts: BTreeMap<String, String>,
    /// The graph file each extending graph file extends.
    bases: BTreeMap<String, String>,
}

impl Sources {
    /// Remembers `text` as the contents of `file`.
    pub fn add(&mut self, file: &str, text: &str) {
        self.texts.insert(file.to_string(), text.to_string());
    }

    /// Remembers that graph file `file` extends `base`.
    pub fn add_base(&mut self, file: &str, base: &str) {
        self.bases.insert(file.to_string(), base.to_string());
    }

    /// The text of `file` (empty when unknown).
    pub fn text(&self, file: &str) -> &str {
        self.texts.get(file).map_or("", |t| t.as_str())
    }

    /// The file that declared `name` among `file` and the files it extends: the first of them,
    /// extending file first, whose text quotes `name` (`file` when none does).
    pub fn declaring<'a>(&'a self, file: &'a str, name: &str) -> &'a str {
        let quoted = format!("\"{name}\"");
        let mut at = file;
        while !self.text(at).contains(&quoted) {
            match self.bases.get(at) {
                Some(base) => at = base,
                None => return file,
            }
        }
        at
    }

    /// An error at the first quoted `name` in `file` (or in the file it extends that declared it).
    pub fn at_name(&self, file: &str, name: &str, message: impl Into<String>) -> Error {
        let file = self.declaring(file, name);
        Error::invalid_at_name(file, self.text(file), name, message)
    }

    /// An error at the declaration `"name":` in `file` (or in the file it extends that declared
    /// it).
    pub fn at_key(&self, file: &str, name: &str, message: impl Into<String>) -> Error {
        let file = self.declaring(file, name);
        Error::invalid_at_key(file, self.text(file), name, message)
    }
}

/// A pass of a loaded graph, with the file it was declared in and the ids of the resources
/// and streams its declaration names (interned where the graph is built, [`crate::Graph`]).
#[derive(Debug, Clone)]
pub struct Pass {
    /// The declaration.
    pub decl: PassDecl,
    /// The file (virtual path) that declares it: a catalog or the graph.
    pub origin: String,
    /// The resources it reads (`decl.reads`, interned).
    pub reads: Vec<ResourceId>,
    /// The resources it writes (`decl.writes`, interned).
    pub writes: Vec<ResourceId>,
    /// The streams it emits into (`decl.emits`, interned).
    pub emits: Vec<StreamId>,
}

impl Pass {
    /// A pass declared by `decl` in `origin`, not interned yet.
    fn new(decl: PassDecl, origin: &str) -> Pass {
        Pass {
            decl,
            origin: origin.to_string(),
            reads: Vec::new(),
            writes: Vec::new(),
            emits: Vec::new(),
        }
    }

    /// The WGSL function implementing the pass.
    pub fn function(&self) -> &str {
        self.decl.function.as_deref().unwrap_or(&self.decl.name)
    }
}

indexes!(PassId => Pass);

/// An entry of the graph's `passes` list, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entry {
    /// Index into [`Declared::passes`].
    Pass(usize),
    /// Index into [`Declared::ops`].
    Op(usize),
}

/// Everything a graph declares, its catalogs' contributions merged in.
#[derive(Debug, Clone)]
pub struct Declared {
    /// The graph file's parsed form (layouts, outputs, ...).
    pub file: GraphFile,
    /// WGSL library files, in order, without repeats.
    pub library: Vec<String>,
    /// Passes, in the graph's order.
    pub passes: Vec<Pass>,
    /// Operators, in the graph's order.
    pub ops: Vec<Operator>,
    /// The graph's `passes` entries in order.
    pub entries: Vec<Entry>,
    /// Resources by name.
    pub resources: BTreeMap<String, ResourceDecl>,
    /// Catalog resources that no pass lists but a pass that derives its reads or writes may
    /// use (its catalog declares them): they join the live graph's resources where the
    /// derivation finds a pass that uses them.
    pub candidates: BTreeMap<String, ResourceDecl>,
    /// Counters, in order.
    pub counters: Vec<String>,
    /// Constants with their defaults.
    pub constants: BTreeMap<String, ConstValue>,
    /// Derived `u32` constants: name → count expression over the other constants.
    pub derived: BTreeMap<String, String>,
    /// Conditions over the constants that must hold, from the graph and the files it uses.
    pub checks: Vec<ConstCheck>,
    /// The file declaring each resource, counter and constant.
    pub origins: BTreeMap<String, String>,
    /// The texts of the graph, catalog and include files.
    pub sources: Sources,
}

impl Declared {
    /// The WGSL files of the graph: its library and its passes' sources, in order, each once.
    pub fn wgsl_files(&self) -> Vec<String> {
        let mut files = self.library.clone();
        for p in &self.passes {
            if !files.contains(&p.decl.source) {
                files.push(p.decl.source.clone());
            }
        }
        files
    }
}

/// A condition over the constants that must hold (`checks` of a graph or catalog).
#[derive(Debug, Clone, PartialEq)]
pub struct ConstCheck {
    /// The condition, an expression over the constants (0 fails).
    pub condition: String,
    /// What the constants may be, for the error.
    pub message: String,
    /// The file that declares it.
    pub file: String,
}

/// Adds `file`'s checks to `out`, each condition once.
fn add_checks(out: &mut Vec<ConstCheck>, checks: &BTreeMap<String, String>, file: &str) {
    for (condition, message) in checks {
        if !out.iter().any(|c| &c.condition == condition) {
            out.push(ConstCheck {
                condition: condition.clone(),
                message: message.clone(),
                file: file.to_string(),
            });
        }
    }
}

/// How strongly a declaration holds: the graph's own over an included file's over a
/// catalog's over a pass's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Rank {
    Pass,
    Catalog,
    Include,
    Graph,
}

/// Declarations collected from several files, each with where it came from.
struct Merged<T> {
    items: BTreeMap<String, (T, Rank, String)>,
}

impl<T: PartialEq + Clone + std::fmt::Debug> Merged<T> {
    fn new() -> Self {
        Merged { items: BTreeMap::new() }
    }

    /// Adds `name` from `file`: a stronger rank replaces, the same rank must agree.
    fn add(&mut self, sources: &Sources, what: &str, name: &str, value: &T, rank: Rank, file: &str) -> Result<()> {
        match self.items.get(name) {
            Some((_, r, _)) if *r > rank => Ok(()),
            Some((old, r, old_file)) if *r == rank && old != value && old_file != file => Err(sources.at_key(
                file,
                name,
                format!("{what} '{name}' is declared as {value:?} here and as {old:?} in {old_file}; declare it once in the graph"),
            )),
            _ => {
                self.items.insert(name.to_string(), (value.clone(), rank, file.to_string()));
                Ok(())
            }
        }
    }

    fn into_parts(self, origins: &mut BTreeMap<String, String>) -> BTreeMap<String, T> {
        self.items
            .into_iter()
            .map(|(name, (value, _, file))| {
                origins.insert(name.clone(), file);
                (name, value)
            })
            .collect()
    }
}

fn push_unique(list: &mut Vec<String>, items: &[String]) {
    for i in items {
        if !list.contains(i) {
            list.push(i.clone());
        }
    }
}

/// A graph file's declaration with what it was read from: the texts of the graph file and of
/// any files it extends, and the file that declared each entry of `passes` (the graph file, or
/// a graph it extends).
#[derive(Debug, Clone)]
pub struct GraphSource {
    /// The declaration, any bases' merged in.
    pub file: GraphFile,
    /// The file that declared each entry of `file.passes`.
    pub entry_files: Vec<String>,
    /// The texts read so far.
    pub sources: Sources,
}

/// Merges the graph `file` (its declaration `source`) with its catalogs and includes.
pub fn declare(vfs: &Vfs, file: &str, source: GraphSource) -> Result<Declared> {
    let GraphSource {
        file: g,
        entry_files,
        mut sources,
    } = source;
    let catalogs = read_catalogs(vfs, file, &g.catalogs, &mut sources)?;
    let includes = read_catalogs(vfs, file, &g.include, &mut sources)?;
    let offered = Offered {
        includes: &includes,
        catalogs: &catalogs,
    };
    let (passes, ops, entries) = graph_entries(&g, &entry_files, &offered, &sources)?;
    // What each part brings: library, counters, constants, resources.
    let mut parts = Parts::of_graph(&g, file, &sources)?;
    for (path, inc) in &includes {
        parts.add_include(path, inc, &sources)?;
    }
    for p in &passes {
        let cat = catalogs.iter().chain(&includes).find(|(path, _)| *path == p.origin);
        parts.add_pass(p, cat.map(|(_, c)| c), &sources)?;
    }
    // A catalog's resources that operators name join as well (the first catalog declaring one).
    for op in &ops {
        for name in op.reads().into_iter().chain(op.writes()) {
            if let Some((path, r)) = catalogs
                .iter()
                .chain(&includes)
                .find_map(|(path, cat)| cat.resources.get(name).map(|r| (path, r)))
            {
                parts
                    .resources
                    .add(&sources, "resource", name, r, Rank::Catalog, path)?;
            }
        }
    }
    let mut origins = BTreeMap::new();
    for c in &parts.counters {
        origins.insert(c.clone(), file.to_string());
    }
    let resources = parts.resources.into_parts(&mut origins);
    let mut candidates = BTreeMap::new();
    for (name, (r, origin)) in parts.candidates {
        if !resources.contains_key(&name) {
            origins.insert(name.clone(), origin);
            candidates.insert(name, r);
        }
    }
    let declared = Declared {
        library: parts.library,
        passes,
        ops,
        entries,
        constants: parts.constants.into_parts(&mut origins),
        derived: parts.derived.into_parts(&mut origins),
        resources,
        candidates,
        counters: parts.counters,
        checks: parts.checks,
        origins,
        sources,
        file: g,
    };
    declared.check(file)?;
    Ok(declared)
}

/// The catalog (or include) files `paths` that graph `file` names, read and parsed, their texts
/// added to `sources`.
fn read_catalogs(vfs: &Vfs, file: &str, paths: &[String], sources: &mut Sources) -> Result<Vec<(String, CatalogFile)>> {
    let mut out = Vec::new();
    for path in paths {
        let t = vfs
            .read(path)
            .map_err(|e| sources.at_name(file, path, format!("cannot read pass catalog: {e}")))?;
        sources.add(path, &t);
        out.push((path.clone(), parse_ron(path, &t)?));
    }
    Ok(out)
}

/// The graph's `passes` entries: its passes (its own, and those it `Use`s from its includes
/// and catalogs, where the later file wins) and operators, in order; an error for an unknown
/// pass or a name used twice.
fn graph_entries(
    g: &GraphFile,
    entry_files: &[String],
    from: &Offered,
    sources: &Sources,
) -> Result<(Vec<Pass>, Vec<Operator>, Vec<Entry>)> {
    let mut offered: BTreeMap<String, (PassDecl, String)> = BTreeMap::new();
    for (path, cat) in from.includes.iter().chain(from.catalogs) {
        for d in &cat.passes {
            offered.insert(d.name.clone(), (d.clone(), path.clone()));
        }
    }
    let mut passes: Vec<Pass> = Vec::new();
    let mut ops: Vec<Operator> = Vec::new();
    let mut entries = Vec::new();
    for (entry, file) in g.passes.iter().zip(entry_files) {
        let file = file.as_str();
        if let Some(op) = Operator::from_entry(entry, file) {
            let op = op.map_err(|(what, why)| sources.at_name(file, &what, why))?;
            entries.push(Entry::Op(ops.len()));
            ops.push(op);
            continue;
        }
        let catalog_pass = |name: &String| -> Result<Pass> {
            let (decl, origin) = offered.get(name).cloned().ok_or_else(|| {
                let known: Vec<&str> = offered.keys().map(|s| s.as_str()).collect();
                sources.at_name(
                    file,
                    name,
                    format!(
                        "unknown pass '{name}' (the catalogs {:?} offer: {})",
                        g.catalogs,
                        known.join(", ")
                    ),
                )
            })?;
            Ok(Pass::new(decl, &origin))
        };
        let mut pass = match entry {
            PassEntry::Use(name) => catalog_pass(name)?,
            PassEntry::UseWith(with) => {
                let mut pass = catalog_pass(&with.name)?;
                for (listed, more, field) in [
                    (&mut pass.decl.listed_reads, &with.reads, "reads"),
                    (&mut pass.decl.listed_writes, &with.writes, "writes"),
                ] {
                    match listed {
                        Some(list) => add_missing(list, more),
                        None if !more.is_empty() => {
                            return Err(sources.at_name(
                                file,
                                &more[0],
                                format!(
                                    "UseWith of '{}' lists `{field}` ({}), but its catalog derives them from the WGSL (which sees what the graph's functions it calls use); leave `{field}` out",
                                    with.name,
                                    more.join(", ")
                                ),
                            ));
                        }
                        None => {}
                    }
                }
                pass.decl.enabled = match (&pass.decl.enabled, &with.enabled) {
                    (Some(a), Some(b)) => Some(format!("({a}) && ({b})")),
                    (a, b) => a.clone().or_else(|| b.clone()),
                };
                pass
            }
            PassEntry::Pass(decl) => Pass::new(decl.clone(), file),
            _ => unreachable!("operators are taken above"),
        };
        pass.decl.reads = pass.decl.listed_reads.clone().unwrap_or_default();
        pass.decl.writes = pass.decl.listed_writes.clone().unwrap_or_default();
        entries.push(Entry::Pass(passes.len()));
        passes.push(pass);
    }
    let names: Vec<&str> = g.passes.iter().map(PassEntry::name).collect();
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            return Err(sources.at_name(&entry_files[i], n, format!("pass '{n}' appears twice")));
        }
    }
    Ok((passes, ops, entries))
}

/// The declaration files a graph's `Use` entries take passes from.
struct Offered<'a> {
    includes: &'a [(String, CatalogFile)],
    catalogs: &'a [(String, CatalogFile)],
}

/// Appends the names of `more` that `list` lacks, in order.
fn add_missing(list: &mut Vec<String>, more: &[String]) {
    for name in more {
        if !list.contains(name) {
            list.push(name.clone());
        }
    }
}

/// What the files of a graph bring, merged: WGSL library files and counters in order without
/// repeats, constants, derived constants and resources by rank ([`Merged`]), and checks.
struct Parts {
    library: Vec<String>,
    counters: Vec<String>,
    constants: Merged<ConstValue>,
    derived: Merged<String>,
    resources: Merged<ResourceDecl>,
    /// Catalog resources a pass that derives its reads or writes may use, with the catalog.
    candidates: BTreeMap<String, (ResourceDecl, String)>,
    checks: Vec<ConstCheck>,
}

impl Parts {
    /// What graph `g` (file `file`) declares itself.
    fn of_graph(g: &GraphFile, file: &str, sources: &Sources) -> Result<Parts> {
        let mut parts = Parts {
            library: g.library.clone(),
            counters: g.counters.clone(),
            constants: Merged::new(),
            derived: Merged::new(),
            resources: Merged::new(),
            candidates: BTreeMap::new(),
            checks: Vec::new(),
        };
        for (name, v) in &g.constants {
            parts.constants.add(sources, "constant", name, v, Rank::Graph, file)?;
        }
        for (name, e) in &g.derived {
            parts
                .derived
                .add(sources, "derived constant", name, e, Rank::Graph, file)?;
        }
        for (name, r) in &g.resources {
            parts.resources.add(sources, "resource", name, r, Rank::Graph, file)?;
        }
        add_checks(&mut parts.checks, &g.checks, file);
        Ok(parts)
    }

    /// What the included file `path` declares, all of it.
    fn add_include(&mut self, path: &str, inc: &CatalogFile, sources: &Sources) -> Result<()> {
        add_checks(&mut self.checks, &inc.checks, path);
        push_unique(&mut self.library, &inc.library);
        push_unique(&mut self.counters, &inc.counters);
        for (name, v) in &inc.constants {
            self.constants.add(sources, "constant", name, v, Rank::Include, path)?;
        }
        for (name, e) in &inc.derived {
            self.derived
                .add(sources, "derived constant", name, e, Rank::Include, path)?;
        }
        for (name, r) in &inc.resources {
            self.resources.add(sources, "resource", name, r, Rank::Include, path)?;
        }
        for (name, r) in &inc.candidates {
            self.candidates
                .entry(name.clone())
                .or_insert_with(|| (r.clone(), path.to_string()));
        }
        Ok(())
    }

    /// What pass `p` brings: its catalog's (or include's) library, counters, constants and
    /// checks, the resources of it that the pass reads or writes, and the pass's own. When the
    /// pass leaves `reads` or `writes` to be derived, the catalog's other resources become
    /// candidates, which join the graph where the derivation finds a pass using them.
    fn add_pass(&mut self, p: &Pass, catalog: Option<&CatalogFile>, sources: &Sources) -> Result<()> {
        let d = &p.decl;
        if let Some(cat) = catalog {
            push_unique(&mut self.library, &cat.library);
            push_unique(&mut self.counters, &cat.counters);
            for (name, v) in &cat.constants {
                self.constants
                    .add(sources, "constant", name, v, Rank::Catalog, &p.origin)?;
            }
            for (name, e) in &cat.derived {
                self.derived
                    .add(sources, "derived constant", name, e, Rank::Catalog, &p.origin)?;
            }
            add_checks(&mut self.checks, &cat.checks, &p.origin);
            for (name, r) in &cat.candidates {
                self.candidates
                    .entry(name.clone())
                    .or_insert_with(|| (r.clone(), p.origin.clone()));
            }
            for (name, r) in &cat.resources {
                if d.reads.contains(name) || d.writes.contains(name) {
                    self.resources
                        .add(sources, "resource", name, r, Rank::Catalog, &p.origin)?;
                } else if d.listed_reads.is_none() || d.listed_writes.is_none() {
                    self.candidates
                        .entry(name.clone())
                        .or_insert_with(|| (r.clone(), p.origin.clone()));
                }
            }
        }
        push_unique(&mut self.library, &d.library);
        push_unique(&mut self.counters, &d.counters);
        for (name, v) in &d.constants {
            self.constants
                .add(sources, "constant", name, v, Rank::Pass, &p.origin)?;
        }
        Ok(())
    }
}

impl Declared {
    /// An error at the declaration of `name` (a resource, counter or constant) in the file
    /// that declares it, or at its first mention in the graph file.
    pub fn error_at_decl(&self, graph_file: &str, name: &str, message: impl Into<String>) -> Error {
        let file = self.origins.get(name).map_or(graph_file, |f| f.as_str());
        self.sources.at_key(file, name, message)
    }

    /// Every check of names and references.
    fn check(&self, file: &str) -> Result<()> {
        self.check_names(file)?;
        self.check_passes()?;
        self.check_ops()?;
        self.check_resources(file)?;
        self.check_streams(file)?;
        self.check_loop_bounds(file)?;
        self.check_measured(file)?;
        self.check_parameters(file)?;
        self.check_layout_constants(file)?;
        self.check_coverage(file)?;
        let g = &self.file;
        if !g.layouts.contains_key(&g.default_layout) {
            return Err(self.sources.at_name(
                file,
                &g.default_layout,
                format!("default layout '{}' is not one of the layouts", g.default_layout),
            ));
        }
        Ok(())
    }

    /// Each `coverage` condition parses and names only constants.
    fn check_coverage(&self, file: &str) -> Result<()> {
        let coverage = &self.file.coverage;
        let conditions = coverage
            .misses
            .iter()
            .map(|m| &m.when)
            .chain(coverage.biased.iter().map(|b| &b.when));
        for when in conditions {
            let Some(when) = when else { continue };
            let unknown = Expr::parse(when).map(|e| {
                e.names()
                    .into_iter()
                    .find(|n| !self.constants.contains_key(n) && !self.derived.contains_key(n))
            });
            let why = match unknown {
                Err(e) => e,
                Ok(Some(name)) => format!("'{name}' is not a constant of the graph"),
                Ok(None) => continue,
            };
            return Err(self
                .sources
                .at_name(file, when, format!("coverage: when: '{when}': {why}")));
        }
        Ok(())
    }

    fn check_names(&self, file: &str) -> Result<()> {
        let g = &self.file;
        for name in self
            .resources
            .keys()
            .chain(g.streams.keys())
            .chain(self.counters.iter())
            .chain(self.constants.keys())
            .chain(self.derived.keys())
            .chain(g.parameters.keys())
        {
            if !is_identifier(name) || name.starts_with("lg_") {
                return Err(self.error_at_decl(
                    file,
                    name,
                    format!("'{name}' is not a valid name (a WGSL identifier not starting with 'lg_')"),
                ));
            }
        }
        for name in self.derived.keys() {
            if self.constants.contains_key(name) || g.parameters.contains_key(name) {
                return Err(self.error_at_decl(
                    file,
                    name,
                    format!("'{name}' is derived and also declared as a constant or parameter"),
                ));
            }
            if let Err(e) = Expr::parse(&self.derived[name]) {
                return Err(self.error_at_decl(file, name, format!("derived constant '{name}': {e}")));
            }
        }
        for c in &self.checks {
            if let Err(e) = Expr::parse(&c.condition) {
                return Err(self
                    .sources
                    .at_key(&c.file, &c.condition, format!("check '{}': {e}", c.condition)));
            }
        }
        for name in g.parameters.keys() {
            if self.constants.contains_key(name) {
                return Err(self
                    .sources
                    .at_key(file, name, format!("'{name}' is both a constant and a parameter")));
            }
        }
        Ok(())
    }

    fn check_passes(&self) -> Result<()> {
        let g = &self.file;
        for p in &self.passes {
            let d = &p.decl;
            let here = |name: &str, message: String| self.sources.at_name(&p.origin, name, message);
            if !is_identifier(p.function()) {
                return Err(here(
                    &d.name,
                    format!("pass name '{}' is not a WGSL identifier", d.name),
                ));
            }
            for r in d.reads.iter().chain(d.writes.iter()) {
                if !self.resources.contains_key(r) {
                    let known: Vec<&str> = self.resources.keys().map(|s| s.as_str()).collect();
                    return Err(here(
                        r,
                        format!(
                            "unknown resource '{r}' used by pass '{}' (graph '{}' declares: {})",
                            d.name,
                            g.name,
                            known.join(", ")
                        ),
                    ));
                }
            }
            for s in &d.emits {
                if !g.streams.contains_key(s) {
                    return Err(here(s, format!("pass '{}' emits into unknown stream '{s}'", d.name)));
                }
            }
            if let Role::Start { over, counted } = &d.role {
                Expr::parse(over).map_err(|e| here(over, e))?;
                if let Some(c) = counted {
                    self.check_counter(&p.origin, &d.name, c)?;
                }
            }
            if let Some(e) = &d.enabled {
                Expr::parse(e).map_err(|why| here(e, format!("pass '{}': enabled: {why}", d.name)))?;
            }
        }
        Ok(())
    }

    /// A GPU counter must be a `u32` resource.
    fn check_counter(&self, file: &str, user: &str, counter: &str) -> Result<()> {
        match self.resources.get(counter) {
            Some(r) if is_u32_word(&r.ty) => Ok(()),
            Some(r) => Err(self.sources.at_name(
                file,
                counter,
                format!(
                    "'{user}' is counted by '{counter}', whose elements are '{}'; a counter is a u32 or atomic<u32>",
                    r.ty
                ),
            )),
            None => Err(self.sources.at_name(
                file,
                counter,
                format!("'{user}' is counted by unknown resource '{counter}'"),
            )),
        }
    }

    fn check_ops(&self) -> Result<()> {
        for op in &self.ops {
            let here = |name: &str, message: String| self.sources.at_name(&op.origin, name, message);
            if let Some(e) = &op.enabled {
                Expr::parse(e).map_err(|why| here(e, format!("operator '{}': enabled: {why}", op.name)))?;
            }
            if let Some(c) = op.domain.as_ref().and_then(|d| d.counted.as_deref()) {
                self.check_counter(&op.origin, &op.name, c)?;
            }
            for (buffer, want) in op.buffers() {
                let r = self.resources.get(buffer).ok_or_else(|| {
                    here(
                        buffer,
                        format!("operator '{}' uses unknown resource '{buffer}'", op.name),
                    )
                })?;
                if !want.accepts(&r.ty) {
                    return Err(here(
                        buffer,
                        format!(
                            "operator '{}' ({}) needs {} elements in '{buffer}', which holds '{}'",
                            op.name,
                            op.describe(),
                            want.describe(),
                            r.ty
                        ),
                    ));
                }
                if r.scope == Scope::External {
                    return Err(here(
                        buffer,
                        format!(
                            "operator '{}' uses '{buffer}', which the host supplies (External); operators work on resources the engine allocates",
                            op.name
                        ),
                    ));
                }
            }
            self.check_op_pairs(op)?;
        }
        Ok(())
    }

    /// The checks of an operator between two of its resources: a sort's keys and values are
    /// different resources, a scan sums into elements of its input's type, a scatter or
    /// gather moves elements into a resource of their type.
    fn check_op_pairs(&self, op: &Operator) -> Result<()> {
        let here = |name: &str, message: String| self.sources.at_name(&op.origin, name, message);
        if let OpKind::Sort {
            keys,
            values: Some(values),
            ..
        } = &op.kind
            && keys == values
        {
            return Err(here(
                values,
                format!(
                    "operator '{}' sorts '{keys}' with itself as its values; keys and values must be different resources",
                    op.name
                ),
            ));
        }
        if let OpKind::Scan { input, output } = &op.kind {
            let (a, b) = (&self.resources[input].ty, &self.resources[output].ty);
            if summed_type(a) != summed_type(b) {
                return Err(here(
                    output,
                    format!(
                        "operator '{}' sums '{input}' ({a}) into '{output}' ({b}); both must hold u32 (or atomic<u32>) or both f32",
                        op.name
                    ),
                ));
            }
        }
        let moved = match &op.kind {
            OpKind::Scatter {
                input: Some(input),
                output,
                ..
            }
            | OpKind::Gather { input, output, .. } => Some((input, output)),
            _ => None,
        };
        if let Some((input, output)) = moved {
            let (a, b) = (&self.resources[input].ty, &self.resources[output].ty);
            if a != b {
                return Err(here(
                    output,
                    format!(
                        "operator '{}' moves '{input}' ({a}) into '{output}' ({b}); both must hold the same type",
                        op.name
                    ),
                ));
            }
        }
        Ok(())
    }

    fn check_resources(&self, file: &str) -> Result<()> {
        for (name, r) in self.resources.iter().chain(&self.candidates) {
            let err = |message: String| self.error_at_decl(file, name, message);
            if r.scope == Scope::External && r.count.is_some() {
                return Err(err(format!(
                    "external resource '{name}' has a count; its data sizes it, so write its WGSL type (e.g. array<{}>)",
                    r.ty
                )));
            }
            if r.clear && r.scope != Scope::Transient {
                return Err(err(format!(
                    "resource '{name}' has clear: true but is not Transient (persistent resources are zeroed once, when created)"
                )));
            }
            if let Some(count) = &r.count {
                let e = Expr::parse(count).map_err(|e| {
                    let origin = self.origins.get(name).map_or(file, |f| f.as_str());
                    self.sources.at_name(origin, count, format!("resource '{name}': {e}"))
                })?;
                if let Some(p) = e.names().iter().find(|n| self.file.parameters.contains_key(*n)) {
                    return Err(err(format!(
                        "resource '{name}' is sized by parameter '{p}', which changes every frame; sizes are fixed when the program is compiled, so use a constant"
                    )));
                }
            }
        }
        for o in &self.file.outputs {
            match self.resources.get(o) {
                None => return Err(self.sources.at_name(file, o, format!("output '{o}' is not a resource"))),
                Some(r) if r.scope == Scope::Transient => {
                    return Err(self.sources.at_name(
                        file,
                        o,
                        format!(
                            "output '{o}' is Transient, so its memory is reused within a frame; make it Persistent"
                        ),
                    ));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }

    fn check_streams(&self, file: &str) -> Result<()> {
        for (name, s) in &self.file.streams {
            let err = |at: &str, message: String| self.sources.at_name(file, at, message);
            let err_key = |message: String| self.sources.at_key(file, name, message);
            let consumer = self
                .passes
                .iter()
                .find(|p| p.decl.name == s.to)
                .ok_or_else(|| err(&s.to, format!("stream '{name}' feeds unknown pass '{}'", s.to)))?;
            if consumer.decl.item != s.item {
                return Err(err_key(format!(
                    "stream type mismatch: stream '{name}' carries '{}' but its consumer '{}' runs over '{}'",
                    s.item, s.to, consumer.decl.item
                )));
            }
            if matches!(consumer.decl.role, Role::Start { .. }) {
                return Err(err(
                    &s.to,
                    format!(
                        "stream '{name}' feeds '{}', a Start pass; streams feed Step or Loop passes",
                        s.to
                    ),
                ));
            }
            match &s.per_call {
                PerCall::Number(0) => return Err(err_key(format!("stream '{name}' has per_call 0"))),
                PerCall::Expr(e) => {
                    if let Err(why) = Expr::parse(e) {
                        return Err(err_key(format!("stream '{name}': per_call: {why}")));
                    }
                }
                PerCall::Number(_) => {}
            }
        }
        Ok(())
    }

    /// Each loop bound names the item of a pass and parses as a count expression.
    fn check_loop_bounds(&self, file: &str) -> Result<()> {
        for (item, e) in &self.file.loop_bounds {
            let err = |message: String| self.sources.at_key(file, item, message);
            if !self.passes.iter().any(|p| &p.decl.item == item) {
                return Err(err(format!("loop_bounds: no pass runs over items of type '{item}'")));
            }
            if let Err(why) = Expr::parse(e) {
                return Err(err(format!("loop_bounds of '{item}': {why}")));
            }
        }
        Ok(())
    }

    fn check_measured(&self, file: &str) -> Result<()> {
        for (name, m) in &self.file.measured {
            let err = |message: String| self.sources.at_key(file, name, message);
            if !matches!(self.constants.get(name), Some(ConstValue::F32(_))) {
                return Err(err(format!(
                    "measured constant '{name}' must be declared as an F32 constant"
                )));
            }
            for c in [&m.ratio.0, &m.ratio.1] {
                if !self.counters.contains(c) {
                    return Err(err(format!("measured constant '{name}': no counter '{c}'")));
                }
            }
            if let Some(value) = &m.value {
                let e = Expr::parse(value).map_err(|why| err(format!("measured constant '{name}': value: {why}")))?;
                let known = |n: &String| n == crate::ir::MEASURED_RATIO || self.constants.contains_key(n);
                if let Some(n) = e.names().into_iter().find(|n| !known(n)) {
                    return Err(err(format!(
                        "measured constant '{name}': value uses '{n}', which is neither {} nor a constant",
                        crate::ir::MEASURED_RATIO
                    )));
                }
            }
            for (c, v) in &m.set {
                match self.constants.get(c) {
                    Some(d) if d.wgsl_type() == v.wgsl_type() => {}
                    _ => {
                        return Err(err(format!(
                            "measured constant '{name}': sets '{c}', which is no constant of that type"
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// A layout's constants are constants of the graph, of their declared type.
    fn check_layout_constants(&self, file: &str) -> Result<()> {
        for (layout, decl) in &self.file.layouts {
            for (c, v) in decl.constants.iter().flatten() {
                match self.constants.get(c) {
                    Some(d) if d.wgsl_type() == v.wgsl_type() => {}
                    Some(d) => {
                        return Err(self.sources.at_key(
                            file,
                            c,
                            format!(
                                "layout '{layout}': constant '{c}' is {} in the graph but set as {}",
                                d.wgsl_type(),
                                v.wgsl_type()
                            ),
                        ));
                    }
                    None => {
                        return Err(self.sources.at_key(
                            file,
                            c,
                            format!("layout '{layout}': sets '{c}', which is no constant of the graph"),
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    fn check_parameters(&self, file: &str) -> Result<()> {
        let most = crate::limits::MAX_PARAMETERS;
        if let Some(first) = self.file.parameters.keys().next()
            && self.file.parameters.len() > most
        {
            return Err(self.sources.at_key(
                file,
                first,
                format!(
                    "{} parameters; a frame record holds at most {most}",
                    self.file.parameters.len()
                ),
            ));
        }
        Ok(())
    }
}
