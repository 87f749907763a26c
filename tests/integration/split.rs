//! Geometry split over several buffers (scenes/src/pack/split.rs): a scene whose primitives or
//! attributes exceed one storage binding renders from chunks. `--max-binding` splits a small
//! scene as a large one splits, so the split kernels render the glTF Cornell box (triangles
//! with vertex normals: primitives and attributes both split) in every estimator family and
//! trace the same rays and give the unsplit image to float rounding (the film's atomic sums
//! add in any order): the chunks hold the same elements, only the buffer each is read from
//! differs.

use crate::common::{Rendered, assert_same_render, borrowed, data, gpu, measured, options};
use lightgraph::run::{LayoutOverrides, LoadedScene, Session, load_graph};
use lightgraph_engine::ConstValue;
use lightgraph_scenes::bvh::BvhKind;

/// The test scene `file` of tests/data/scenes with the BVH `kind`.
fn scene(file: &str, kind: BvhKind) -> LoadedScene {
    let file = data(&format!("scenes/{file}"));
    let text = std::fs::read_to_string(&file).unwrap();
    LoadedScene::parse(file.to_str().unwrap(), &text, kind, Some(&data(""))).unwrap()
}

/// Renders 3 frames of 16×16 at 2 samples per pixel, seed 5, with `constants`, binding at most `max_binding`
/// bytes of geometry at once: the render, and whether its kernels read split geometry.
fn render(
    scene: &LoadedScene,
    (graph, layout): (&str, &str),
    constants: &[(&str, ConstValue)],
    max_binding: Option<u64>,
) -> anyhow::Result<(Rendered, bool)> {
    let graph = load_graph(graph).unwrap();
    let overrides = LayoutOverrides {
        max_binding,
        ..Default::default()
    };
    let mut session = Session::new(
        gpu(),
        &graph,
        layout,
        scene,
        options((16, 16), 2, 5, constants, overrides),
    )?;
    for _ in 0..3 {
        session.render_frame()?;
    }
    let split = session
        .program()
        .kernels
        .iter()
        .any(|k| k.source.text().contains("fn split_index"));
    let rendered = Rendered {
        image: session.image()?,
        counters: session.counters.clone(),
        loops_capped: session.loops_capped,
        memory_bytes: session.memory_bytes(),
    };
    Ok((rendered, split))
}

/// Asserts that `scene` split at `max_binding` bytes renders what it renders whole with each
/// of `runs` (graph, layout).
fn assert_split_renders_whole(scene: &LoadedScene, runs: &[(&str, &str)], max_binding: u64) {
    for &(graph, layout) in runs {
        // Both renders take one measurement of LVC-BPT's measured constant.
        let owned = measured(scene, graph, layout, ((16, 16), 2, 5), &[]);
        let constants = borrowed(&owned);
        let (whole, whole_split) = render(scene, (graph, layout), &constants, None).unwrap();
        let (split, split_split) = render(scene, (graph, layout), &constants, Some(max_binding)).unwrap();
        assert!(
            !whole_split,
            "{graph} {layout}: a scene that fits one binding is not split"
        );
        assert!(split_split, "{graph} {layout}: --max-binding {max_binding} splits it");
        assert!(
            whole.image.mean.iter().flatten().any(|&v| v > 0.0),
            "{graph} {layout}: a black image"
        );
        assert_same_render(&whole, &split, &format!("{graph} {layout}, split against whole"));
    }
}

#[test]
fn split_geometry_renders_the_unsplit_image_in_every_family() {
    // The glTF Cornell box, 36 triangles; 600 bytes a binding: 12 primitives (48 bytes) a
    // chunk, so 3 chunks. Its vertex normals are its faces' (no attribute is read).
    for (runs, kind) in [
        (
            &[("pt", "NaivePTsk"), ("bpt-lvc", "LVC-BPTmk"), ("vcm", "VCMsk")][..],
            BvhKind::Cwbvh,
        ),
        (&[("pt", "StreamingPTmk2"), ("ppm", "PPMsk")][..], BvhKind::Bvh2),
    ] {
        let box_ = scene("gltf-cornell.ron", kind);
        assert_eq!(box_.compiled.primitives.len(), 36);
        assert_split_renders_whole(&box_, runs, 600);
    }
    // Two triangles shaded by tilted vertex normals (a 2.7 times brighter square without
    // them); 48 bytes a binding: one primitive and one attribute (40 bytes) a chunk.
    let quad = scene("tilted-normals-quad.ron", BvhKind::Cwbvh);
    assert_eq!(quad.compiled.attributes.len(), 2);
    assert_split_renders_whole(&quad, &[("pt", "NaivePTsk"), ("vcm", "VCMsk")], 48);
}

#[test]
fn geometry_too_large_for_every_chunk_is_an_error_naming_it() {
    // 200 bytes a binding: 4 primitives a chunk, 16 in 4 chunks, fewer than the box's 36.
    let box_ = scene("gltf-cornell.ron", BvhKind::Cwbvh);
    let e = format!(
        "{:#}",
        render(&box_, ("pt", "NaivePTsk"), &[], Some(200)).err().unwrap()
    );
    assert!(
        e.contains("the scene is too large for this GPU")
            && e.contains("'primitives' buffer takes")
            && e.contains("4 chunks")
            && e.contains("36 primitives"),
        "{e}"
    );
}
