// Pass `light_generate` (Start over PATHS): light sub-path `index` starts on a light picked
// with its own random numbers, its point on the light stratified among the frame's PATHS
// sub-paths (`light_path_start_stratified`); no item when the scene has no light or the
// emission is void.

fn light_generate(p: ptr<function, LightPath>, index: u32) -> bool {
    return light_generate_stratified(p, index, PATHS);
}

// `light_generate` for sub-path `index` of `count`, its point on the light stratified
// (`light_path_start_stratified`).
fn light_generate_stratified(p: ptr<function, LightPath>, index: u32, count: u32) -> bool {
    if (scene.num_lights == 0u) {
        return false;
    }
    var rng = rng_seed(frame.seed, frame.index, index);
    let started = light_path_start_stratified(p, &rng, LightStratum(index, count, frame.index));
    (*p).rng = rng;
    (*p).index = index;
    return started;
}
