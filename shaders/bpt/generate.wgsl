// Pass `bpt_generate` (Start over PATHS): sample `index` traces its whole light sub-path,
// connecting each non-delta vertex to the camera (t = 1, through the shared `shadow` pass)
// and storing it in the item, then starts its camera sub-path.

fn bpt_generate(p: ptr<function, BptPath>, index: u32) -> bool {
    var rng = rng_seed(frame.seed, frame.index, index);
    bpt_camera_start(p, index, &rng);
    (*p).light_count = 0u;
    (*p).pad = 0u;
    var lp: LightPath;
    if (scene.num_lights > 0u && light_path_start(&lp, &rng)) {
        lp.rng = rng;
        loop {
            light_path_trace(&lp);
            if (lp.hit_t < 0.0) {
                break;
            }
            let s = light_path_surface(lp);
            let bsdf = light_path_bsdf(lp, s);
            if (!bsdf.valid) {
                break;
            }
            light_path_arrive(&lp, bsdf);
            if (!bsdf.is_delta) {
                let v = light_vertex_at(lp, s);
                let ray = light_vertex_to_camera(v, bsdf);
                if (!is_black(ray.contribution)) {
                    emit_shadow(ray);
                }
                if (lp.length + 2u <= MAX_PATH_LENGTH) {
                    (*p).light[(*p).light_count] = v;
                    (*p).light_count += 1u;
                }
            }
            if (lp.length + 2u > MAX_PATH_LENGTH || !light_path_scatter(&lp, s, bsdf, 1.0)) {
                break;
            }
        }
        rng = lp.rng;
    }
    (*p).rng = rng;
    return true;
}
