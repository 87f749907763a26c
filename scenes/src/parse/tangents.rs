//! Tangent frames for normal maps where a glTF mesh gives none, as glTF asks: MikkTSpace
//! (`bevy_mikktspace`, a safe Rust port that gives the C reference's results) in the normal
//! map's texture space with v pointing up the image. glTF's v runs down the image, so
//! MikkTSpace sees (u, 1 - v): its bitangent then points to the image's top, the +Y of glTF's
//! normal textures.

use crate::model::CornerTangents;
use glam::Vec3;

/// The tangent frame of a corner whose tangent is unknown (a degenerate triangle with no
/// neighbour to borrow from): any unit vector perpendicular to its normal `n`, w = 1.
pub fn any_tangent(n: Vec3) -> [f32; 4] {
    let t = n.normalize_or(Vec3::Z).any_orthonormal_vector();
    [t.x, t.y, t.z, 1.0]
}

/// MikkTSpace's tangents of the triangles `indices` over `positions` and texture coordinates
/// `uvs` (glTF's, v down), with vertex `normals`, or each triangle's own normal without them
/// (flat shading).
pub fn generate(
    positions: &[[f32; 3]],
    indices: &[[u32; 3]],
    uvs: &[[f32; 2]],
    normals: Option<&[[f32; 3]]>,
) -> Result<Vec<CornerTangents>, String> {
    let mut mesh = Mesh {
        positions,
        indices,
        uvs,
        normals,
        tangents: vec![[[0.0; 4]; 3]; indices.len()],
    };
    bevy_mikktspace::generate_tangents(&mut mesh).map_err(|e| format!("MikkTSpace failed: {e:?}"))?;
    Ok(mesh.tangents)
}

/// A triangle mesh as MikkTSpace reads it, and the tangents it writes.
struct Mesh<'a> {
    positions: &'a [[f32; 3]],
    indices: &'a [[u32; 3]],
    uvs: &'a [[f32; 2]],
    normals: Option<&'a [[f32; 3]]>,
    tangents: Vec<CornerTangents>,
}

impl Mesh<'_> {
    fn vertex(&self, face: usize, corner: usize) -> usize {
        self.indices[face][corner] as usize
    }

    /// The unit normal of triangle `face` by its winding.
    fn face_normal(&self, face: usize) -> Vec3 {
        let p = self.indices[face].map(|i| Vec3::from_array(self.positions[i as usize]));
        (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
    }
}

impl bevy_mikktspace::Geometry for Mesh<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)]
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match self.normals {
            Some(n) => n[self.vertex(face, vert)],
            None => self.face_normal(face).to_array(),
        }
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let [u, v] = self.uvs[self.vertex(face, vert)];
        [u, 1.0 - v]
    }

    fn set_tangent(&mut self, tangent: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        self.tangents[face][vert] = match tangent {
            Some(t) => t.tangent_encoded(),
            None => any_tangent(Vec3::from_array(self.normal(face, vert))),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Positions, triangles and texture coordinates.
    type Mesh = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<[f32; 2]>);

    /// A unit square in the xz-plane facing +y (two triangles), u along +x and glTF's v along
    /// `v_axis` (±z).
    fn square(v_axis: f32) -> Mesh {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
        let uvs = positions
            .iter()
            .map(|p| [p[0], if v_axis > 0.0 { p[2] } else { 1.0 - p[2] }])
            .collect();
        // Winding (0, 2, 1): (p2 - p0) x (p1 - p0) = (1, 0, 1) x (1, 0, 0) = +y.
        (positions, vec![[0, 2, 1], [0, 3, 2]], uvs)
    }

    fn assert_tangents(tangents: &[CornerTangents], expected: [f32; 4]) {
        for t in tangents.iter().flatten() {
            let d: f32 = t.iter().zip(expected).map(|(a, b)| (a - b).abs()).sum();
            assert!(d < 1e-5, "{t:?}, expected {expected:?}");
        }
    }

    #[test]
    fn the_tangent_follows_u_and_the_bitangent_the_image_up() {
        // glTF's v along +z: the image's top (v = 0) lies towards -z, where the bitangent
        // must point; n x t = y x x = -z, so w = +1.
        let (p, i, uv) = square(1.0);
        let normals = [[0.0, 1.0, 0.0]; 4];
        assert_tangents(&generate(&p, &i, &uv, Some(&normals)).unwrap(), [1.0, 0.0, 0.0, 1.0]);
        // The same without vertex normals: the triangles' own.
        assert_tangents(&generate(&p, &i, &uv, None).unwrap(), [1.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn a_texture_mirrored_along_v_flips_the_handedness() {
        // glTF's v along -z: the image's top lies towards +z, which is -(n x t).
        let (p, i, uv) = square(-1.0);
        assert_tangents(&generate(&p, &i, &uv, None).unwrap(), [1.0, 0.0, 0.0, -1.0]);
    }

    #[test]
    fn a_degenerate_texture_mapping_gets_a_tangent_perpendicular_to_the_normal() {
        let (p, i, _) = square(1.0);
        let tangents = generate(&p, &i, &[[0.5, 0.5]; 4], None).unwrap();
        for t in tangents.iter().flatten() {
            let v = Vec3::new(t[0], t[1], t[2]);
            assert!((v.length() - 1.0).abs() < 1e-5 && v.y.abs() < 1e-5, "{t:?}");
        }
    }
}
