// StreamingBPT (van Antwerpen 2011): a pool of samples, each tracing its light sub-path and
// then its camera sub-path one ray per iteration, keeping every vertex a connection can use
// (up to MAX_PATH_LENGTH - 2 per sub-path) in the vertex buffers at its slot (`lg_slot`),
// out of the item, so that an iteration moves only the sub-paths' state. A finished sample
// hands each (camera vertex, light vertex) pair to the connection stage, one thread per pair;
// the t = 1 splats and the s = 1 light samples go out as shadow rays on the way. The estimator, random
// numbers included, is NaiveBPT's, so the two give the same image for the same seed.

// StreamingBPT's item: both sub-paths in flight and how many vertices each has stored.
struct StreamingSample {
    camera: CameraSubpath,
    light_path: LightPath,
    on_light: u32,              // 1 while the light sub-path is traced
    light_count: u32,
    camera_count: u32,
    pad: u32,
}

// Where vertex `i` of the sample in slot `lg_slot` lies in `sbpt_light_vertices` and
// `sbpt_camera_vertices`.
fn sbpt_vertex_at(i: u32) -> u32 {
    return lg_slot * LIGHT_VERTEX_SLOTS + i;
}

// One connection of the connection stage.
struct VertexPair {
    camera: CameraVertex,
    light: LightVertex,
}

// Pass `sbpt_generate` (Start over PATHS per frame run at once, `frame_slot`): sample `index`
// starts its light sub-path (or its camera sub-path when there is no light to start from),
// with NaiveBPT's random numbers and strata.
fn sbpt_generate(p: ptr<function, StreamingSample>, index: u32) -> bool {
    let f = frame_slot(index);
    var rng = rng_seed(frame.seed, f.frame_index, f.path);
    (*p).camera = camera_subpath_start(f.path % PIXELS, &rng);
    (*p).camera.pixel += f.film_base;
    (*p).light_count = 0u;
    (*p).camera_count = 0u;
    (*p).pad = 0u;
    (*p).on_light = 0u;
    var lp: LightPath;
    if (scene.num_lights > 0u && light_path_start_stratified(&lp, &rng, LightStratum(f.path, PATHS, f.frame_index))) {
        lp.rng = rng;
        (*p).on_light = 1u;
    }
    (*p).light_path = lp;
    (*p).camera.rng = rng;
    return true;
}

// Pass `sbpt_trace` (Loop): the closest hit of the ray of the sub-path being traced.
fn sbpt_trace(p: ptr<function, StreamingSample>) -> bool {
    if ((*p).on_light != 0u) {
        var lp = (*p).light_path;
        light_path_trace(&lp);
        (*p).light_path = lp;
    } else {
        var camera = (*p).camera;
        camera_subpath_trace(&camera);
        (*p).camera = camera;
    }
    return true;
}

// Pass `sbpt_extend` (Loop): at the new vertex of the light sub-path, the t = 1 splat, the
// vertex stored and the next direction (the camera sub-path takes over when it ends); at the
// new vertex of the camera sub-path, emission found (s = 0), a light sampled (s = 1), the
// vertex stored and the next direction. A sample whose camera sub-path ends emits its pairs.
fn sbpt_extend(p: ptr<function, StreamingSample>) -> bool {
    if ((*p).on_light != 0u) {
        var lp = (*p).light_path;
        let a = light_path_land(&lp);
        var go_on = false;
        if (a.alive) {
            let visit = bpt_light_visit(&lp, a, film_base_of((*p).camera.pixel));
            if (visit.store) {
                sbpt_light_vertices[sbpt_vertex_at((*p).light_count)] = visit.vertex;
                (*p).light_count += 1u;
            }
            go_on = visit.go_on;
        }
        (*p).light_path = lp;
        if (!go_on) {
            (*p).on_light = 0u;
            (*p).camera.rng = lp.rng;
        }
        return true;
    }
    var camera = (*p).camera;
    let alive = sbpt_camera_vertex(p, &camera);
    (*p).camera = camera;
    if (!alive) {
        sbpt_emit_pairs(p);
    }
    return alive;
}

// The camera half of `sbpt_extend` (NaiveBPT's `bpt_vertex` with the connections deferred);
// false when the camera sub-path ends.
fn sbpt_camera_vertex(p: ptr<function, StreamingSample>, c: ptr<function, CameraSubpath>) -> bool {
    let v = camera_visit(c, mis_counts(1.0));
    if (!v.alive) {
        return false;
    }
    camera_emit_direct(v);
    let s = v.a.s;
    if (!v.a.bsdf.is_delta && (*c).length + 2u <= MAX_PATH_LENGTH && (*p).light_count > 0u) {
        sbpt_camera_vertices[sbpt_vertex_at((*p).camera_count)] = camera_vertex_at(*c, s);
        (*p).camera_count += 1u;
    }
    var rng = v.rng;
    let alive = camera_scatter(c, v.a, mis_counts(1.0), &rng);
    (*c).rng = rng;
    return alive;
}

// The vertex to keep of camera sub-path `c` at its surface `s`.
fn camera_vertex_at(c: CameraSubpath, s: Surface) -> CameraVertex {
    var v: CameraVertex;
    v.position = s.position;
    v.extent = s.extent;
    v.throughput = c.throughput;
    v.d_vcm = c.d_vcm;
    v.normals = vertex_normals(s);
    v.d_vc = c.d_vc;
    v.towards = -c.direction;
    v.material = s.material;
    v.tex = s.tex;
    v.pixel = c.pixel;
    v.length = c.length;
    return v;
}

// The surface a kept camera vertex lies on (what its BSDF and connections need of it).
fn camera_vertex_surface(v: CameraVertex) -> Surface {
    let n = v.normals;
    return Surface(v.position, vertex_geometric_normal(n), v.material, -1, v.extent, v.tex, vertex_shading_normal(n));
}

// Every pair of stored vertices that makes a path of at most MAX_PATH_LENGTH segments, into
// the connection stage's queue.
fn sbpt_emit_pairs(p: ptr<function, StreamingSample>) {
    for (var i = 0u; i < (*p).camera_count; i += 1u) {
        let cv = sbpt_camera_vertices[sbpt_vertex_at(i)];
        for (var j = 0u; j < (*p).light_count; j += 1u) {
            let lv = sbpt_light_vertices[sbpt_vertex_at(j)];
            if (light_vertex_length(lv) + 1u + cv.length > MAX_PATH_LENGTH) {
                break;
            }
            emit_connect(VertexPair(cv, lv));
        }
    }
}

// Pass `sbpt_connect` (Step over VertexPair): the connection of one pair, as a shadow ray.
fn sbpt_connect(pair: ptr<function, VertexPair>) -> bool {
    let cv = (*pair).camera;
    let s = camera_vertex_surface(cv);
    let bsdf = surface_bsdf(s, cv.towards);
    let c = CameraSubpath(
        cv.position, cv.pixel, -cv.towards, cv.length, cv.throughput, 0u, cv.d_vcm, cv.d_vc,
        PathHit(),
    );
    let ray = bpt_connect(c, s, bsdf, (*pair).light, mis_counts(1.0));
    if (!is_black(ray.contribution)) {
        emit_shadow(ray);
    }
    return false;
}
