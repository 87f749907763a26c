// The pinhole camera. Needs the resource `camera`.

// The unit direction through raster position (x, y): (0, 0) is the top-left corner.
fn camera_direction(x: f32, y: f32) -> vec3<f32> {
    let ndc_x = 2.0 * x / camera.width - 1.0;
    let ndc_y = 1.0 - 2.0 * y / camera.height;
    return normalize(camera.forward + ndc_x * camera.right + ndc_y * camera.up);
}
