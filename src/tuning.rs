//! Per-adapter tuning profiles (`data/tuning/*.ron`, docs/tuning.md): the device knobs of a
//! graph's named layouts (wgpu's loop guards, pool sizes, code variants such as
//! `CWBVH_CHILD_SCAN`), each with a link to the measurement that chose it, and the layout a
//! built-in scene renders fastest in without `--layout`. Graphs keep the algorithm and their
//! legal layouts; a profile only changes speed, never the image (every layout of one estimator
//! renders the same image to float rounding, knobs or none).
//!
//! A render takes the first built-in profile whose `adapters` name its adapter, else the
//! `default` profile; `--tuning NAME|FILE|none` chooses another, a profile of one's own, or
//! none at all.

use anyhow::{Context, Result, anyhow, bail};
use lightgraph_engine::ir::LayoutDecl;
use lightgraph_engine::{ConstValue, Gpu, Graph};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// The profile every adapter takes that no other built-in profile names.
pub const DEFAULT_PROFILE: &str = "default";

/// The built-in profiles: name and text.
const BUILT_IN: [(&str, &str); 2] = [
    ("nvidia-h100", include_str!("../data/tuning/nvidia-h100.ron")),
    (DEFAULT_PROFILE, include_str!("../data/tuning/default.ron")),
];

/// The device knobs of one named layout.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Knobs {
    /// [`LayoutDecl::loop_guards`].
    pub loop_guards: Option<bool>,
    /// [`LayoutDecl::threads`].
    pub threads: Option<u64>,
    /// [`LayoutDecl::workgroup_size`].
    pub workgroup_size: Option<u32>,
    /// Constants added to the layout's (code variants that render the same image).
    pub constants: BTreeMap<String, ConstValue>,
    /// The measurement that chose them: a link into the repository's docs (`docs/...#anchor`).
    pub why: String,
}

impl Knobs {
    /// The knobs in words, e.g. `loop guards off, 2097152 threads, CWBVH_CHILD_SCAN=true`.
    pub fn summary(&self) -> String {
        let mut parts = Vec::new();
        if let Some(b) = self.loop_guards {
            parts.push(format!("loop guards {}", if b { "on" } else { "off" }));
        }
        if let Some(t) = self.threads {
            parts.push(format!("{t} threads"));
        }
        if let Some(w) = self.workgroup_size {
            parts.push(format!("workgroup {w}"));
        }
        parts.extend(self.constants.iter().map(|(k, v)| format!("{k}={v}")));
        parts.join(", ")
    }

    /// `decl` with these knobs.
    fn apply(&self, mut decl: LayoutDecl) -> LayoutDecl {
        if let Some(b) = self.loop_guards {
            decl.loop_guards = b;
        }
        if self.threads.is_some() {
            decl.threads = self.threads;
        }
        if let Some(w) = self.workgroup_size {
            decl.workgroup_size = w;
        }
        decl.constants.extend(self.constants.clone());
        decl
    }
}

/// The layout measured fastest for a built-in scene: a render of it without `--layout` takes
/// it (after the layout cache).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneLayout {
    /// The graph's built-in name.
    pub graph: String,
    /// The built-in scene's name.
    pub scene: String,
    /// The fastest named layout.
    pub layout: String,
    /// Its camera samples a second.
    pub rate: f64,
    /// The graph's default layout's.
    pub default_rate: f64,
    /// When it was measured.
    pub measured: String,
    /// The measurement: a link into the repository's docs.
    pub why: String,
}

/// A tuning profile as its file writes it.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Profile {
    /// Its name (the file's stem; not written in the file).
    #[serde(skip)]
    pub name: String,
    /// What it is for.
    pub description: String,
    /// Texts of adapter names that take this profile (e.g. `NVIDIA H100`).
    pub adapters: Vec<String>,
    /// A built-in profile whose layout knobs this one takes where it gives none (not its
    /// scenes' layouts, which were measured on its adapters only).
    pub like: Option<String>,
    /// Knobs by graph name, then by layout name.
    pub layouts: BTreeMap<String, BTreeMap<String, Knobs>>,
    /// The layouts measured fastest for built-in scenes on this profile's adapters.
    pub scenes: Vec<SceneLayout>,
}

