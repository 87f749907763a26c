//! Mitsuba's `serialized` meshes (the binary format of Mitsuba 0.4 to 3): a header (u16
//! 0x041C, u16 version 3 or 4), then a zlib stream holding flags, the name (version 4), the
//! vertex and triangle counts, positions, normals, texture coordinates, colours and the
//! triangles' vertex indices, all little-endian. A file of several meshes concatenates them
//! and ends with a dictionary: each mesh's file offset (u64 in version 4, u32 in version 3),
//! then the mesh count (u32).

use super::mesh::Mesh;
use flate2::read::ZlibDecoder;
use glam::Vec3;
use std::io::Read;

/// The first u16 of every mesh.
const MAGIC: u16 = 0x041C;
/// Flag: the mesh has vertex normals.
const HAS_NORMALS: u64 = 0x0001;
/// Flag: the mesh has texture coordinates.
const HAS_UVS: u64 = 0x0002;
/// Flag: the mesh has vertex colours.
const HAS_COLORS: u64 = 0x0008;
/// Flag: the mesh is to be shaded with face normals.
const FACE_NORMALS: u64 = 0x0010;
/// Flag: the arrays hold f64s (otherwise f32s).
const DOUBLE_PRECISION: u64 = 0x2000;

/// One mesh of a serialized file.
#[derive(Debug, Clone, PartialEq)]
pub struct Serialized {
    /// The triangles, with the file's normals and texture coordinates (as stored: v = 0 at
    /// the image's top row, Mitsuba's convention).
    pub mesh: Mesh,
    /// The mesh asks for face normals (flag 0x0010, as the `face_normals` property).
    pub face_normals: bool,
}

/// Mesh `index` of the serialized file `bytes`; an error says what is wrong (the caller
/// names the file).
pub fn parse(bytes: &[u8], index: u64) -> Result<Serialized, String> {
    let version = header(bytes, 0)?;
    let start = mesh_offset(bytes, version, index)?;
    if start != 0 {
        let other = header(bytes, start)?;
        if other != version {
            return Err(format!("mesh {index} has version {other}, the file {version}"));
        }
    }
    let compressed = &bytes[start + 4..];
    mesh(&mut ZlibDecoder::new(compressed), version)
}

