// The camera: a pinhole, or with THIN_LENS a thin lens (depth of field) of radius
// `camera.lens_radius` focused on the plane at `camera.focus_distance` along the view
// direction. A thin lens's ray through raster position (x, y) starts at a uniform point of the
// lens and passes through the pinhole ray's point on the plane in focus; the same raster
// point maps to a direction from the lens point with the pinhole's density (area on the image
// plane to solid angle by cos^3), so `camera_pdf_w` serves both. Needs the resource `camera`.

// A camera ray: its origin (the camera's position, or a point of the lens) and unit direction.
struct CameraRay {
    origin: vec3<f32>,
    direction: vec3<f32>,
}

// Two uniform numbers for a point of the lens, drawn from `rng` only for a lens (a pinhole
// draws none, whatever the kernel's flags: its random streams stay as they were).
fn camera_lens_sample(rng: ptr<function, u32>) -> vec2<f32> {
#if THIN_LENS
    if (camera_has_lens()) {
        return rng_vec2(rng);
    }
#endif
    return vec2<f32>(0.0);
}

// Whether the camera is a thin lens (kernels with every feature compiled in also render
// pinholes).
fn camera_has_lens() -> bool {
    return camera.lens_radius > 0.0;
}

// The point of the lens for `lens` (uniform over the disk; the camera's position for a pinhole).
fn camera_lens_point(lens: vec2<f32>) -> vec3<f32> {
#if THIN_LENS
    let disk = sample_unit_disk(lens) * camera.lens_radius;
    return camera.position + disk.x * normalize(camera.right) + disk.y * normalize(camera.up);
#else
    return camera.position;
#endif
}

// The ray through raster position (x, y) from the lens point of `lens`.
fn camera_ray(x: f32, y: f32, lens: vec2<f32>) -> CameraRay {
    let d = camera_direction(x, y);
#if THIN_LENS
    if (camera_has_lens()) {
        let focus = camera.position + d * (camera.focus_distance / dot(d, camera.forward));
        let origin = camera_lens_point(lens);
        return CameraRay(origin, normalize(focus - origin));
    }
#endif
    return CameraRay(camera.position, d);
}

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

// The ray through a uniform point of pixel `pixel`, jittered with two numbers of `rng` (and
// from a lens point of two more with THIN_LENS).
fn camera_jittered_ray(pixel: u32, rng: ptr<function, u32>) -> CameraRay {
    let jitter = rng_vec2(rng);
    let lens = camera_lens_sample(rng);
    return camera_ray(f32(pixel % WIDTH) + jitter.x, f32(pixel / WIDTH) + jitter.y, lens);
}

// Where a light sub-path meets the camera through lens point `lens_point` (light tracing;
// `camera_lens_point`): the raster position of the world point `p` (x, y) and the cosine
// between the view direction and the direction from the lens point to `p` (z); z <= 0 when `p`
// is behind the camera or outside the image.
fn camera_raster(p: vec3<f32>, lens_point: vec3<f32>) -> vec3<f32> {
    let d = normalize(p - lens_point);
    let cos_view = dot(d, camera.forward);
    if (cos_view <= EPS_COSINE) {
        return vec3<f32>(0.0);
    }
    // The pinhole's direction to where the ray crosses the plane in focus (d itself for a
    // pinhole), over its cosine to the view direction.
    var through = d / cos_view;
#if THIN_LENS
    if (camera_has_lens()) {
        let focus = lens_point + d * (camera.focus_distance / cos_view) - camera.position;
        through = focus / dot(focus, camera.forward);
    }
#endif
    let r2 = dot(camera.right, camera.right);
    let u2 = dot(camera.up, camera.up);
    let ndc = vec2<f32>(dot(through, camera.right) / r2, dot(through, camera.up) / u2);
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
