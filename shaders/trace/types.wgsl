// Items and records of the trace-only benchmark (graphs/trace.ron).

// A ray made once and cast every frame; `t_max` 0 where there is none (an AO or diffuse ray
// of a camera ray that left the scene).
struct TraceRay {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    pixel: u32,
}

// The item of every pass: none crosses a kernel.
struct TraceItem {
    pixel: u32,
}
