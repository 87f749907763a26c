// Pass `trace_show` (Start over PATHS): the three results of an index into its pixel, so the
// benchmark leaves an image to look at: red, the camera ray's hit (nearer is brighter);
// green, an open ambient-occlusion ray; blue, a diffuse-bounce ray that hit something.

fn trace_show(s: ptr<function, TraceItem>, index: u32) -> bool {
    let primary = trace_results[index];
    let ao = trace_results[PATHS + index];
    let diffuse = trace_results[2u * PATHS + index];
    let near = select(0.0, exp(-primary / scene.radius), primary >= 0.0);
    film_add(trace_rays[index].pixel, vec3<f32>(near, select(0.0, 1.0, ao == 0.0), select(0.0, 1.0, diffuse >= 0.0)));
    return false;
}
