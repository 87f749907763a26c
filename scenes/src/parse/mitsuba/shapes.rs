//! Shape geometry: `obj` (through `tobj`) and `ply` (through `ply-rs-bw`) meshes, and the
//! built-in `rectangle`, `disk`, `cube` and `sphere`, made in object space as Mitsuba defines
//! them and placed in the world by `to_world`. Texture coordinates follow Mitsuba's
//! convention, v = 0 at the image's top row: an OBJ's `vt` v is flipped, as Mitsuba does; a
//! PLY's u and v are taken as they are, as Mitsuba 3 does (checked by rendering the exported
//! Sponza in Mitsuba 3.9.1: with flipped v its mean came out 27% darker than lightgraph's).

use super::mesh::Mesh;
use super::xml::{Context, Props, Result};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// Segments around a disk's rim, and around a sphere tessellated into triangles (half as
/// many from pole to pole). Both meshes keep the analytic area, and every point of them lies
/// within 1e-4 of the radius from the circle or sphere (the sphere's vertices 6.3e-5 outside,
/// its face centres at most 8.8e-5 inside; the disk's rim vertices 5.0e-5 outside, its edge
/// midpoints 2.5e-5 inside).
pub const SEGMENTS: u32 = 256;

/// The object-space mesh of a shape of `kind` other than `sphere` (see [`sphere`]), with the
/// properties the kind reads; `None` for a kind this importer does not know. Meshes read
/// from files without normals get area-weighted vertex normals (as Mitsuba computes them).
pub fn mesh(ctx: &mut Context, props: &Props, kind: &str) -> Result<Option<Mesh>> {
    Ok(Some(match kind {
        "obj" => smoothed(obj(ctx, props)?),
        "ply" => smoothed(ply(ctx, props)?),
        "serialized" => serialized(ctx, props)?,
        "rectangle" => rectangle(),
        "disk" => disk(),
        "cube" => cube(),
        _ => return Ok(None),
    }))
}

/// `mesh` with area-weighted vertex normals when it has none.
fn smoothed(mut mesh: Mesh) -> Mesh {
    if mesh.normals.is_none() {
        mesh.smooth_normals();
    }
    mesh
}

