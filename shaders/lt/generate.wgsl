// Pass `light_generate` (Start over PATHS): light sub-path `index` starts on a light picked
// with its own random numbers; no item when the scene has no light or the emission is void.

fn light_generate(p: ptr<function, LightPath>, index: u32) -> bool {
    if (scene.num_lights == 0u) {
        return false;
    }
    var rng = rng_seed(frame.seed, frame.index, index);
    let started = light_path_start(p, &rng);
    (*p).rng = rng;
    (*p).index = index;
    return started;
}
