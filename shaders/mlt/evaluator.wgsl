// What a chain's path evaluator (`fn mlt_path(src: ptr<function, PrimarySamples>) ->
// MltPath`, brought by the graph) returns, and what it shares.

// A path of primary samples: where it lands and what it carries there; with FILM_BIASED also
// the part of that light the graph's biased technique added (Metropolised VCM's merges), which
// the splats add to the film's biased channel as well (passes/film.ron).
struct MltPath {
    radiance: vec3<f32>,
    pixel: u32,
#if FILM_BIASED
    biased: vec3<f32>,
#endif
}

// The path that carries `radiance` to `pixel`, `biased` of it from the graph's biased
// technique (kept with FILM_BIASED only).
fn mlt_path_of(radiance: vec3<f32>, biased: vec3<f32>, pixel: u32) -> MltPath {
#if FILM_BIASED
    return MltPath(radiance, pixel, biased);
#else
    return MltPath(radiance, pixel);
#endif
}

// Adds path `p`'s light times `factor` to its pixel, and its biased part times the same factor
// to the film's biased channel: that channel holds the biased technique's share of every splat.
fn mlt_splat(p: MltPath, factor: f32) {
    film_add(p.pixel, p.radiance * factor);
#if FILM_BIASED
    film_add_biased(p.pixel, p.biased * factor);
#endif
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
