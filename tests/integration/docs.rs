//! The examples of docs/graphs.md, as a newcomer would copy them: every fenced block marked
//! `file=PATH` is written to a folder of its own, and each graph there renders in each of its
//! layouts with what it promises.

use crate::cli::temp_dir;
use crate::common::render;
use lightgraph::run::load_scene;
use std::path::PathBuf;

/// Writes the example files of docs/graphs.md below a fresh folder; returns it.
fn write_examples() -> PathBuf {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/graphs.md")).unwrap();
    let dir = temp_dir("docs-examples");
    let mut written = 0;
    let mut rest = doc.as_str();
    while let Some(start) = rest.find("```") {
        let after = &rest[start + 3..];
        let header_end = after.find('\n').unwrap();
        let header = &after[..header_end];
        let body_end = after[header_end..].find("```").unwrap() + header_end;
        if let Some(path) = header.split_whitespace().find_map(|w| w.strip_prefix("file=")) {
            let file = dir.join(path);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(&file, &after[header_end + 1..body_end]).unwrap();
            written += 1;
        }
        rest = &after[body_end + 3..];
    }
    assert_eq!(
        written, 5,
        "docs/graphs.md has two examples of a graph and its WGSL each, and one graph that extends the first"
    );
    dir
}

#[test]
fn the_examples_of_the_graph_guide_render() {
    let dir = write_examples();
    let scene = load_scene("cornell-diffuse").unwrap();
    let (w, h) = (16, 16);
    let ao = dir.join("lab/ao.ron");
    for layout in ["fused", "split"] {
        let r = render(&scene, ao.to_str().unwrap(), layout, (w, h), 2, 2, 3, &[]);
        assert_eq!(r.counters["rays_primary"], (w * h * 2 * 2) as u64, "ao {layout}");
        // Four occlusion rays per camera ray that hits (every one in the closed box).
        assert_eq!(
            r.counters["rays_occlusion"],
            4 * r.counters["rays_primary"],
            "ao {layout}"
        );
        assert!(r.image.mean.iter().all(|p| (0.0..=1.0).contains(&p[0])), "ao {layout}");
        assert!(
            r.image.mean.iter().any(|p| p[0] > 0.5),
            "ao {layout}: nothing unoccluded"
        );
    }
    // The graph that extends `ao`: its constants, its layouts.
    let wide = dir.join("lab/ao-wide.ron");
    for layout in ["stored", "stored_wide", "fused_again"] {
        let r = render(&scene, wide.to_str().unwrap(), layout, (w, h), 2, 2, 3, &[]);
        assert_eq!(
            r.counters["rays_occlusion"],
            8 * r.counters["rays_primary"],
            "ao-wide {layout}"
        );
    }
    let sorted = dir.join("lab/sorted.ron");
    let r = render(&scene, sorted.to_str().unwrap(), "sorted", (w, h), 2, 2, 3, &[]);
    assert_eq!(r.counters["rays_primary"], (w * h * 2 * 2) as u64);
    // Every camera ray of the closed box hits; each pixel's mean is its albedo at the hit
    // (the walls of scenes/cornell/cornell-diffuse.ron: at most 0.803922 in any channel).
    assert!(
        r.image
            .mean
            .iter()
            .all(|p| p.iter().all(|&c| (0.0..=0.803923).contains(&c))),
        "sorted"
    );
    let lit = r.image.mean.iter().filter(|p| p[0] > 0.1).count();
    assert!(lit > (w * h) as usize / 2, "sorted: {lit} pixels with an albedo");
}
