//! The compiled scene as the light-transport graphs' external resources, and the camera for
//! an image size.

use super::compile::CompiledScene;
use crate::gpu::GpuCamera;
use crate::model::framing::default_camera;
use crate::model::{FovAxis, Look, Scene};
use glam::Vec3;
use std::collections::BTreeMap;

impl CompiledScene {
    /// The camera for an image of `width` x `height` pixels.
    pub fn camera(scene: &Scene, width: u32, height: u32) -> GpuCamera {
        let c = &scene.camera.clone().unwrap_or_else(|| default_camera(scene));
        let position = Vec3::from(c.position);
        let forward = match c.look {
            Look::Forward(d) => Vec3::from(d),
            Look::Target(t) => Vec3::from(t) - position,
        }
        .normalize();
        let right = forward.cross(Vec3::from(c.up)).normalize();
        let up = right.cross(forward);
        let t = (c.fov_degrees.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let horizontal = match c.fov_axis {
            FovAxis::Horizontal => true,
            FovAxis::Vertical => false,
            FovAxis::Smaller => width <= height,
        };
        let (tx, ty) = if horizontal { (t, t / aspect) } else { (t * aspect, t) };
        GpuCamera {
            position: position.into(),
            width: width as f32,
            forward: forward.into(),
            height: height as f32,
            right: (right * tx).into(),
            lens_radius: c.lens.map_or(0.0, |l| l.aperture_radius),
            up: (up * ty).into(),
            focus_distance: c.lens.map_or(0.0, |l| l.focus_distance),
        }
    }

    /// The external resources of the light-transport graphs, by resource name.
    pub fn resources(&self, camera: &GpuCamera) -> BTreeMap<String, Vec<u8>> {
        let mut out = BTreeMap::new();
        out.insert("scene".to_string(), bytemuck::bytes_of(&self.info).to_vec());
        out.insert("camera".to_string(), bytemuck::bytes_of(camera).to_vec());
        out.insert(
            "primitives".to_string(),
            bytemuck::cast_slice(&self.primitives).to_vec(),
        );
        out.insert("bvh".to_string(), self.bvh.clone());
        out.insert("materials".to_string(), bytemuck::cast_slice(&self.materials).to_vec());
        out.insert("lights".to_string(), bytemuck::cast_slice(&self.lights).to_vec());
        out.insert(
            "light_alias".to_string(),
            bytemuck::cast_slice(&self.light_alias).to_vec(),
        );
        out.insert(
            "environment".to_string(),
            bytemuck::bytes_of(&self.environment).to_vec(),
        );
        out.insert(
            "env_texels".to_string(),
            bytemuck::cast_slice(&self.env_texels).to_vec(),
        );
        out.insert("env_cdf".to_string(), bytemuck::cast_slice(&self.env_cdf).to_vec());
        out.insert(
            "plastic_tables".to_string(),
            bytemuck::cast_slice(&self.plastic_tables).to_vec(),
        );
        out.insert(
            "attributes".to_string(),
            bytemuck::cast_slice(&self.attributes).to_vec(),
        );
        out.insert("media".to_string(), bytemuck::cast_slice(&self.media.media).to_vec());
        out.insert(
            "material_media".to_string(),
            bytemuck::cast_slice(&self.media.material_media).to_vec(),
        );
        out.insert("media_info".to_string(), bytemuck::bytes_of(&self.media.info).to_vec());
        out.insert(
            "media_grids".to_string(),
            bytemuck::cast_slice(&self.media.grids).to_vec(),
        );
        out.insert(
            "media_density".to_string(),
            bytemuck::cast_slice(&self.media.density).to_vec(),
        );
        out.insert("textures".to_string(), bytemuck::cast_slice(&self.textures).to_vec());
        out.insert("texels".to_string(), bytemuck::cast_slice(&self.texels).to_vec());
        out
    }
}