impl Profile {
    /// Parses the profile `name` from `text` (read from `file`): an error names the file, the
    /// line and the problem.
    pub fn parse(name: &str, file: &str, text: &str) -> Result<Profile> {
        let mut p: Profile = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| anyhow!("{file}:{}:{}: {}", e.span.start.line, e.span.start.col, e.code))?;
        p.name = name.to_string();
        if let Some(like) = p.like.as_deref().filter(|l| !BUILT_IN.iter().any(|(n, _)| n == l)) {
            bail!("{file}: like: no built-in tuning profile is called '{like}'");
        }
        Ok(p)
    }

    /// Reads a profile of one's own from a `.ron` file.
    pub fn read(path: &Path) -> Result<Profile> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading the tuning profile {}", path.display()))?;
        let name = path
            .file_stem()
            .map_or("profile".into(), |s| s.to_string_lossy().into_owned());
        Profile::parse(&name, &path.display().to_string(), &text)
    }

    /// The knobs of `graph`'s layout `layout`: this profile's, else those of the profile it is
    /// `like`.
    pub fn knobs(&self, graph: &str, layout: &str) -> Option<&Knobs> {
        let own = self.layouts.get(graph).and_then(|l| l.get(layout));
        own.or_else(|| built_in_named(self.like.as_deref()?)?.knobs(graph, layout))
    }

    /// The layout `layout` of `graph` with this profile's knobs, where `decl` is that layout as
    /// the graph writes it; any other layout (one the tuner or the layout cache made) as it is.
    pub fn apply(&self, graph: &Graph, layout: &str, decl: LayoutDecl) -> LayoutDecl {
        let written = graph.layouts.get(layout).is_some_and(|w| *w == decl);
        match self.knobs(&graph.name, layout).filter(|_| written) {
            Some(k) => k.apply(decl),
            None => decl,
        }
    }

    /// The layout measured fastest for the built-in scene `scene` rendered by `graph`.
    pub fn scene_layout(&self, graph: &str, scene: &str) -> Option<&SceneLayout> {
        self.scenes.iter().find(|s| s.graph == graph && s.scene == scene)
    }

    /// Every knob's and scene layout's problem with the built-in graphs: a graph or layout
    /// that does not exist, a constant the graph lacks or of another type (for tests and
    /// `lightgraph tuning --check`).
    pub fn problems(&self, load: impl Fn(&str) -> Result<Graph>) -> Vec<String> {
        let mut out = Vec::new();
        let mut graphs = BTreeMap::new();
        let names = self.layouts.keys().chain(self.scenes.iter().map(|s| &s.graph));
        for name in names {
            if !graphs.contains_key(name) {
                graphs.insert(name.clone(), load(name));
            }
        }
        for (graph, layouts) in &self.layouts {
            let Ok(g) = &graphs[graph] else {
                out.push(format!("{}: no graph '{graph}'", self.name));
                continue;
            };
            for (layout, knobs) in layouts {
                if !g.layouts.contains_key(layout) {
                    out.push(format!("{}: graph '{graph}' has no layout '{layout}'", self.name));
                }
                for (c, v) in &knobs.constants {
                    let same_type = g
                        .constants
                        .get(c)
                        .is_some_and(|d| std::mem::discriminant(d) == std::mem::discriminant(v));
                    if !same_type {
                        out.push(format!(
                            "{}: {graph} {layout}: '{c}' is no {v:?} constant of the graph",
                            self.name
                        ));
                    }
                }
            }
        }
        for s in &self.scenes {
            match &graphs[&s.graph] {
                Ok(g) if !g.layouts.contains_key(&s.layout) => out.push(format!(
                    "{}: graph '{}' has no layout '{}'",
                    self.name, s.graph, s.layout
                )),
                Ok(_) => {}
                Err(_) => out.push(format!("{}: no graph '{}'", self.name, s.graph)),
            }
        }
        out
    }
}