/// Mitsuba's rectangle: [-1, 1]² in the plane z = 0, facing +Z, with Mitsuba's texture
/// coordinates ((x + 1) / 2, (y + 1) / 2).
pub fn rectangle() -> Mesh {
    let positions: Vec<Vec3> = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
        .map(|[x, y]| Vec3::new(x, y, 0.0))
        .to_vec();
    Mesh {
        uvs: Some(
            positions
                .iter()
                .map(|p| [(p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0])
                .collect(),
        ),
        normals: Some(vec![Vec3::Z; 4]),
        positions,
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Mitsuba's disk: the unit disk in the plane z = 0 facing +Z, as a fan of [`SEGMENTS`]
/// triangles whose rim lies a little outside the circle, so that the fan's area is π. Its
/// texture coordinates are Mitsuba's polar ones, (r, φ / 2π): each triangle has its own
/// centre vertex at its middle angle, and the rim's vertex at φ = 0 is repeated at 2π.
pub fn disk() -> Mesh {
    let n = SEGMENTS as f64;
    // The regular n-gon of circumradius k has the area n k² sin(2π / n) / 2.
    let k = (2.0 * PI / (n * (2.0 * PI / n).sin())).sqrt();
    let mut out = Mesh {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    let mut vertex = |p: Vec3, uv: [f64; 2]| {
        out.positions.push(p);
        out.normals.as_mut().unwrap().push(Vec3::Z);
        out.uvs.as_mut().unwrap().push(uv.map(|c| c as f32));
        out.positions.len() as u32 - 1
    };
    let rim: Vec<u32> = (0..=SEGMENTS)
        .map(|i| {
            let phi = 2.0 * PI * i as f64 / n;
            vertex(
                Vec3::new((k * phi.cos()) as f32, (k * phi.sin()) as f32, 0.0),
                [k, i as f64 / n],
            )
        })
        .collect();
    let fans: Vec<[u32; 3]> = (0..SEGMENTS as usize)
        .map(|i| [vertex(Vec3::ZERO, [0.0, (i as f64 + 0.5) / n]), rim[i], rim[i + 1]])
        .collect();
    out.indices = fans;
    out
}

/// Mitsuba's cube: [-1, 1]³ with outward faces (flat shaded), with Mitsuba's texture
/// coordinates: each face maps two of x, y, z, each as (c + 1) / 2 or (1 - c) / 2
/// ([`cube_uv`]).
pub fn cube() -> Mesh {
    let mut out = Mesh {
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // Two axes spanning the face, ordered so that u x v = n.
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let v = n.cross(u);
            let base = out.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = n + u * a + v * b;
                out.positions.push(p);
                out.uvs.as_mut().unwrap().push(cube_uv(axis, sign > 0.0, p));
            }
            out.indices
                .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
    }
    out
}

/// The texture coordinates of Mitsuba 3's cube at point `p` of the face normal to `axis` on
/// its `positive` side (read off Mitsuba 3.9.1's intersections: its cube is a mesh with these
/// per-face coordinates).
fn cube_uv(axis: usize, positive: bool, p: Vec3) -> [f32; 2] {
    let up = |c: f32| (c + 1.0) / 2.0;
    let down = |c: f32| (1.0 - c) / 2.0;
    match (axis, positive) {
        (0, true) => [up(p.y), down(p.z)],
        (0, false) => [up(p.y), up(p.z)],
        (1, true) => [down(p.x), down(p.z)],
        (1, false) => [up(p.z), up(p.x)],
        (2, true) => [up(p.y), up(p.x)],
        _ => [down(p.y), up(p.x)],
    }
}

/// A sphere as a latitude-longitude mesh of [`SEGMENTS`] x [`SEGMENTS`]/2 quads with
/// smooth normals and Mitsuba's texture coordinates (for emitting, textured and flipped spheres
/// and spheres under non-uniform scales; others stay analytic), its vertices pushed out radially so that its area is the sphere's, 4πr².
pub fn sphere(center: Vec3, radius: f32) -> Mesh {
    let (nu, nv) = (SEGMENTS, SEGMENTS / 2);
    let mut directions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=nv {
        let theta = PI * j as f64 / nv as f64;
        // Each pole's vertices at one position (sin π is not 0 in floating point either).
        let sin_theta = if j == 0 || j == nv { 0.0 } else { theta.sin() };
        for i in 0..=nu {
            // The seam's last column repeats the first's positions exactly (sin 2π is not
            // 0 in floating point), so that the mesh is closed (`model::enclosure`).
            let phi = 2.0 * PI * (i % nu) as f64 / nu as f64;
            directions.push(DVec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), theta.cos()));
            uvs.push([i as f32 / nu as f32, j as f32 / nv as f32]);
        }
    }
    let indices = lat_long_triangles(nu, nv);
    let unit_area: f64 = indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| directions[i as usize]);
            (b - a).cross(c - a).length() / 2.0
        })
        .sum();
    let scale = radius as f64 * (4.0 * PI / unit_area).sqrt();
    Mesh {
        positions: directions.iter().map(|&d| center + (d * scale).as_vec3()).collect(),
        normals: Some(directions.iter().map(|d| d.as_vec3()).collect()),
        uvs: Some(uvs),
        indices,
    }
}

/// The outward-facing triangles of a grid of `nu` + 1 by `nv` + 1 vertices (rows from the
/// +Z pole to the -Z pole), without the poles' degenerate ones.
fn lat_long_triangles(nu: u32, nv: u32) -> Vec<[u32; 3]> {
    let row = nu + 1;
    let mut out = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (j * row + i, j * row + i + 1, (j + 1) * row + i + 1, (j + 1) * row + i);
            if j > 0 {
                out.push([a, d, b]);
            }
            if j + 1 < nv {
                out.push([b, d, c]);
            }
        }
    }
    out
}

