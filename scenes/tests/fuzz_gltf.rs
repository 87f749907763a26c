//! Fuzzing of the glTF loader with proptest: the committed glTF Cornell box
//! (`tests/data/gltf/cornell_box`) and an indexed variant of it are mutated (structured JSON
//! edits of accessors, buffer views, buffers, primitives, nodes, materials and the root: set a
//! field to an odd value, remove it, drop or repeat an array entry, replace any value; text
//! edits of the JSON; truncated or altered bytes of the binary buffer), written to a temporary
//! directory and loaded with [`resolve_gltf`], then compiled with [`CompiledScene::with_bvh`]
//! for both BVH kinds.
//!
//! Properties: no input panics; every refusal is an error whose message starts with the glTF
//! file's path and says what is wrong; no allocation exceeds 1 GiB (a global allocator refuses
//! larger ones, which aborts the test with the input left in the temporary directory), so a
//! huge accessor count cannot make the loader allocate terabytes.
//!
//! Bound: 4000 inputs, about fifteen seconds in a debug build;
//! `LIGHTGRAPH_FUZZ_CASES=N cargo test -p lightgraph-scenes --test fuzz_gltf -- --nocapture`
//! runs N inputs (and prints the counts), `LIGHTGRAPH_FUZZ_SEED=K` other inputs.

#[path = "../../engine/tests/common/fuzz.rs"]
mod fuzz;

use fuzz::{Edit, JSON, Outcome, apply, edits, fuzz};
use lightgraph_scenes::bvh::BvhKind;
use lightgraph_scenes::{CompiledScene, parse_scene, resolve_gltf};
use proptest::prelude::*;
use proptest::sample::Index;
use serde_json::{Value, json};
use std::alloc::{GlobalAlloc, Layout, System};
use std::fmt;
use std::io::Write;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The largest allocation the tests of this file may make.
const MAX_ALLOCATION: usize = 1 << 30;

/// The system allocator, refusing allocations above [`MAX_ALLOCATION`] after saying so.
struct Capped;

fn refuse(size: usize) -> bool {
    if size <= MAX_ALLOCATION {
        return false;
    }
    // Formats nothing that allocates: the size as digits, the directory as bytes.
    let mut digits = [0u8; 20];
    let mut n = size;
    let mut i = digits.len();
    while n > 0 || i == digits.len() {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
    }
    let mut err = std::io::stderr();
    let _ = err.write_all(b"\nfuzz gltf: refused an allocation of ");
    let _ = err.write_all(&digits[i..]);
    let _ = err.write_all(b" bytes; the input is in ");
    let _ = err.write_all(case_dir().as_os_str().as_bytes());
    let _ = err.write_all(b"\n");
    true
}

unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if refuse(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract is System's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if refuse(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract is System's.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if refuse(new_size) {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract is System's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract is System's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

/// The directory inputs are written to (one per test process, a folder in it per test).
fn case_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| std::env::temp_dir().join(format!("lightgraph-fuzz-gltf-{}", std::process::id())))
}

const GLTF: &str = "CornellBox-Original.gltf";
const BIN: &str = "CornellBox-Original.bin";

/// The Cornell box as committed, and a variant whose first primitive is indexed with u16
/// indices appended to the buffer.
fn seeds() -> &'static [(Value, Vec<u8>)] {
    static SEEDS: OnceLock<Vec<(Value, Vec<u8>)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/gltf/cornell_box");
        let gltf: Value = serde_json::from_slice(&std::fs::read(dir.join(GLTF)).unwrap()).unwrap();
        let bin = std::fs::read(dir.join(BIN)).unwrap();
        let mut indexed = gltf.clone();
        let mut indexed_bin = bin.clone();
        for i in [0u16, 1, 2, 3, 4, 5] {
            indexed_bin.extend(i.to_le_bytes());
        }
        let views = indexed["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": 12}));
        let view = views.len() - 1;
        let accessors = indexed["accessors"].as_array_mut().unwrap();
        accessors.push(json!({"bufferView": view, "componentType": 5123, "count": 6, "type": "SCALAR"}));
        let accessor = accessors.len() - 1;
        indexed["meshes"][0]["primitives"][0]["indices"] = json!(accessor);
        indexed["buffers"][0]["byteLength"] = json!(indexed_bin.len());
        vec![(gltf, bin), (indexed, indexed_bin)]
    })
}

