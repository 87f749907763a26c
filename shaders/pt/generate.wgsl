// Pass `generate` (Start over PATHS): path `index` samples pixel index % PIXELS (in 8x8
// tiles with TILED_PIXELS, camera_tiled_pixel), jittered uniformly inside the pixel.

fn generate(path: ptr<function, CameraPath>, index: u32) -> bool {
    var pixel = index % PIXELS;
    if (TILED_PIXELS) {
        pixel = camera_tiled_pixel(pixel);
    }
    var rng = rng_seed(frame.seed, frame.index, index);
    let jitter = rng_vec2(&rng);
    let x = f32(pixel % WIDTH) + jitter.x;
    let y = f32(pixel / WIDTH) + jitter.y;
    (*path).origin = camera.position;
    (*path).direction = camera_direction(x, y);
    (*path).pixel = pixel;
    (*path).length = 0u;
    (*path).throughput = vec3<f32>(1.0);
    (*path).rng = rng;
    (*path).last_pdf = 1.0;
    (*path).last_specular = 1u;
    return true;
}
