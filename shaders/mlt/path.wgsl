// Path tracing as a function of primary samples: the contribution and the pixel of the path
// that the numbers of `src` make, the same estimator as the graph `pt` (next-event estimation
// and BSDF sampling combined by MIS, Russian roulette) through the same functions
// (shaders/pt/trace.wgsl, found.wgsl, bounce.wgsl). The numbers are used in a fixed order:
// the raster position (2), the lens (2), then at each vertex that goes on the light pick (1),
// the point on the light (2), the BSDF sample (3) and the roulette (1): 4 + 7 per bounce.

// Hook: a Markov chain's path evaluator, the path the primary samples of `src` make (its
// pixel and contribution; the chain's target is its luminance). Default here: path tracing
// (pssmlt).
fn mlt_path(src: ptr<function, PrimarySamples>) -> MltPath {
    let x = primary_next(src) * f32(WIDTH);
    let y = primary_next(src) * f32(HEIGHT);
    let lens = vec2<f32>(primary_next(src), primary_next(src));
    let pixel = min(u32(y), HEIGHT - 1u) * WIDTH + min(u32(x), WIDTH - 1u);
    let ray = camera_ray(x, y, lens);
    var path = CameraPath();
    path.origin = ray.origin;
    path.direction = ray.direction;
    path.pixel = pixel;
    path.throughput = vec3<f32>(1.0);
    path.last_pdf = 1.0;
    path.last_specular = 1u;
    var radiance = vec3<f32>(0.0);
    loop {
        trace(&path);
        if (path_hit_escaped(path.hit)) {
            radiance += path_background_found(path);
            break;
        }
        let s = path_surface(path);
        let bsdf = surface_bsdf(s, -path.direction);
        if (!bsdf.valid) {
            break;
        }
        radiance += path_light_found(path, s, bsdf);
        if (path.length >= MAX_PATH_LENGTH || bsdf.continuation <= 0.0) {
            break;
        }
        let light_u = primary_next(src);
        let light_uv = vec2<f32>(primary_next(src), primary_next(src));
        let u = vec3<f32>(primary_next(src), primary_next(src), primary_next(src));
        let roulette_u = primary_next(src);
        let v = PathVertex(s, bsdf, false);
        let shadow = material_next_event(path, v, light_u, light_uv);
        let goes_on = material_scatter(&path, v, u, roulette_u);
        radiance += mlt_unblocked(shadow);
        if (!goes_on) {
            break;
        }
    }
    return mlt_path_of(radiance, vec3<f32>(0.0), pixel);
}
