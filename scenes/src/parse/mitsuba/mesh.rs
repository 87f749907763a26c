//! The triangle mesh that every shape kind is made into ([`super::shapes`] and
//! [`super::serialized`] meshes alike), placed in the world by its transform.

use glam::{Mat3, Mat4, Vec3};

/// A triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Three vertex indices per triangle, facing by the right-hand rule.
    pub indices: Vec<[u32; 3]>,
    /// Unit shading normals per vertex (none: flat shading).
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates per vertex.
    pub uvs: Option<Vec<[f32; 2]>>,
}

impl Mesh {
    /// The mesh placed by `m`: normals by its inverse transpose, and the winding reversed by a
    /// mirroring `m` (so triangles keep facing as authored) or by `flip` (Mitsuba's
    /// `flip_normals`, which also turns the normals over).
    pub fn placed(mut self, m: Mat4, flip: bool) -> Mesh {
        let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
        let sign = if flip { -1.0 } else { 1.0 };
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if let Some(normals) = &mut self.normals {
            for n in normals {
                *n = (normal_matrix * *n).normalize_or_zero() * sign;
            }
        }
        if (m.determinant() < 0.0) != flip {
            for t in &mut self.indices {
                t.swap(1, 2);
            }
        }
        self
    }

    /// Area-weighted vertex normals (Mitsuba computes these for meshes without normals).
    pub fn smooth_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.indices {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                normals[i as usize] += n;
            }
        }
        self.normals = Some(normals.into_iter().map(Vec3::normalize_or_zero).collect());
    }
}