/// Objects a structured edit addresses (`*`: an entry of the array) and the fields it sets or
/// removes there.
const SECTIONS: &[(&str, &[&str])] = &[
    (
        "accessors/*",
        &[
            "bufferView",
            "byteOffset",
            "count",
            "componentType",
            "type",
            "sparse",
            "normalized",
        ],
    ),
    ("bufferViews/*", &["buffer", "byteOffset", "byteLength", "byteStride"]),
    ("buffers/*", &["byteLength", "uri"]),
    ("meshes/0/primitives/*", &["attributes", "indices", "material", "mode"]),
    (
        "meshes/0/primitives/*/attributes",
        &["POSITION", "NORMAL", "TEXCOORD_0"],
    ),
    (
        "nodes/*",
        &["mesh", "children", "matrix", "translation", "rotation", "scale"],
    ),
    (
        "materials/*",
        &["pbrMetallicRoughness", "emissiveFactor", "extensions", "doubleSided"],
    ),
    (
        "",
        &["scene", "scenes", "nodes", "extensionsRequired", "images", "textures"],
    ),
];

/// Values the structured edits put in place: the JSON dialect's numbers and values, and
/// objects and arrays that make sense in some field.
fn values() -> Vec<Value> {
    let mut out: Vec<Value> = JSON
        .numbers
        .iter()
        .chain(JSON.values)
        .map(|v| serde_json::from_str(v).unwrap())
        .collect();
    out.extend(JSON.strings.iter().map(|s| json!(s)));
    out.extend([
        json!({"count": 2147483648u64, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}),
        json!({"count": 4, "indices": {"bufferView": 0, "componentType": 5121, "byteOffset": 70}, "values": {"bufferView": 1}}),
        json!([1, 0]),
        json!(vec![1e30; 16]),
        json!(vec![0.0; 16]),
        json!([{"uri": "missing.png"}]),
        json!([{"bufferView": 0, "mimeType": "image/png"}]),
        json!([{"source": 0}]),
        json!({"baseColorTexture": {"index": 0}}),
        json!({"POSITION": 0}),
        json!(["KHR_unknown"]),
    ]);
    out
}

/// One structured edit of the JSON document.
#[derive(Debug, Clone)]
enum JsonEdit {
    /// Sets a field of an object of a section to a value.
    Set(usize, Index, Index, Index),
    /// Removes a field.
    Remove(usize, Index, Index),
    /// Removes an entry of a section's array.
    Drop(usize, Index),
    /// Repeats an entry of a section's array.
    Repeat(usize, Index),
    /// Replaces any value of the document.
    Replace(Index, Index),
}

fn json_edit() -> impl Strategy<Value = JsonEdit> {
    let (s, i) = (|| 0..SECTIONS.len(), || any::<Index>());
    prop_oneof![
        6 => (s(), i(), i(), i()).prop_map(|(a, b, c, d)| JsonEdit::Set(a, b, c, d)),
        2 => (s(), i(), i()).prop_map(|(a, b, c)| JsonEdit::Remove(a, b, c)),
        1 => (s(), i()).prop_map(|(a, b)| JsonEdit::Drop(a, b)),
        1 => (s(), i()).prop_map(|(a, b)| JsonEdit::Repeat(a, b)),
        2 => (i(), i()).prop_map(|(a, b)| JsonEdit::Replace(a, b)),
    ]
}

/// The value at `path` (`*` picks an array entry by `item`).
fn at<'a>(mut v: &'a mut Value, path: &str, item: &Index) -> Option<&'a mut Value> {
    for part in path.split('/').filter(|p| !p.is_empty()) {
        v = match v {
            Value::Array(a) => {
                let i = match part {
                    "*" => (!a.is_empty()).then(|| item.index(a.len()))?,
                    _ => part.parse().ok()?,
                };
                a.get_mut(i)?
            }
            Value::Object(o) => o.get_mut(part)?,
            _ => return None,
        };
    }
    Some(v)
}

