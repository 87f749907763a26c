// Vertex connection and merging (Georgiev et al. 2012), mapped to the GPU as Davidovic et al.
// 2014 map it: LVC-BPT's light phase stores every non-delta light vertex in the Light Vertex
// Cache (shaders/bpt/lvc.wgsl), the engine puts the cache in sub-path order for the
// connections and builds the full hash grid over the same vertices for the merges
// (graphs/vcm.ron), then each camera vertex (shaders/vcm/camera.wgsl) makes LVC-BPT's
// connections and merges with the vertices within this frame's radius (photon mapping's r_i, shaders/pm/camera.wgsl), all
// weighted by one recursive MIS in which a merge counts pi r^2 N_light (`vcm_counts`).
//
// VCM_CONNECT and VCM_MERGE switch the two halves off. Without merging the passes do exactly
// what LVC-BPT's do; without connections (no light sampling, light tracing or connections)
// exactly what PBPM's do: the same random numbers, the same vertices (stored off the surface,
// their direction read with the photons' 24 bits), the same weights. d_vc carries PBPM's dVM
// then (see `MisCounts`).
//
// With PM_ITERATIONS > 1 a frame is that many VCM iterations at once (a small image then
// fills the GPU): camera sample and light sub-path `index` belong to iteration
// `vcm_iteration(index)`, a merge finds only the vertices of its own iteration's light
// sub-paths (each iteration has its own buckets of the grid) and counts N_light as one
// iteration's. Connections pick from the whole cache, as LVC-BPT's do at several samples per
// pixel.

// The strategies' counts: connections as LVC-BPT's, a merge pi r^2 N_light times a vertex
// connection (0 without merging), N_light the light sub-paths of one iteration.
fn vcm_counts() -> MisCounts {
    var merge = 0.0;
    if (VCM_MERGE) {
        let r = pm_radius();
        merge = mis_pow(PI * r * r * pm_merge_paths());
    }
    return MisCounts(lvc_eta(), merge, VCM_CONNECT);
}

// Pass `vcm_light_generate` (Start over the light sub-paths): LVC-BPT's start; without
// connections dVM (d_vc) starts at 0, as PBPM's.
fn vcm_light_generate(p: ptr<function, LightPath>, index: u32) -> bool {
    let started = lvc_light_generate(p, index);
    if (!VCM_CONNECT) {
        (*p).d_vc = 0.0;
    }
    return started;
}

// Pass `vcm_bounce` (Loop): the light sub-path's new vertex into the cache (also when only a
// merge can use it) with its grid key and point (`vcm_grid_key`), the t = 1 splat, and the
// next direction.
fn vcm_bounce(p: ptr<function, LightPath>) -> bool {
    var stored = lvc_none_stored();
    let alive = lvc_light_visit(p, vcm_counts(), select(2u, 1u, VCM_MERGE), &stored);
    if (VCM_MERGE && stored.index != LVC_NOT_STORED) {
        vcm_grid_key(stored, (*p).index);
    }
    return alive;
}

// The frame's iteration (of PM_ITERATIONS) of camera sample or light sub-path `index`: the
// samples per pixel of a frame, and the light sub-paths with them, cut into equal groups.
fn vcm_iteration(index: u32) -> u32 {
    return index / (PATHS / PM_ITERATIONS);
}

// The bucket of `cell` in the grid of the frame's iteration `iteration`: each of the
// PM_ITERATIONS iterations has its own PM_CELLS / PM_ITERATIONS buckets (a multiple of 8).
fn vcm_bucket(cell: vec3<i32>, iteration: u32) -> u32 {
    let groups = PM_CELLS / (8u * PM_ITERATIONS);
    return cell_bucket_among(cell, iteration * groups, groups);
}

// A cached vertex as the grid holds it: its position and its place in `lvc_staging` (16 bytes
// in bucket order, where the whole 48-byte vertex would take three times the scatter's traffic
// and the walk's reads; a merge loads the vertex only once found).
struct GridPoint {
    position: vec3<f32>,
    vertex: u32,
}

// Cached vertex `v` of light sub-path `owner`, as the light phase stores it: its hash grid
// bucket, in the grid of its sub-path's iteration, and its point, for the grid's `Count`,
// `Scan` and `Scatter` (written here, where a pass of their own read the vertices back: on an
// H100 the 256x256 box 2% faster; an atomic count here as well was slower).
fn vcm_grid_key(v: LvcStored, owner: u32) {
    var iteration = 0u;
    if (PM_ITERATIONS > 1u) {
        iteration = vcm_iteration(owner);
    }
    grid_key[v.index] = vcm_bucket(cell_of(v.position), iteration);
    vcm_points[v.index] = GridPoint(v.position, v.index);
}

