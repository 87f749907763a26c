// Metropolised VCM and LVC-BPT (after Šik, Otsu, Hachisuka and Křivánek 2016): the chains run
// over camera sub-paths, and a camera sub-path's value is everything VCM's camera phase adds
// for it (shaders/vcm/camera.wgsl), MIS-weighted as there: the emission it finds (s = 0), a light
// sampled at each vertex (s = 1), LVC-BPT's connections to the frame's Light Vertex Cache
// (s >= 2) and, with VCM_MERGE, the merges with the cached vertices in this frame's radius.
// The light phase (the cache, the grid, light tracing's t = 1 splats) runs as in VCM, apart
// from the chains. The camera sub-path draws from stream 0, the connections' picks of cache
// vertices from a stream drawn anew for each proposal (`stream_fresh`): the cache is new each
// frame, so a stored pick would name a different vertex anyway (docs/mlt.md says why the
// chains stay correct while the cache changes under them).

// Hook: a Markov chain's path evaluator, the camera sub-path the primary samples of `src`
// make and what it adds to its pixel (the chain's target is its luminance). Default here:
// Metropolised VCM's camera sub-path (mvcm).
fn mlt_path(src: ptr<function, PrimarySamples>) -> MltPath {
    streams_read(*src);
    var rng = stream_start(0u);
    var picks = stream_fresh();
    var c = camera_subpath_at_raster(&rng);
    let counts = vcm_counts();
    var connected = vec3<f32>(0.0);
    var merged = vec3<f32>(0.0);
    loop {
        camera_subpath_trace(&c);
        let found = camera_land(&c, counts);
        connected += found.emission;
        let visit = camera_visit_at(&c, found.a, counts);
        if (!visit.alive) {
            break;
        }
        connected += mvcm_connected(c, visit, counts, &picks);
        merged += mvcm_merged(c, visit, counts);
        var scatter_rng = visit.rng;
        if (!camera_scatter(&c, visit.a, counts, &scatter_rng)) {
            break;
        }
        c.rng = scatter_rng;
    }
    // The merges are the biased part (graphs/mvcm.ron's FILM_BIASED), as in VCM's camera phase.
    return mlt_path_of(connected + merged, merged, c.pixel);
}

// What camera vertex `visit` of sub-path `c` gathers by connecting, as `vcm_vertex` does: the
// light sample's shadow ray and the connections (their picks from `picks`), each unblocked one
// MIS-weighted.
fn mvcm_connected(c: CameraSubpath, visit: CameraVisit, counts: MisCounts, picks: ptr<function, u32>) -> vec3<f32> {
    var r = mlt_unblocked(visit.direct);
    let n = lvc_connections_at(visit, VCM_CONNECT);
    let m = lvc_cached();
    for (var k = 0u; k < n; k += 1u) {
        r += mlt_unblocked(lvc_connection(c, visit, counts, m, rng_f32(picks)));
    }
    return r;
}

// What camera vertex `visit` of sub-path `c` gathers by merging (VCM_MERGE, at a non-delta
// vertex), MIS-weighted as `vcm_vertex` weighs it.
fn mvcm_merged(c: CameraSubpath, visit: CameraVisit, counts: MisCounts) -> vec3<f32> {
    if (!VCM_MERGE || visit.a.bsdf.is_delta) {
        return vec3<f32>(0.0);
    }
    let pending = pending_merge_at(visit.a.s, -c.direction, c.throughput, c.d_vc, c.length);
    return vcm_merged(pending, c.d_vcm, visit.a.bsdf, 0u, counts);
}
