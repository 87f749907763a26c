//! Fuzzing of Mitsuba scene files with proptest: the committed test scenes
//! (`tests/data/mitsuba`, every feature the importer reads in Mitsuba 3's and 0.5's names,
//! and media)
//! are mutated (text edits, and token-aware edits of numbers, attribute strings, words and
//! elements) and go through [`mitsuba::parse`] (with their OBJ, PLY and PNG files beside
//! them) and [`CompiledScene::with_bvh`] for both BVH kinds.
//!
//! Properties: no input panics; every refusal of the importer is an error that starts with
//! the file, a line and column within it, and says what is wrong; every scene it accepts
//! either compiles or is refused by the compiler with a message.
//!
//! Bound: 3000 mutated scenes, a few seconds in a release build;
//! `LIGHTGRAPH_FUZZ_CASES=N cargo test -p lightgraph-scenes --test fuzz_mitsuba -- --nocapture`
//! runs N inputs (and prints the counts), `LIGHTGRAPH_FUZZ_SEED=K` other inputs.

#[path = "../../engine/tests/common/fuzz.rs"]
mod fuzz;

use fuzz::{Dialect, Mutated, Outcome, check_located, edits, fuzz};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::mitsuba;
use proptest::prelude::*;
use proptest::sample::Index;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// XML attribute values: numbers, references, parameters and names Mitsuba reads.
#[rustfmt::skip]
const XML: Dialect = Dialect {
    numbers: &[
        "0", "-1", "1", "2", "0.5", "-0.0", "nan", "inf", "-inf", "1e30", "-1e30", "1e-45", "180", "90", "65536",
        "4294967296", "1 2", "1, 2, 3, 4",
    ],
    values: &["\"\"", "\"$res\"", "\"$nowhere\"", "\"true\"", "\"0 0 0\"", "\"x\""],
    strings: &[
        "", "x", "$res", "$", "$$", "checker", "pair", "floor", "models/quad.obj", "models/tetra.ply",
        "textures/checker.png", "../nowhere.obj", "diagonal", "larger", "y", "Au", "none", "water", "beckmann",
        "shapegroup", "instance", "sphere", "area", "envmap", "1e400", "é", "homogeneous", "heterogeneous",
        "hg", "isotropic", "interior", "exterior", "null", "fog", "juice", "boundary", "volpath",
    ],
};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mitsuba")
}

/// The seed scenes: (file name, text).
fn seeds() -> &'static [(String, String)] {
    static SEEDS: OnceLock<Vec<(String, String)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        ["all-features.xml", "version-0.5.xml", "media.xml"]
            .iter()
            .map(|name| (name.to_string(), std::fs::read_to_string(data().join(name)).unwrap()))
            .collect()
    })
}

/// Imports and compiles with both BVH kinds.
fn check(file: &str, text: &str) -> Result<Outcome, String> {
    let scene = match mitsuba::parse(file, &data(), text) {
        Ok(imported) => imported.scene,
        Err(e) => {
            let message = e.to_string();
            check_located(&message, file, text.lines().count())?;
            return Ok(Outcome::Refused(message));
        }
    };
    for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
        match CompiledScene::with_bvh(&scene, kind) {
            Ok(compiled) => {
                let (w, h) = scene.resolution;
                compiled.resources(&CompiledScene::camera(&scene, w, h));
            }
            Err(e) if e.trim().is_empty() => return Err("an empty compile error".into()),
            Err(e) => return Ok(Outcome::Refused(e)),
        }
    }
    Ok(Outcome::Ok)
}

#[test]
fn fuzz_mitsuba_files() {
    let mutated = (any::<Index>(), edits(3)).prop_map(|(i, edits)| {
        let (file, text) = &seeds()[i.index(seeds().len())];
        Mutated::new(file, text, edits, &XML)
    });
    fuzz("mitsuba", 3000, mutated, |m| check(&m.file, &m.text));
}

#[test]
fn seeds_import_and_compile() {
    for (file, text) in seeds() {
        assert_eq!(check(file, text).unwrap(), Outcome::Ok, "{file}");
    }
}
