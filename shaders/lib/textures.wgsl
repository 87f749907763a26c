// Material parameters at a surface point: the material's factors, scaled by its textures.
// Needs the resource `materials`.

// Material `index` resolved at texture coordinates `tex`.
fn material_at(index: u32, tex: vec2<f32>) -> Material {
    return materials[index];
}