// The merge at camera vertex `v` (dVCM `d_vcm`) of `iteration`: every cached vertex within the
// radius (the full hash grid's NaiveQuery over `vcm_grid`, shaders/pm/grid.wgsl) over
// pi r^2 N_light, as radiance for the vertex's pixel. With VCM_MERGE_AT_VERTEX `bsdf` is the
// vertex's; otherwise it is set up from `v` at the first vertex found (most queries find none
// where the radius is small against the scene: Sponza's 1.6 M queries a frame find 27 k). The walk only finds
// vertices, up to VCM_FOUND_BATCH at a time (`vcm_find`), and they are weighed after it, so
// the walk's loop holds no BSDF code; it resumes where it stopped.
fn vcm_merged(v: PendingMerge, d_vcm: f32, bsdf: Bsdf, iteration: u32, counts: MisCounts) -> vec3<f32> {
    var m = merge_query_at(v.position, v.d_vm, v.length);
    m.bsdf = bsdf;
    var cursor = VcmCursor(cell_box(m.position, m.radius).lo, 0u, false);
    var set_up = VCM_MERGE_AT_VERTEX;
    loop {
        var found: array<u32, VCM_FOUND_BATCH>;
        let n = vcm_find(m.position, m.radius, iteration, &cursor, &found);
        if (n > 0u && !set_up) {
            m.bsdf = pending_merge_bsdf(v);
            set_up = true;
        }
        for (var j = 0u; j < n; j += 1u) {
            vcm_merge_vertex(&m, lvc_staging[found[j]], d_vcm, counts);
        }
        if (cursor.done) {
            break;
        }
    }
    return v.throughput * m.sum * merge_kernel(m.radius);
}

// Cached vertices a walk finds before their weighing (2: on an H100 1.6% faster on the 256x256
// diffuse box than 4, and 1% on Sponza; 1 and 8 slower; docs/performance.md).
const VCM_FOUND_BATCH: u32 = 2u;

// Where a merge's walk over the grid goes on: the cell and the entry of its bucket, or done.
struct VcmCursor {
    cell: vec3<i32>,
    entry: u32,
    done: bool,
}

// The next cached vertices within `radius` of `position` in the grid of `iteration`, from the
// cursor on: up to VCM_FOUND_BATCH of their places in `lvc_staging` into `found`, in the
// walk's order. Returns how many, and leaves the cursor at the next one (done after the last
// cell).
fn vcm_find(position: vec3<f32>, radius: f32, iteration: u32, cursor: ptr<function, VcmCursor>,
            found: ptr<function, array<u32, VCM_FOUND_BATCH>>) -> u32 {
    let box = cell_box(position, radius);
    var walk = CellWalk(box, (*cursor).cell);
    var first = (*cursor).entry;
    var n = 0u;
    loop {
        let range = vcm_reached_bucket(walk.cell, position, radius, iteration);
        for (var i = max(first, range.x); i < range.y; i += 1u) {
            let point = vcm_grid[i];
            if (pm_in_range(point.position, position, radius) && cell_owns(box, walk.cell, point.position)) {
                if (n == VCM_FOUND_BATCH) {
                    (*cursor).cell = walk.cell;
                    (*cursor).entry = i;
                    return n;
                }
                (*found)[n] = point.vertex;
                n += 1u;
            }
        }
        first = 0u;
        if (!cell_walk_next(&walk)) {
            break;
        }
    }
    (*cursor).done = true;
    return n;
}

// The points in `vcm_grid` of the bucket of `cell` in the grid of `iteration`, or none when
// the cell is out of the reach of a merge of `radius` at `position`.
fn vcm_reached_bucket(cell: vec3<i32>, position: vec3<f32>, radius: f32, iteration: u32) -> vec2<u32> {
    if (!cell_reaches(cell, position, radius)) {
        return vec2<u32>(0u);
    }
    let b = vcm_bucket(cell, iteration);
    if (b + 1u < PM_CELLS) {
        return vec2<u32>(grid_first[b], grid_first[b + 1u]);
    }
    return vec2<u32>(grid_first[b], min(atomicLoad(&lvc_count), arrayLength(&vcm_grid)));
}

// Adds cached vertex `v`, in range of merge `m` (counted as `pm_found`), to it: the BSDF for
// the direction the light sub-path arrived from times its throughput, with VCM's weight
// (Georgiev et al.: the light side's dVCM / eta + dVM p, the camera side's likewise, where
// dVM = dVC / eta; PBPM's dVM alone without connections). Vertices that would make the path
// longer than MAX_PATH_LENGTH, and those `vcm_merges_vertex` declines, are left out.
fn vcm_merge_vertex(m: ptr<function, Merge>, v: LightVertex, camera_d_vcm: f32, counts: MisCounts) {
    count(COUNTER_PM_FOUND, 1u);
    if (light_vertex_length(v) + (*m).length > MAX_PATH_LENGTH || !vcm_merges_vertex(*m, v)) {
        return;
    }
    let towards = decode_octahedral_24(octahedral_24(v.fix));
    let e = bsdf_eval_merge((*m).bsdf, towards);
    if (is_black(e.f)) {
        return;
    }
    var w_light = v.d_vc * mis_pow(e.pdf_forward * (*m).bsdf.continuation);
    var w_camera = (*m).d_vm * mis_pow(e.pdf_reverse * bsdf_continuation_towards((*m).bsdf, towards));
    if (counts.vc) {
        w_light = (v.d_vcm + w_light) / counts.merge;
        w_camera = (camera_d_vcm + w_camera) / counts.merge;
    }
    (*m).sum += e.f * v.throughput * (1.0 / (w_light + 1.0 + w_camera));
}

// Hook: whether the merge `m` at a camera vertex (its position, radius, BSDF, camera sub-path
// length and dVM) takes cached light vertex `v`, found within its radius, asked for every one
// that keeps the path within MAX_PATH_LENGTH (`light_vertex_length`, `light_vertex_bsdf` read
// its packed fields). Default: every such vertex. The MIS weights count every cached vertex
// in range as merged, so one declined is light the image loses, not light another strategy
// takes instead (a merge that takes none renders VCM without its merges' share).
fn vcm_merges_vertex(m: Merge, v: LightVertex) -> bool {
    return true;
}
