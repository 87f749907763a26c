// What a chain's path evaluator (`fn mlt_path(src: ptr<function, PrimarySamples>) ->
// MltPath`, brought by the graph) returns, and what it shares.

// A path of primary samples: where it lands and what it carries there.
struct MltPath {
    radiance: vec3<f32>,
    pixel: u32,
}

// The scalar a chain's target is proportional to: the path's luminance, 0 for a sample the
// film would reject (NaN, infinite or negative).
fn mlt_weight(radiance: vec3<f32>) -> f32 {
    if (!is_valid_sample(radiance)) {
        return 0.0;
    }
    return luminance(radiance);
}

// What a connection's shadow ray brings: its contribution unless something blocks it.
fn mlt_unblocked(shadow: ShadowRay) -> vec3<f32> {
    if (is_black(shadow.contribution)) {
        return vec3<f32>(0.0);
    }
    count(COUNTER_RAYS_SHADOW, 1u);
    if (trace_any(shadow.origin, shadow.direction, shadow.distance)) {
        return vec3<f32>(0.0);
    }
    return shadow.contribution;
}
