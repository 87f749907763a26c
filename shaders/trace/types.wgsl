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

// With the graph's TRACE_STATS: the counters (plus one; 0 counts nothing) that the traversal
// adds a node visit (x) and a primitive test (y) to, set by a pass before it traces.
var<private> trace_stats: vec2<u32>;

// Counts one node visit (`which` 0) or primitive test (1) into the pass's counter.
fn trace_stats_add(which: u32) {
    let counter = trace_stats[which];
    if (counter != 0u) {
        count(counter - 1u, 1u);
    }
}
