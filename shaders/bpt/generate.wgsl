// Pass `bpt_generate` (Start over PATHS per frame run at once, `frame_slot`): sample `index`
// traces its whole light sub-path (its point on the light stratified among the frame's PATHS
// samples, `light_path_start_stratified`), connecting each non-delta vertex to the camera
// (t = 1, through the shared `shadow` pass) and storing it in the item, then starts its camera
// sub-path.

fn bpt_generate(p: ptr<function, BptPath>, index: u32) -> bool {
    let f = frame_slot(index);
    var rng = rng_seed(frame.seed, f.frame_index, f.path);
    (*p).camera = camera_subpath_start(f.path % PIXELS, &rng);
    (*p).camera.pixel += f.film_base;
    (*p).light_count = 0u;
    (*p).pad = 0u;
    var lp: LightPath;
    if (scene.num_lights > 0u && light_path_start_stratified(&lp, &rng, LightStratum(f.path, PATHS, f.frame_index))) {
        lp.rng = rng;
        loop {
            light_path_trace(&lp);
            let a = light_path_land(&lp);
            if (!a.alive) {
                break;
            }
            let visit = bpt_light_visit(&lp, a, f.film_base);
            if (visit.store) {
                (*p).light[(*p).light_count] = visit.vertex;
                (*p).light_count += 1u;
            }
            if (!visit.go_on) {
                break;
            }
        }
        rng = lp.rng;
    }
    (*p).camera.rng = rng;
    return true;
}
