// Pass `light_trace` (Loop): finds the closest hit of the light sub-path's ray.

fn light_trace(p: ptr<function, LightPath>) -> bool {
    light_path_trace(p);
    return true;
}
