// The photon pass: light sub-paths (started and traced as light tracing's, shaders/lt) that
// store a photon at every non-delta vertex a merge can use. PM_LIGHT_PATHS sub-paths per frame
// (one per camera sample by default, as SmallVCM). With PM_MEASURING the pass only counts the
// photons it would store (the graph's measured PM_AVERAGE_LENGTH sizes the photon buffer).

// A light sub-path of photon mapping: the light tracing state, its dVM, the photon stored at
// its last vertex (PM_NONE if none: for the original stochastic grid's insertion, a pass of
// its own after `pm_bounce`), whether it goes on (`pm_light_continue` ends it), and for SPPM
// whether it left a delta light through delta lobes alone (`sppm_delta_chains`).
struct PhotonPath {
    light: LightPath,
    d_vm: f32,
    stored: u32,
    alive: u32,
    delta_chain: u32,
}

const PM_NONE: u32 = 0xffffffffu;

// Pass `pm_light_generate` (Start over the light sub-paths): counts the sub-path for the
// measured average and starts it on a light, as light tracing does.
fn pm_light_generate(p: ptr<function, PhotonPath>, index: u32) -> bool {
    count(COUNTER_PM_PATHS, 1u);
    var light: LightPath;
    let started = light_generate_stratified(&light, index, PM_LIGHT_STARTS);
    *p = photon_path(light);
    return started;
}

// The photon-mapping sub-path of the light sub-path `light`, just started.
fn photon_path(light: LightPath) -> PhotonPath {
    let delta_chain = select(0u, 1u, sppm_delta_chains() && light_path_from_delta_light(light));
    return PhotonPath(light, 0.0, PM_NONE, 1u, delta_chain);
}

// Pass `pm_light_trace` (Loop): the closest hit of the sub-path's ray.
fn pm_light_trace(p: ptr<function, PhotonPath>) -> bool {
    var light = (*p).light;
    light_path_trace(&light);
    (*p).light = light;
    return true;
}

// Pass `pm_bounce` (Loop): at the sub-path's new vertex, a photon into `pm_staging` when the
// vertex is not delta and a merge there keeps the path within MAX_PATH_LENGTH (counted as
// `pm_overflow` when the buffer is full), then the next direction. Always true: whether the
// sub-path goes on is `alive`, so that the passes after it see its last photon.
fn pm_bounce(p: ptr<function, PhotonPath>) -> bool {
    (*p).alive = select(0u, 1u, pm_visit_light_vertex(p));
    return true;
}

// Pass `pm_light_continue` (Loop, last): ends the sub-path when `pm_bounce` said so.
fn pm_light_continue(p: ptr<function, PhotonPath>) -> bool {
    return (*p).alive != 0u;
}

// `pm_bounce`'s work; false when the sub-path ends.
fn pm_visit_light_vertex(p: ptr<function, PhotonPath>) -> bool {
    (*p).stored = PM_NONE;
    var light = (*p).light;
    let a = light_path_land(&light);
    (*p).light = light;
    if (!a.alive) {
        return false;
    }
    let here = pm_light_arrive(p, a);
    if (here.stored && !PM_MEASURING) {
        let i = atomicAdd(&pm_count, 1u);
        if (i < arrayLength(&pm_staging)) {
            pm_staging[i] = here.photon;
            (*p).stored = i;
        } else {
            count(COUNTER_PM_OVERFLOW, 1u);
        }
    }
    return pm_light_scatter(p, a);
}

// The photon a sub-path leaves at the vertex it arrived at (`a`, landed): stored when the
// vertex is not delta and a merge there keeps the path within MAX_PATH_LENGTH (counted as
// `pm_stored`).
struct PhotonHere {
    photon: Photon,
    stored: bool,
}

// The sub-path's arrival at `a`: its dVM there, and the photon it leaves (`PhotonHere`).
fn pm_light_arrive(p: ptr<function, PhotonPath>, a: Arrival) -> PhotonHere {
    let length = (*p).light.length;
    (*p).d_vm = mis_clamp((*p).d_vm / mis_pow(abs(a.bsdf.fix.z)));
    var here: PhotonHere;
    here.stored = !a.bsdf.is_delta && length + 1u <= MAX_PATH_LENGTH && pm_stores_photon(p, a);
    if (here.stored) {
        count(COUNTER_PM_STORED, 1u);
        let towards = -(*p).light.direction;
        let position = light_vertex_position(a.s, towards);
        let packed = photon_pack(towards, length, (*p).delta_chain != 0u);
        here.photon = Photon(position, (*p).d_vm, (*p).light.throughput, packed);
    }
    return here;
}

// Hook: whether light sub-path `p` stores a photon at the vertex it arrived at (`a`), asked
// at each non-delta vertex where a merge keeps the path within MAX_PATH_LENGTH, in the order
// the sub-path meets them; it may read and write the sub-path's fields (a field a graph adds
// to `PhotonPath` with `item_fields` carries what it needs from vertex to vertex). Default:
// every such vertex (the global photon map); a caustic map keeps the vertices reached from the
// light through delta vertices alone (L S+ D).
fn pm_stores_photon(p: ptr<function, PhotonPath>, a: Arrival) -> bool {
    return true;
}

// The sub-path's next direction from the vertex it arrived at (`a`); false when it ends there.
fn pm_light_scatter(p: ptr<function, PhotonPath>, a: Arrival) -> bool {
    if ((*p).light.length + 2u > MAX_PATH_LENGTH) {
        return false;
    }
    var rng = (*p).light.rng;
    let r = pm_scatter(a.bsdf, a.s, (*p).light.throughput, (*p).d_vm, &rng);
    (*p).light.rng = rng;
    if (!r.alive) {
        return false;
    }
    (*p).light.origin = r.origin;
    (*p).light.direction = r.direction;
    (*p).light.throughput = r.throughput;
    (*p).d_vm = r.d_vm;
    if (!r.specular) {
        (*p).delta_chain = 0u;
    }
    return true;
}