/// Every built-in profile.
pub fn built_in() -> &'static [Profile] {
    static PARSED: OnceLock<Vec<Profile>> = OnceLock::new();
    PARSED.get_or_init(|| {
        BUILT_IN
            .iter()
            .map(|(name, text)| {
                let file = format!("data/tuning/{name}.ron");
                // The shipped files parse: the `tuning` tests parse each.
                Profile::parse(name, &file, text).unwrap_or_default()
            })
            .collect()
    })
}

/// The built-in profile called `name`.
pub fn built_in_named(name: &str) -> Option<&'static Profile> {
    built_in().iter().find(|p| p.name == name)
}

/// The built-in profile of the adapter called `adapter`: the first that names it, else the
/// default one.
pub fn for_adapter(adapter: &str) -> &'static Profile {
    let named = built_in()
        .iter()
        .find(|p| p.adapters.iter().any(|a| adapter.contains(a.as_str())));
    named.unwrap_or_else(|| built_in_named(DEFAULT_PROFILE).expect("the default profile is built in"))
}

/// Which profile a run takes (`--tuning`).
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Tuning {
    /// The adapter's built-in profile ([`for_adapter`]).
    #[default]
    Adapter,
    /// None: the layouts as the graphs write them.
    None,
    /// This one.
    Profile(Arc<Profile>),
}

impl Tuning {
    /// `--tuning`'s value: `auto`, `none`, a built-in profile's name or a `.ron` file (read and
    /// parsed now, and checked against the graphs `load` loads, so that a bad file is an error
    /// before any work).
    pub fn parse(s: &str, load: impl Fn(&str) -> Result<Graph>) -> Result<Tuning, String> {
        match s {
            "auto" => Ok(Tuning::Adapter),
            "none" => Ok(Tuning::None),
            _ if s.ends_with(".ron") => {
                let p = Profile::read(Path::new(s)).map_err(|e| format!("{e:#}"))?;
                match p.problems(load).as_slice() {
                    [] => Ok(Tuning::Profile(Arc::new(p))),
                    problems => Err(format!("{s}: {}", problems.join("; "))),
                }
            }
            _ => built_in_named(s)
                .map(|p| Tuning::Profile(Arc::new(p.clone())))
                .ok_or_else(|| {
                    let names: Vec<&str> = built_in().iter().map(|p| p.name.as_str()).collect();
                    format!(
                        "no built-in tuning profile '{s}' (built in: {}; or auto, none, a .ron file)",
                        names.join(", ")
                    )
                }),
        }
    }

    /// The profile this choice gives on the adapter called `adapter` (None: no GPU, the
    /// default profile), if any.
    pub fn profile(&self, adapter: Option<&str>) -> Option<&Profile> {
        match self {
            Tuning::Adapter => Some(adapter.map_or_else(|| for_adapter(""), for_adapter)),
            Tuning::None => None,
            Tuning::Profile(p) => Some(p),
        }
    }