/// The object of section `s` that `item` picks, and the field that `key` picks.
fn field<'a>(
    doc: &'a mut Value,
    s: usize,
    item: &Index,
    key: &Index,
) -> Option<(&'a mut serde_json::Map<String, Value>, &'static str)> {
    let (path, keys) = SECTIONS[s];
    match at(doc, path, item)? {
        Value::Object(o) => Some((o, keys[key.index(keys.len())])),
        _ => None,
    }
}

/// Every value of the document, as paths of keys and indices.
fn paths(v: &Value, prefix: String, out: &mut Vec<String>) {
    match v {
        Value::Object(o) => o.iter().for_each(|(k, x)| paths(x, format!("{prefix}/{k}"), out)),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| paths(x, format!("{prefix}/{i}"), out)),
        _ => {}
    }
    out.push(prefix);
}

fn apply_json(doc: &mut Value, edit: &JsonEdit, values: &[Value]) {
    let section = |s: usize| SECTIONS[s];
    match edit {
        JsonEdit::Set(s, item, key, value) => {
            if let Some((o, key)) = field(doc, *s, item, key) {
                o.insert(key.into(), values[value.index(values.len())].clone());
            }
        }
        JsonEdit::Remove(s, item, key) => {
            if let Some((o, key)) = field(doc, *s, item, key) {
                o.remove(key);
            }
        }
        JsonEdit::Drop(s, item) | JsonEdit::Repeat(s, item) => {
            let path = section(*s).0.trim_end_matches("/*");
            if let Some(Value::Array(a)) = at(doc, path, item).filter(|_| section(*s).0.ends_with('*'))
                && !a.is_empty()
            {
                let i = item.index(a.len());
                match edit {
                    JsonEdit::Drop(..) => drop(a.remove(i)),
                    _ => a.insert(i, a[i].clone()),
                }
            }
        }
        JsonEdit::Replace(node, value) => {
            let mut all = Vec::new();
            paths(doc, String::new(), &mut all);
            let path = &all[node.index(all.len())];
            if let Some(v) = doc.pointer_mut(path) {
                *v = values[value.index(values.len())].clone();
            }
        }
    }
}

/// One edit of the binary buffer.
#[derive(Debug, Clone)]
enum BinEdit {
    /// Cuts it off.
    Truncate(Index),
    /// Flips bits of one byte.
    Flip(Index, u8),
    /// Overwrites four bytes (a NaN, an infinity, a huge index).
    Set(Index, [u8; 4]),
}

fn bin_edit() -> impl Strategy<Value = BinEdit> {
    let word = prop::sample::select(vec![
        [0xff; 4],
        [0, 0, 0x80, 0x7f],
        [0xff, 0xff, 0x7f, 0x7f],
        [0x10, 0, 0, 0],
    ]);
    prop_oneof![
        any::<Index>().prop_map(BinEdit::Truncate),
        (any::<Index>(), 1..=255u8).prop_map(|(i, x)| BinEdit::Flip(i, x)),
        (any::<Index>(), word).prop_map(|(i, w)| BinEdit::Set(i, w)),
    ]
}

fn apply_bin(bin: &mut Vec<u8>, edit: &BinEdit) {
    if bin.is_empty() {
        return;
    }
    match edit {
        BinEdit::Truncate(i) => bin.truncate(i.index(bin.len())),
        BinEdit::Flip(i, x) => {
            let n = bin.len();
            bin[i.index(n)] ^= x;
        }
        BinEdit::Set(i, w) => {
            let at = i.index(bin.len());
            for (b, v) in bin[at..].iter_mut().zip(w) {
                *b = *v;
            }
        }
    }
}

/// A mutated asset: the glTF text and buffer bytes, with the edits that made them.
#[derive(Clone)]
struct Asset {
    gltf: String,
    bin: Vec<u8>,
    edits: (usize, Vec<JsonEdit>, Vec<Edit>, Vec<BinEdit>),
}

impl fmt::Debug for Asset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{GLTF} ({} buffer bytes) after {:?}:\n{}\n",
            self.bin.len(),
            self.edits,
            self.gltf
        )
    }
}

