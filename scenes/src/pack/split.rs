//! Geometry larger than one storage binding: the primitives and their attributes split into
//! chunks of equal length (the last shorter), each its own resource (`primitives`,
//! `primitives_1`, ...). The shaders compiled with the [`FLAG`] select a chunk by index
//! (`primitive_at`, `attribute_at` in shaders/lib/intersect.wgsl); without it the chunks are
//! neither compiled in nor bound, so a scene that fits one binding renders as before.

use crate::gpu::{GpuPrimitive, GpuTriangleAttributes};
use std::collections::BTreeMap;
use std::fmt;

/// The preprocessor flag of kernels for split geometry.
pub const FLAG: &str = "SPLIT_GEOMETRY";

/// How many chunks a split resource has at most (the resources `name`, `name_1` ..
/// `name_3` in passes/scene.ron).
pub const CHUNKS: usize = 4;

/// The resources that split, with their element sizes in bytes.
const SPLIT: [(&str, usize); 2] = [
    ("primitives", size_of::<GpuPrimitive>()),
    ("attributes", size_of::<GpuTriangleAttributes>()),
];

/// The name of chunk `k` of resource `name`: the name itself for the first.
pub fn chunk_name(name: &str, k: usize) -> String {
    match k {
        0 => name.to_string(),
        _ => format!("{name}_{k}"),
    }
}

/// A resource that even [`CHUNKS`] chunks of one binding each cannot hold.
#[derive(Debug, Clone, PartialEq)]
pub struct TooLarge {
    /// The resource.
    pub name: &'static str,
    /// Its size in bytes.
    pub bytes: u64,
    /// The most bytes one chunk holds.
    pub chunk_bytes: u64,
}

impl fmt::Display for TooLarge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mib = |b: u64| b as f64 / 1048576.0;
        write!(
            f,
            "its '{}' buffer takes {:.1} MiB, more than {CHUNKS} chunks of {:.1} MiB (one storage binding each) hold",
            self.name,
            mib(self.bytes),
            mib(self.chunk_bytes)
        )
    }
}

/// Splits the geometry of `resources` (the scene's, by name) into [`CHUNKS`] resources each
/// where one of them is larger than `max_binding` bytes, every chunk but the last holding
/// as many whole elements as fit `max_binding`; the chunks past the data are empty. Returns
/// whether it split (then the kernels need [`FLAG`]); leaves `resources` as they are if not.
pub fn split(resources: &mut BTreeMap<String, Vec<u8>>, max_binding: u64) -> Result<bool, TooLarge> {
    let size = |name: &str| resources.get(name).map_or(0, |b| b.len() as u64);
    if SPLIT.iter().all(|&(name, _)| size(name) <= max_binding) {
        return Ok(false);
    }
    for (name, stride) in SPLIT {
        let per_chunk = (max_binding / stride as u64).max(1) as usize;
        let chunk_bytes = (per_chunk * stride) as u64;
        let bytes = resources.remove(name).unwrap_or_default();
        if bytes.len() as u64 > chunk_bytes * CHUNKS as u64 {
            return Err(TooLarge {
                name,
                bytes: bytes.len() as u64,
                chunk_bytes,
            });
        }
        let mut chunks = bytes.chunks(per_chunk * stride);
        for k in 0..CHUNKS {
            let chunk = chunks.next().map(<[u8]>::to_vec).unwrap_or_default();
            resources.insert(chunk_name(name, k), chunk);
        }
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(primitives: usize, attributes: usize) -> BTreeMap<String, Vec<u8>> {
        let p = size_of::<GpuPrimitive>();
        let a = size_of::<GpuTriangleAttributes>();
        BTreeMap::from([
            ("primitives".to_string(), (0..primitives * p).map(|i| i as u8).collect()),
            (
                "attributes".to_string(),
                (0..attributes * a).map(|i| (i / 7) as u8).collect(),
            ),
            ("bvh".to_string(), vec![1; 64]),
        ])
    }

    #[test]
    fn geometry_within_one_binding_stays_whole() {
        let mut r = scene(10, 10);
        let before = r.clone();
        assert_eq!(split(&mut r, 48 * 10), Ok(false));
        assert_eq!(r, before);
    }

    #[test]
    fn chunks_hold_whole_elements_and_join_to_the_data() {
        let before = scene(10, 10);
        let mut r = before.clone();
        // 100 bytes a binding: 2 primitives (48 bytes) or 2 attributes (40 bytes) a chunk.
        assert!(split(&mut r, 100).is_err());
        let mut r = before.clone();
        // 250 bytes: 5 primitives, 6 attributes a chunk; 2 chunks each, 2 empty.
        assert_eq!(split(&mut r, 250), Ok(true));
        for (name, per) in [("primitives", 5 * 48), ("attributes", 6 * 40)] {
            let chunks: Vec<&[u8]> = (0..CHUNKS).map(|k| r[&chunk_name(name, k)].as_slice()).collect();
            assert_eq!(chunks[0].len(), per, "{name}: the first chunk is full");
            assert_eq!(chunks.concat(), before[name], "{name}: the chunks join to the data");
            assert!(chunks[2].is_empty() && chunks[3].is_empty());
        }
        assert_eq!(r["bvh"], before["bvh"]);
    }

    #[test]
    fn scenes_without_attributes_split_their_primitives_alone() {
        let mut r = scene(10, 0);
        assert_eq!(split(&mut r, 48 * 3), Ok(true));
        assert_eq!(r["primitives"].len(), 48 * 3);
        assert_eq!(r["primitives_3"].len(), 48);
        assert!((0..CHUNKS).all(|k| r[&chunk_name("attributes", k)].is_empty()));
    }

    #[test]
    fn too_much_for_every_chunk_names_the_resource() {
        let mut r = scene(10, 0);
        let e = split(&mut r, 48 * 2).unwrap_err();
        assert_eq!(e.name, "primitives");
        assert_eq!((e.bytes, e.chunk_bytes), (480, 96));
        assert!(e.to_string().contains("'primitives' buffer takes"));
    }
}
