// The pinhole camera. Needs the resource `camera`.

// The unit direction through raster position (x, y): (0, 0) is the top-left corner.
fn camera_direction(x: f32, y: f32) -> vec3<f32> {
    let ndc_x = 2.0 * x / camera.width - 1.0;
    let ndc_y = 1.0 - 2.0 * y / camera.height;
    return normalize(camera.forward + ndc_x * camera.right + ndc_y * camera.up);
}

// The pixel of sample `index` (< PIXELS) in tile order: 8x8 tiles row by row (narrower or
// lower at the right and bottom edges), each row by row, so 64 consecutive samples cover a
// tile, not a strip of a row: threads of a workgroup then query nearby photons (photon
// mapping), whose cells a warp shares. A bijection of 0 .. PIXELS.
fn camera_tiled_pixel(index: u32) -> u32 {
    let ty = index / (WIDTH * 8u);
    let r = index - ty * WIDTH * 8u;
    let th = min(8u, HEIGHT - ty * 8u);
    let tx = r / (8u * th);
    let q = r - tx * 8u * th;
    let tw = min(8u, WIDTH - tx * 8u);
    return (ty * 8u + q / tw) * WIDTH + tx * 8u + q % tw;
}

// The direction through a uniform point of pixel `pixel`, jittered with two numbers of `rng`.
fn camera_jittered_direction(pixel: u32, rng: ptr<function, u32>) -> vec3<f32> {
    let jitter = rng_vec2(rng);
    return camera_direction(f32(pixel % WIDTH) + jitter.x, f32(pixel / WIDTH) + jitter.y);
}

// Where a light sub-path meets the camera (light tracing): the raster position of the world
// point `p` (x, y) and the cosine between the view direction and the direction to `p` (z);
// z <= 0 when `p` is behind the camera or outside the image.
fn camera_raster(p: vec3<f32>) -> vec3<f32> {
    let d = normalize(p - camera.position);
    let cos_view = dot(d, camera.forward);
    if (cos_view <= EPS_COSINE) {
        return vec3<f32>(0.0);
    }
    let r2 = dot(camera.right, camera.right);
    let u2 = dot(camera.up, camera.up);
    let ndc = vec2<f32>(dot(d, camera.right) / (r2 * cos_view), dot(d, camera.up) / (u2 * cos_view));
    let x = 0.5 * (ndc.x + 1.0) * camera.width;
    let y = 0.5 * (1.0 - ndc.y) * camera.height;
    if (!(x >= 0.0 && x < camera.width && y >= 0.0 && y < camera.height)) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(x, y, cos_view);
}

// The solid-angle density of a camera ray through a uniform point of a pixel, in the
// direction at cosine `cos_view` to the view direction: the image plane at distance 1 has
// area 4 |right| |up| over width x height pixels, and area there turns into solid angle by
// cos^3. It is also the pinhole's importance for that pixel (SmallVCM's
// imageToSolidAngleFactor, with pixels as the unit of image area).
fn camera_pdf_w(cos_view: f32) -> f32 {
    let pixel_area = 4.0 * length(camera.right) * length(camera.up) / (camera.width * camera.height);
    return 1.0 / (pixel_area * cos_view * cos_view * cos_view);
}
