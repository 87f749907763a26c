// Pass `generate` (Start over PATHS per frame run at once): path `index` of a frame samples
// pixel index % PIXELS (in 8x8 tiles with TILED_PIXELS, camera_tiled_pixel), jittered
// uniformly inside the pixel. With FRAMES_AT_ONCE frames run as one, index i is path
// i % PATHS of frame k = i / PATHS, whose random numbers are those of frame index
// frame.index FRAMES_AT_ONCE + k and whose light goes to film slot k (passes/film.ron).

fn generate(path: ptr<function, CameraPath>, index: u32) -> bool {
    let f = frame_slot(index);
    var pixel = f.path % PIXELS;
    if (TILED_PIXELS) {
        pixel = camera_tiled_pixel(pixel);
    }
    var rng = rng_seed(frame.seed, f.frame_index, f.path);
    let jitter = rng_vec2(&rng);
    let x = f32(pixel % WIDTH) + jitter.x;
    let y = f32(pixel / WIDTH) + jitter.y;
    let ray = camera_ray(x, y, camera_lens_sample(&rng));
    (*path).origin = ray.origin;
    (*path).direction = ray.direction;
    (*path).pixel = f.film_base + pixel;
    (*path).length = 0u;
    (*path).throughput = vec3<f32>(1.0);
    (*path).rng = rng;
    (*path).last_pdf = 1.0;
    (*path).last_specular = 1u;
#if MEDIA
    (*path).medium = media_info.x;
    (*path).vertex = VERTEX_SURFACE;
    (*path).gap = 0.0;
#endif
    return true;
}