fn asset() -> impl Strategy<Value = Asset> {
    let json_edits = prop::collection::vec(json_edit(), 0..=3);
    let text_edits = prop::option::weighted(0.25, edits(2)).prop_map(Option::unwrap_or_default);
    let bin_edits = prop::collection::vec(bin_edit(), 0..=2);
    (0..seeds().len(), json_edits, text_edits, bin_edits).prop_map(|(seed, json_edits, text_edits, bin_edits)| {
        let (mut doc, mut bin) = seeds()[seed].clone();
        let values = values();
        json_edits.iter().for_each(|e| apply_json(&mut doc, e, &values));
        bin_edits.iter().for_each(|e| apply_bin(&mut bin, e));
        let gltf = apply(&serde_json::to_string_pretty(&doc).unwrap(), &text_edits, &JSON);
        Asset {
            gltf,
            bin,
            edits: (seed, json_edits, text_edits, bin_edits),
        }
    })
}

/// Loads the asset from the folder `test` of [`case_dir`] into a scene with a background light
/// and compiles it.
fn check(test: &str, asset: &Asset) -> Result<Outcome, String> {
    let dir = &case_dir().join(test);
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join(GLTF), &asset.gltf).unwrap();
    std::fs::write(dir.join(BIN), &asset.bin).unwrap();
    let text = format!(
        "Scene(gltf: \"{GLTF}\", camera: (position: (0.0, 1.0, 3.6), look: Target((0.0, 1.0, 0.0)), \
         up: (0.0, 1.0, 0.0), fov_degrees: 40.0), lights: [Background(radiance: (1.0, 1.0, 1.0))])"
    );
    let mut scene = parse_scene("fuzz.ron", &text).unwrap();
    if let Err(e) = resolve_gltf(&mut scene, "fuzz.ron", Some(dir)) {
        let prefix = format!("{}: ", dir.join(GLTF).display());
        return match e.message.strip_prefix(&prefix) {
            Some(what) if !what.trim().is_empty() => Ok(Outcome::Refused(e.message)),
            _ => Err(format!("'{e}' does not start with '{prefix}' and say what is wrong")),
        };
    }
    for kind in [BvhKind::Bvh2, BvhKind::Cwbvh] {
        match CompiledScene::with_bvh(&scene, kind) {
            Ok(_) => {}
            Err(e) if e.trim().is_empty() => return Err("an empty BVH error".into()),
            Err(e) => return Ok(Outcome::Refused(e)),
        }
    }
    Ok(Outcome::Ok)
}

#[test]
fn fuzz_gltf_assets() {
    fuzz("gltf", 4000, asset(), |a| check("fuzz", a));
    let _ = std::fs::remove_dir_all(case_dir().join("fuzz"));
}

/// An unmutated seed as an asset.
fn seed(i: usize) -> Asset {
    let (doc, bin) = seeds()[i].clone();
    Asset {
        gltf: serde_json::to_string_pretty(&doc).unwrap(),
        bin,
        edits: (i, Vec::new(), Vec::new(), Vec::new()),
    }
}

#[test]
fn seeds_load() {
    for i in 0..seeds().len() {
        assert_eq!(check("seeds", &seed(i)), Ok(Outcome::Ok), "seed {i}");
    }
    let _ = std::fs::remove_dir_all(case_dir().join("seeds"));
}

/// Accessor counts of 2^31 (plain, and sparse without a buffer view, which the gltf crate
/// would fill with 2^31 zero positions) are refused without a large allocation: [`Capped`]
/// aborts the test on any allocation above 1 GiB.
#[test]
fn huge_accessor_counts_allocate_nothing_large() {
    let huge = 1u64 << 31;
    let sparse =
        json!({"count": huge, "indices": {"bufferView": 1, "componentType": 5125}, "values": {"bufferView": 1}});
    for (i, sparse) in [None, Some(sparse)].into_iter().enumerate() {
        let mut asset = seed(0);
        let mut doc: Value = serde_json::from_str(&asset.gltf).unwrap();
        let accessor = doc["accessors"][0].as_object_mut().unwrap();
        accessor.insert("count".into(), json!(huge));
        if let Some(sparse) = sparse {
            accessor.insert("sparse".into(), sparse);
            accessor.remove("bufferView");
        }
        asset.gltf = doc.to_string();
        let outcome = check("huge", &asset);
        assert!(
            matches!(&outcome, Ok(Outcome::Refused(e)) if e.contains("accessor 0")),
            "case {i}: {outcome:?}"
        );
    }
    let _ = std::fs::remove_dir_all(case_dir().join("huge"));
}
