//! Layouts measured fastest for a built-in scene on an adapter, shipped with lightgraph
//! (`data/measured-layouts.ron`, measured by `bench/defaults.sh`): a render of such a scene
//! without `--layout`, on an adapter whose name contains the entry's, takes the entry's layout
//! (after the layout cache), so that the gallery renders fast by default where it was measured.
//! No layout per kind of adapter is fastest on every scene (docs/performance.md, "Default
//! layouts against the fastest").

use serde::Deserialize;
use std::sync::OnceLock;

/// One measured choice.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredLayout {
    /// The graph's built-in name.
    pub graph: String,
    /// The built-in scene's name.
    pub scene: String,
    /// Text of the adapter's name (e.g. `NVIDIA H100`).
    pub adapter: String,
    /// The fastest named layout.
    pub layout: String,
    /// Its camera samples a second.
    pub rate: f64,
    /// The graph's default layout's.
    pub default_rate: f64,
    /// When it was measured.
    pub measured: String,
}

/// The shipped table.
const TABLE: &str = include_str!("../data/measured-layouts.ron");

/// Every entry of the shipped table (its parse is tested: `measured_layouts` tests).
pub fn table() -> &'static [MeasuredLayout] {
    static PARSED: OnceLock<Vec<MeasuredLayout>> = OnceLock::new();
    PARSED.get_or_init(|| ron::from_str(TABLE).unwrap_or_default())
}

/// The measured layout of `graph` for `scene` on the adapter called `adapter`, if any.
pub fn find(graph: &str, scene: &str, adapter: &str) -> Option<&'static MeasuredLayout> {
    table()
        .iter()
        .find(|m| m.graph == graph && m.scene == scene && adapter.contains(&m.adapter))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_parses_and_names_layouts_of_its_graphs_faster_than_their_defaults() {
        let parsed: Vec<MeasuredLayout> = ron::from_str(TABLE).expect("data/measured-layouts.ron parses");
        assert!(!parsed.is_empty());
        let scenes: Vec<String> = crate::assets::scene_names().into_iter().map(|(n, _)| n).collect();
        for m in &parsed {
            let graph = crate::run::load_graph(&m.graph).unwrap();
            assert!(graph.layouts.contains_key(&m.layout), "{m:?}");
            assert_ne!(graph.default_layout, m.layout, "{m:?}");
            assert!(scenes.contains(&m.scene), "{m:?}");
            assert!(m.rate > 1.05 * m.default_rate, "{m:?}");
        }
    }

    #[test]
    fn an_entry_holds_for_its_graph_scene_and_adapter_only() {
        let h100 = "NVIDIA H100 80GB HBM3";
        assert_eq!(find("pt", "sponza", h100).unwrap().layout, "StreamingPTmk2");
        assert!(find("pt", "sponza", "llvmpipe (LLVM 15.0.6, 256 bits)").is_none());
        assert!(find("pt", "cornell-diffuse", h100).is_none());
        assert!(find("ppm", "sponza", h100).is_none());
    }
}