/// Mesh `shape_index` (default 0) of a `serialized` file; smooth normals unless the file has
/// normals or asks for face normals.
fn serialized(ctx: &mut Context, props: &Props) -> Result<Mesh> {
    let node = props.node();
    let index = match props.integer(ctx, "shape_index")? {
        None => 0,
        Some(i) if i >= 0 => i as u64,
        Some(i) => return Err(ctx.error(node, format!("shape_index {i} is negative"))),
    };
    let path = props.file(ctx, "a serialized shape")?;
    let in_file = |e: String| ctx.error(node, format!("{}: {e}", path.display()));
    let bytes = std::fs::read(&path).map_err(|e| in_file(e.to_string()))?;
    let read = super::serialized::parse(&bytes, index).map_err(in_file)?;
    Ok(if read.face_normals {
        Mesh {
            normals: None,
            ..read.mesh
        }
    } else {
        smoothed(read.mesh)
    })
}

fn obj(ctx: &mut Context, props: &Props) -> Result<Mesh> {
    let node = props.node();
    let path = props.file(ctx, "an obj shape")?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj(&path, &options).map_err(|e| ctx.error(node, format!("{}: {e}", path.display())))?;
    let mut out = Mesh::default();
    let (mut with_normals, mut with_uvs) = (true, true);
    for model in &models {
        let m = &model.mesh;
        let base = out.positions.len() as u32;
        let count = m.positions.len() / 3;
        out.positions
            .extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        with_normals &= m.normals.len() == count * 3;
        with_uvs &= m.texcoords.len() == count * 2;
        let normals = out.normals.get_or_insert_with(Vec::new);
        normals.extend(
            m.normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or_zero()),
        );
        let uvs = out.uvs.get_or_insert_with(Vec::new);
        uvs.extend(m.texcoords.chunks_exact(2).map(|t| [t[0], 1.0 - t[1]]));
        for t in m.indices.chunks_exact(3) {
            if let Some(&bad) = t.iter().find(|&&i| i as usize >= count) {
                return Err(ctx.error(node, format!("{}: a face uses vertex {bad} of {count}", path.display())));
            }
            out.indices.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    if !with_normals {
        out.normals = None;
    }
    if !with_uvs {
        out.uvs = None;
    }
    Ok(out)
}

fn ply(ctx: &mut Context, props: &Props) -> Result<Mesh> {
    use ply_rs_bw::ply::Property;
    let node = props.node();
    let path = props.file(ctx, "a ply shape")?;
    let shown = path.display().to_string();
    let mut file = std::fs::File::open(&path).map_err(|e| ctx.error(node, format!("{shown}: {e}")))?;
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut file)
        .map_err(|e| ctx.error(node, format!("{shown}: {e}")))?;
    let empty = Vec::new();
    let vertices = ply.payload.get("vertex").unwrap_or(&empty);
    let scalar = |v: &ply_rs_bw::ply::DefaultElement, key: &str| v.get(key).and_then(Property::to_f32_lossy);
    let mut out = Mesh::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for v in vertices {
        let p = ["x", "y", "z"].map(|k| scalar(v, k));
        let [Some(x), Some(y), Some(z)] = p else {
            return Err(ctx.error(node, format!("{shown}: a vertex has no x, y and z")));
        };
        out.positions.push(Vec3::new(x, y, z));
        if let [Some(x), Some(y), Some(z)] = ["nx", "ny", "nz"].map(|k| scalar(v, k)) {
            normals.push(Vec3::new(x, y, z).normalize_or_zero());
        }
        let u = scalar(v, "u")
            .or_else(|| scalar(v, "s"))
            .or_else(|| scalar(v, "texture_u"));
        let w = scalar(v, "v")
            .or_else(|| scalar(v, "t"))
            .or_else(|| scalar(v, "texture_v"));
        if let (Some(u), Some(w)) = (u, w) {
            uvs.push([u, w]);
        }
    }
    let count = out.positions.len();
    for face in ply.payload.get("face").unwrap_or(&empty) {
        let list = face.get("vertex_indices").or_else(|| face.get("vertex_index"));
        let indices: Vec<i64> = match list {
            Some(Property::ListInt(v)) => v.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUInt(v)) => v.iter().map(|&i| i as i64).collect(),
            Some(Property::ListShort(v)) => v.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUShort(v)) => v.iter().map(|&i| i as i64).collect(),
            Some(Property::ListChar(v)) => v.iter().map(|&i| i as i64).collect(),
            Some(Property::ListUChar(v)) => v.iter().map(|&i| i as i64).collect(),
            _ => return Err(ctx.error(node, format!("{shown}: a face has no integer vertex_indices"))),
        };
        if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= count) {
            return Err(ctx.error(node, format!("{shown}: a face uses vertex {bad} of {count}")));
        }
        // Polygons as fans.
        for k in 2..indices.len() {
            out.indices
                .push([indices[0] as u32, indices[k - 1] as u32, indices[k] as u32]);
        }
    }
    out.normals = (normals.len() == count).then_some(normals);
    out.uvs = (uvs.len() == count).then_some(uvs);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    /// The area of `m`, summed in f64.
    fn area(m: &Mesh) -> f64 {
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    }

    /// Every triangle's winding normal points away from `inside` (or along `+Z` for flat
    /// shapes when `inside` is None).
    fn faces_out(m: &Mesh, inside: Option<Vec3>) -> bool {
        m.indices.iter().all(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            match inside {
                Some(o) => n.dot((a + b + c) / 3.0 - o) > 0.0,
                None => n.z > 0.0,
            }
        })
    }

    /// Every vertex and every triangle's centre (and edge midpoint) of `m`.
    fn points(m: &Mesh) -> impl Iterator<Item = DVec3> + '_ {
        m.indices.iter().flat_map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            [a, b, c, (a + b + c) / 3.0, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0]
        })
    }

    /// The texture coordinates at `p` on the triangle of `m` that holds it.
    fn uv_at(m: &Mesh, p: Vec3) -> [f32; 2] {
        let uvs = m.uvs.as_ref().unwrap();
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            let (e1, e2, d) = (b - a, c - a, p.as_dvec3() - a);
            let n = e1.cross(e2);
            if d.dot(n).abs() > 1e-3 * n.length() {
                continue;
            }
            let w1 = d.cross(e2).dot(n) / n.length_squared();
            let w2 = e1.cross(d).dot(n) / n.length_squared();
            if w1 >= -1e-9 && w2 >= -1e-9 && w1 + w2 <= 1.0 + 1e-9 {
                let [ua, ub, uc] = t.map(|i| uvs[i as usize]);
                return [0, 1].map(|k| ((1.0 - w1 - w2) * ua[k] as f64 + w1 * ub[k] as f64 + w2 * uc[k] as f64) as f32);
            }
        }
        panic!("no triangle holds {p}");
    }

    #[test]
    fn texture_coordinates_are_mitsubas() {
        // The uv of rays' intersections with Mitsuba 3.9.1's shapes (scalar_rgb), at these
        // points of their object space.
        let flat = [
            (rectangle(), [0.5, 0.9, 0.0], [0.75, 0.95]),
            (rectangle(), [0.5, -0.9, 0.0], [0.75, 0.05]),
            (disk(), [0.5, 0.3, 0.0], [0.583095, 0.0860105]),
            (cube(), [1.0, 0.2, 0.6], [0.6, 0.2]),
            (cube(), [1.0, -0.4, 0.1], [0.3, 0.45]),
            (cube(), [-1.0, 0.2, 0.6], [0.6, 0.8]),
            (cube(), [-1.0, -0.4, 0.1], [0.3, 0.55]),
            (cube(), [0.6, 1.0, 0.2], [0.2, 0.4]),
            (cube(), [0.1, 1.0, -0.4], [0.45, 0.7]),
            (cube(), [0.6, -1.0, 0.2], [0.6, 0.8]),
            (cube(), [0.1, -1.0, -0.4], [0.3, 0.55]),
            (cube(), [0.2, 0.6, 1.0], [0.8, 0.6]),
            (cube(), [-0.4, 0.1, 1.0], [0.55, 0.3]),
            (cube(), [0.2, 0.6, -1.0], [0.2, 0.6]),
            (cube(), [-0.4, 0.1, -1.0], [0.45, 0.3]),
        ];
        for (mesh, p, expected) in flat {
            let got = uv_at(&mesh, Vec3::from(p));
            // The disk's fan interpolates the angle across each triangle from its middle at the
            // centre: within half a segment, 1/512, times the centre's weight.
            let tolerance = if mesh.positions.len() > 24 { 1e-3 } else { 1e-5 };
            assert!(
                (got[0] - expected[0]).abs() < tolerance && (got[1] - expected[1]).abs() < tolerance,
                "at {p:?}: {got:?}, Mitsuba {expected:?}"
            );
        }
        // The sphere's mesh interpolates Mitsuba's (azimuth, polar angle) linearly.
        let s = sphere(Vec3::ZERO, 1.0);
        let got = uv_at(&s, Vec3::new(0.3, 0.4, 0.866025) * 1.0001);
        assert!(
            (got[0] - 0.147584).abs() < 1e-3 && (got[1] - 0.166667).abs() < 1e-3,
            "{got:?}"
        );
    }

    #[test]
    fn rectangle_and_disk_lie_in_z0_facing_plus_z() {
        let r = rectangle();
        assert_eq!(area(&r), 4.0);
        assert!(faces_out(&r, None));
        assert_eq!(r.uvs.as_ref().unwrap()[0], [0.0, 0.0]);
        let d = disk();
        assert!((area(&d) - PI).abs() < 1e-4 * PI, "area {}", area(&d));
        assert!(faces_out(&d, None));
        // The rim: vertices and edge midpoints within 1e-4 of the unit circle.
        let rim = points(&d).map(|p| p.length()).filter(|&l| l > 0.99);
        let worst = rim.map(|l| (l - 1.0).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-4, "the rim strays {worst} from the circle");
    }

    #[test]
    fn cube_and_sphere_face_outward() {
        let c = cube();
        assert_eq!((c.indices.len(), area(&c)), (12, 24.0));
        assert!(faces_out(&c, Some(Vec3::ZERO)));
        let center = Vec3::new(1.0, 2.0, 3.0);
        let s = sphere(center, 2.0);
        assert!(faces_out(&s, Some(center)));
        let want = 16.0 * PI;
        assert!((area(&s) - want).abs() < 1e-4 * want, "area {} for {want}", area(&s));
        let c = center.as_dvec3();
        let worst = points(&s).map(|p| ((p - c).length() - 2.0).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-4 * 2.0, "the mesh strays {worst} from the sphere");
    }

    #[test]
    fn sphere_and_cube_meshes_are_closed() {
        // Every edge, by its corners' positions, is used twice: they can enclose a medium.
        for (name, mesh) in [("sphere", sphere(Vec3::ZERO, 1.0)), ("cube", cube())] {
            let mut uses = std::collections::HashMap::new();
            for t in &mesh.indices {
                let p = t.map(|i| mesh.positions[i as usize].to_array().map(|c| (c + 0.0).to_bits()));
                for k in 0..3 {
                    let (a, b) = (p[k], p[(k + 1) % 3]);
                    *uses.entry(if a < b { (a, b) } else { (b, a) }).or_insert(0) += 1;
                }
            }
            let open = uses.values().filter(|&&n| n % 2 == 1).count();
            assert_eq!(open, 0, "{name}: {open} open edges");
        }
    }

    #[test]
    fn placing_transforms_points_and_normals_and_keeps_facing_under_mirrors() {
        let m = Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let r = rectangle().placed(m, false);
        assert_eq!(r.positions[2], Vec3::new(2.0, 1.0, 5.0));
        assert!(faces_out(&r, None));
        let mirrored = rectangle().placed(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)), false);
        assert!(faces_out(&mirrored, None));
        let flipped = rectangle().placed(Mat4::IDENTITY, true);
        assert!(flipped.indices.iter().all(|t| {
            let [a, b, c] = t.map(|i| flipped.positions[i as usize]);
            (b - a).cross(c - a).z < 0.0
        }));
        assert_eq!(flipped.normals.unwrap()[0], Vec3::NEG_Z);
    }

    #[test]
    fn smooth_normals_average_the_faces() {
        let mut c = cube();
        c.smooth_normals();
        // Each corner of a face belongs to that face only (faces do not share vertices).
        assert_eq!(c.normals.unwrap()[0], Vec3::NEG_X);
    }
}