/// The version of the mesh header at byte `at`.
fn header(bytes: &[u8], at: usize) -> Result<u16, String> {
    let word = |i: usize| bytes.get(at + i..at + i + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    match (word(0), word(2)) {
        (Some(MAGIC), Some(v @ (3 | 4))) => Ok(v),
        (Some(MAGIC), Some(v)) => Err(format!("version {v} is not 3 or 4")),
        (Some(m), Some(_)) => Err(format!(
            "no serialized mesh at byte {at} (it starts with 0x{m:04X}, not 0x{MAGIC:04X})"
        )),
        _ => Err(format!("the file ends at byte {} inside a header", bytes.len())),
    }
}

/// Where mesh `index` starts: 0 for the first, else from the end-of-file dictionary.
fn mesh_offset(bytes: &[u8], version: u16, index: u64) -> Result<usize, String> {
    if index == 0 {
        return Ok(0);
    }
    let count_at = bytes.len().checked_sub(4).ok_or("the file has no mesh dictionary")?;
    let count = le(&bytes[count_at..]);
    if index >= count {
        return Err(format!("shape_index {index} is not below the file's {count} meshes"));
    }
    let width = if version == 4 { 8 } else { 4 };
    let back = (count - index) * width;
    let at = (count_at as u64)
        .checked_sub(back)
        .ok_or_else(|| format!("the dictionary of {count} meshes does not fit in the file"))? as usize;
    let offset = le(&bytes[at..at + width as usize]);
    match usize::try_from(offset) {
        Ok(o) if o < at => Ok(o),
        _ => Err(format!("mesh {index}'s offset {offset} lies outside the file")),
    }
}

/// Reads one mesh from its decompressed stream.
fn mesh(r: &mut impl Read, version: u16) -> Result<Serialized, String> {
    let flags = le(&exact(r, 4, "the flags")?);
    if version == 4 {
        skip_name(r)?;
    }
    let vertices = le(&exact(r, 8, "the vertex count")?);
    let triangles = le(&exact(r, 8, "the triangle count")?);
    if vertices > u32::MAX as u64 {
        return Err(format!("{vertices} vertices: more than 2^32 are not supported"));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let positions = floats(r, vertices, 3, double, "the positions")?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(floats(r, vertices, 3, double, "the normals")?)
    } else {
        None
    };
    let uvs = if flags & HAS_UVS != 0 {
        Some(floats(r, vertices, 2, double, "the texture coordinates")?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        floats(r, vertices, 3, double, "the vertex colours")?;
    }
    let indices = indices(r, triangles, vertices)?;
    stream_end(r)?;
    let vec3s = |v: Vec<f32>| {
        v.chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect::<Vec<_>>()
    };
    Ok(Serialized {
        mesh: Mesh {
            positions: vec3s(positions),
            indices,
            normals: normals.map(|n| vec3s(n).into_iter().map(Vec3::normalize_or_zero).collect()),
            uvs: uvs.map(|t| t.chunks_exact(2).map(|t| [t[0], t[1]]).collect()),
        },
        face_normals: flags & FACE_NORMALS != 0,
    })
}

/// The little-endian unsigned integer of `bytes` (at most 8).
fn le(bytes: &[u8]) -> u64 {
    bytes.iter().rev().fold(0, |v, &b| v << 8 | b as u64)
}

/// Exactly `n` bytes of `r` (read as they arrive: a corrupt count allocates no more than the
/// stream holds); `what` names them when the stream ends early.
fn exact(r: &mut impl Read, n: u64, what: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    r.take(n)
        .read_to_end(&mut out)
        .map_err(|e| format!("{what}: the compressed data is cut short or corrupt ({e})"))?;
    if (out.len() as u64) < n {
        return Err(format!("the file ends inside {what} ({} of {n} bytes)", out.len()));
    }
    Ok(out)
}

/// Checks that the stream ends after the triangles (with its checksum).
fn stream_end(r: &mut impl Read) -> Result<(), String> {
    match r.read(&mut [0u8; 1]) {
        Ok(0) => Ok(()),
        Ok(_) => Err("more data follows the triangles".into()),
        Err(e) => Err(format!(
            "after the triangles: the compressed data is cut short or corrupt ({e})"
        )),
    }
}

/// Skips the mesh's null-terminated name.
fn skip_name(r: &mut impl Read) -> Result<(), String> {
    loop {
        if exact(r, 1, "the mesh name")?[0] == 0 {
            return Ok(());
        }
    }
}

/// `count` x `dim` floats (f64 when `double`, else f32), as f32s.
fn floats(r: &mut impl Read, count: u64, dim: u64, double: bool, what: &str) -> Result<Vec<f32>, String> {
    let size = if double { 8 } else { 4 };
    let n = count
        .checked_mul(dim * size)
        .ok_or_else(|| format!("{what}: {count} vertices overflow"))?;
    let bytes = exact(r, n, what)?;
    Ok(if double {
        bytes.chunks_exact(8).map(|b| f64::from_bits(le(b)) as f32).collect()
    } else {
        bytes.chunks_exact(4).map(|b| f32::from_bits(le(b) as u32)).collect()
    })
}

/// `triangles` triangles of u32 vertex indices, each below `vertices`.
fn indices(r: &mut impl Read, triangles: u64, vertices: u64) -> Result<Vec<[u32; 3]>, String> {
    let n = triangles
        .checked_mul(12)
        .ok_or_else(|| format!("{triangles} triangles overflow"))?;
    let bytes = exact(r, n, "the triangles")?;
    let mut out = Vec::with_capacity(bytes.len() / 12);
    for t in bytes.chunks_exact(12) {
        let i: [u32; 3] = std::array::from_fn(|k| le(&t[4 * k..4 * k + 4]) as u32);
        if let Some(bad) = i.iter().find(|&&i| i as u64 >= vertices) {
            return Err(format!("triangle {} uses vertex {bad} of {vertices}", out.len()));
        }
        out.push(i);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::{Compression, write::ZlibEncoder};
    use std::io::Write;

    /// A mesh to write: f64 values, written as f64 or f32.
    #[derive(Default)]
    struct Part {
        positions: Vec<[f64; 3]>,
        normals: Option<Vec<[f64; 3]>>,
        uvs: Option<Vec<[f64; 2]>>,
        colors: bool,
        triangles: Vec<[u32; 3]>,
        double: bool,
        face_normals: bool,
    }

    /// A tetrahedron's corners and faces.
    fn tetrahedron() -> Part {
        Part {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ..Default::default()
        }
    }

    /// The compressed body of `part` (the layout of Mitsuba's format documentation).
    fn body(version: u16, part: &Part) -> Vec<u8> {
        let mut raw = Vec::new();
        let flag = |on: bool, bit: u32| if on { bit } else { 0 };
        let flags = flag(part.normals.is_some(), 0x0001)
            | flag(part.uvs.is_some(), 0x0002)
            | flag(part.colors, 0x0008)
            | flag(part.face_normals, 0x0010)
            | if part.double { 0x2000 } else { 0x1000 };
        raw.extend(flags.to_le_bytes());
        if version == 4 {
            raw.extend(b"a mesh\0");
        }
        raw.extend((part.positions.len() as u64).to_le_bytes());
        raw.extend((part.triangles.len() as u64).to_le_bytes());
        let mut values = |v: &[f64]| {
            for &x in v {
                if part.double {
                    raw.extend(x.to_le_bytes());
                } else {
                    raw.extend((x as f32).to_le_bytes());
                }
            }
        };
        values(part.positions.as_flattened());
        if let Some(n) = &part.normals {
            values(n.as_flattened());
        }
        if let Some(t) = &part.uvs {
            values(t.as_flattened());
        }
        if part.colors {
            values(&vec![0.5; part.positions.len() * 3]);
        }
        for i in part.triangles.as_flattened() {
            raw.extend(i.to_le_bytes());
        }
        let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
        z.write_all(&raw).unwrap();
        z.finish().unwrap()
    }

    /// A serialized file of `parts`, with the end-of-file dictionary.
    fn file(version: u16, parts: &[Part]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for part in parts {
            offsets.push(out.len() as u64);
            out.extend(0x041Cu16.to_le_bytes());
            out.extend(version.to_le_bytes());
            out.extend(body(version, part));
        }
        for o in offsets {
            if version == 4 {
                out.extend(o.to_le_bytes());
            } else {
                out.extend((o as u32).to_le_bytes());
            }
        }
        out.extend((parts.len() as u32).to_le_bytes());
        out
    }

    #[test]
    fn single_precision_with_normals_and_uvs() {
        let part = Part {
            normals: Some(vec![
                [0.0, 0.0, -2.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ]),
            uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.25, 0.75]]),
            ..tetrahedron()
        };
        let read = parse(&file(4, &[part]), 0).unwrap();
        let m = &read.mesh;
        assert_eq!(m.positions[1], Vec3::X);
        assert_eq!(m.indices, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        assert_eq!(m.normals.as_ref().unwrap()[0], Vec3::NEG_Z, "normals come out unit");
        assert_eq!(m.uvs.as_ref().unwrap()[3], [0.25, 0.75]);
        assert!(!read.face_normals);
    }

    #[test]
    fn double_precision_without_normals_or_uvs_skipping_colours() {
        for version in [3, 4] {
            let part = Part {
                positions: vec![[0.1, 0.2, 0.3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                double: true,
                colors: true,
                face_normals: true,
                ..tetrahedron()
            };
            let read = parse(&file(version, &[part]), 0).unwrap();
            assert_eq!(read.mesh.positions[0], Vec3::new(0.1, 0.2, 0.3));
            assert_eq!(read.mesh.indices.len(), 4);
            assert_eq!((read.mesh.normals, read.mesh.uvs), (None, None));
            assert!(read.face_normals);
        }
    }

    #[test]
    fn shape_index_picks_a_mesh_of_several() {
        for version in [3, 4] {
            let second = Part {
                positions: vec![[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]],
                triangles: vec![[0, 1, 2]],
                ..Default::default()
            };
            let bytes = file(version, &[tetrahedron(), second]);
            assert_eq!(parse(&bytes, 0).unwrap().mesh.indices.len(), 4);
            let read = parse(&bytes, 1).unwrap();
            assert_eq!(
                (read.mesh.positions[0], read.mesh.indices.len()),
                (Vec3::new(5.0, 0.0, 0.0), 1)
            );
            let e = parse(&bytes, 2).unwrap_err();
            assert!(e.contains("shape_index 2 is not below the file's 2 meshes"), "{e}");
        }
    }

    #[test]
    fn truncated_and_corrupt_files_are_errors() {
        let bytes = file(4, &[tetrahedron(), tetrahedron()]);
        // Two meshes of the same size, then two u64 offsets and the count.
        let first_end = (bytes.len() - 20) / 2;
        for len in 0..bytes.len() {
            // The first mesh needs no dictionary: whole, it reads; cut short, it does not.
            assert_eq!(parse(&bytes[..len], 0).is_ok(), len >= first_end, "{len}");
            let _ = parse(&bytes[..len], 1);
        }
        let e = parse(&bytes[..30], 0).unwrap_err();
        assert!(e.contains("cut short or corrupt"), "{e}");
        let e = parse(&[0x1C, 0x04, 5, 0], 0).unwrap_err();
        assert_eq!(e, "version 5 is not 3 or 4");
        let e = parse(b"ply\nformat", 0).unwrap_err();
        assert!(e.contains("not 0x041C"), "{e}");
        // Flipping any byte of the compressed data gives an error or a mesh, never a panic.
        for i in 4..bytes.len() {
            let mut bad = bytes.clone();
            bad[i] ^= 0x5a;
            let _ = parse(&bad, 0);
            let _ = parse(&bad, 1);
        }
        let part = Part {
            triangles: vec![[0, 1, 9]],
            ..tetrahedron()
        };
        let e = parse(&file(3, &[part]), 0).unwrap_err();
        assert_eq!(e, "triangle 0 uses vertex 9 of 4");
    }

    #[test]
    fn an_import_names_the_element_and_the_mesh_file() {
        let dir = std::env::temp_dir().join(format!("lightgraph-serialized-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes = file(4, &[tetrahedron()]);
        std::fs::write(dir.join("good.serialized"), &bytes).unwrap();
        std::fs::write(dir.join("cut.serialized"), &bytes[..bytes.len() / 2]).unwrap();
        let scene = |name: &str, extra: &str| {
            format!(
                "<scene version=\"0.5.0\">\n<shape type=\"serialized\">\n<string name=\"filename\" value=\"{name}\"/>{extra}\n\
                 </shape>\n<emitter type=\"constant\"/></scene>"
            )
        };
        let imported = super::super::parse("s.xml", &dir, &scene("good.serialized", "")).unwrap();
        let crate::model::Shape::Mesh { indices, normals, .. } = &imported.scene.shapes[0] else {
            panic!("not a mesh")
        };
        assert_eq!(indices.len(), 4);
        assert!(normals.is_some(), "smooth normals where the file has none");
        let flat = super::super::parse(
            "s.xml",
            &dir,
            &scene("good.serialized", "<boolean name=\"faceNormals\" value=\"true\"/>"),
        )
        .unwrap();
        assert!(matches!(
            &flat.scene.shapes[0],
            crate::model::Shape::Mesh { normals: None, .. }
        ));
        let e = super::super::parse("s.xml", &dir, &scene("cut.serialized", "")).unwrap_err();
        let cut = dir.join("cut.serialized").display().to_string();
        assert!(
            e.to_string().starts_with(&format!(
                "s.xml:2:1: <shape type=\"serialized\">: {cut}: the flags: the compressed data is cut short"
            )),
            "{e}"
        );
        let e = super::super::parse("s.xml", &dir, &scene("gone.serialized", "")).unwrap_err();
        assert!(e.to_string().contains("gone.serialized' does not exist"), "{e}");
        let e = super::super::parse(
            "s.xml",
            &dir,
            &scene("good.serialized", "<integer name=\"shape_index\" value=\"-1\"/>"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("shape_index -1 is negative"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