    /// The layout `layout` (`decl`) of `graph` with the knobs of this choice's profile on `gpu`.
    pub fn apply(&self, gpu: Option<&Gpu>, graph: &Graph, layout: &str, decl: LayoutDecl) -> LayoutDecl {
        match self.profile(gpu.map(|g| g.info.name.as_str())) {
            Some(p) => p.apply(graph, layout, decl),
            None => decl,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const H100: &str = "NVIDIA H100 80GB HBM3";

    /// A built-in graph (not through crate::run, which depends on this module).
    fn load(name: &str) -> Result<Graph> {
        let (vfs, path) = crate::assets::graph_source(name).map_err(|e| anyhow!(e))?;
        Ok(Graph::load(&vfs, &path)?)
    }
    const LAVAPIPE: &str = "llvmpipe (LLVM 15.0.6, 256 bits)";

    #[test]
    fn the_built_in_profiles_parse_and_name_only_layouts_and_constants_their_graphs_have() {
        for (name, text) in BUILT_IN {
            let p = Profile::parse(name, name, text).unwrap_or_else(|e| panic!("{e:#}"));
            assert_eq!(built_in_named(name), Some(&p));
            let problems = p.problems(load);
            assert!(problems.is_empty(), "{problems:#?}");
        }
    }

    #[test]
    fn an_adapter_takes_the_profile_naming_it_else_the_default_which_has_its_knobs_but_not_its_scenes() {
        assert_eq!(for_adapter(H100).name, "nvidia-h100");
        let default = for_adapter(LAVAPIPE);
        assert_eq!(default.name, DEFAULT_PROFILE);
        assert_eq!(
            default.knobs("pt", "NaivePTsk"),
            for_adapter(H100).knobs("pt", "NaivePTsk")
        );
        assert!(default.knobs("pt", "NaivePTsk").is_some());
        assert_eq!(
            for_adapter(H100).scene_layout("pt", "sponza").unwrap().layout,
            "StreamingPTmk2"
        );
        assert!(default.scene_layout("pt", "sponza").is_none());
        assert!(for_adapter(H100).scene_layout("pt", "cornell-diffuse").is_none());
    }

    #[test]
    fn knobs_apply_to_a_named_layout_as_the_graph_writes_it_and_to_nothing_else() {
        let graph = load("pt").unwrap();
        let written = graph.layouts["NaivePTsk"].clone();
        assert!(
            written.loop_guards && written.constants.is_empty(),
            "the graph keeps no device knob"
        );
        let tuned = for_adapter(H100).apply(&graph, "NaivePTsk", written.clone());
        assert!(!tuned.loop_guards);
        assert_eq!(tuned.constants.get("CWBVH_CHILD_SCAN"), Some(&ConstValue::Bool(true)));
        // A layout the tuner made (another name, or the same name with other fields) is taken
        // as it is.
        assert_eq!(
            format!(
                "{:?}",
                for_adapter(H100).apply(&graph, "NaivePTsk (wg 128)", written.clone())
            ),
            format!("{written:?}")
        );
        let other = LayoutDecl {
            workgroup_size: 128,
            ..written.clone()
        };
        assert!(for_adapter(H100).apply(&graph, "NaivePTsk", other).loop_guards);
        assert!(Tuning::None.apply(None, &graph, "NaivePTsk", written).loop_guards);
    }

    #[test]
    fn each_scene_layout_is_a_layout_of_its_graph_faster_than_its_default_for_a_built_in_scene() {
        let scenes: Vec<String> = crate::assets::scene_names().into_iter().map(|(n, _)| n).collect();
        for p in built_in() {
            for m in &p.scenes {
                let graph = load(&m.graph).unwrap();
                assert_ne!(graph.default_layout, m.layout, "{m:?}");
                assert!(scenes.contains(&m.scene), "{m:?}");
                assert!(m.rate > 1.05 * m.default_rate, "{m:?}");
            }
        }
    }

    #[test]
    fn a_bad_profile_is_an_error_naming_its_file_and_line_and_an_unknown_name_lists_the_built_in_ones() {
        let e = Profile::parse("mine", "mine.ron", "(\n  adapters: [\"X\"],\n  loop_guards: false,\n)").unwrap_err();
        assert!(format!("{e:#}").starts_with("mine.ron:3:"), "{e:#}");
        let e = Profile::parse("mine", "mine.ron", "(like: \"nvidia-a100\")").unwrap_err();
        assert!(format!("{e:#}").contains("'nvidia-a100'"), "{e:#}");
        let e = Tuning::parse("amd", load).unwrap_err();
        assert!(e.contains("nvidia-h100") && e.contains(DEFAULT_PROFILE), "{e}");
        let mine = Profile::parse("mine", "mine.ron", "(layouts: {\"pt\": {\"NaivePTzz\": (loop_guards: false, constants: {\"CWBVH_CHILD_SCAN\": U32(1)}, why: \"\")}})").unwrap();
        let problems = mine.problems(load);
        assert_eq!(problems.len(), 2, "{problems:#?}");
    }
}
