// Adaptive Markov chain photon tracing (Hachisuka and Jensen 2011, "Robust adaptive photon
// tracing using photon path visibility") for progressive photon mapping, with many chains on
// the GPU (graphs/appm.ron, docs/mlt.md). A photon path is a function of its primary samples
// (shaders/mlt/primary.wgsl: a light sub-path of photon mapping, shaders/pm/light.wgsl, drawn
// from stream 0). Its visibility V is 1 when one of its photons lands in a cell marked by a
// camera vertex (`appm_mark`, the first AMC_MARK_FRAMES frames; a marked cell of side 2 r_0
// and its neighbours hold every point within r_0 of the vertex). Each of MLT_CHAINS chains
// runs AMC_CHAIN_STEPS iterations a frame (together PM_LIGHT_PATHS); an iteration traces a
// uniform path, which, when visible, becomes the chain's state (replica exchange), else
// deposits its photons as photon mapping's would, and the chain tries a small step of the
// adaptive size d (accepted when the proposal is visible). The chain's state deposits its
// photons at every iteration, scaled by F, the fraction of uniform paths found visible in
// the frames before: the frame estimates the photons of paths with V = 0 from its uniform
// paths and those with V = 1 from the chains (F times their mean), an unbiased split for any
// V. A chain's state stays in `mlt_samples` across frames, its photons in `appm_paths`; a
// chain with no state yet, or a frame with no F yet (the first frames), deposits its uniform
// paths whole, as photon mapping does. `appm_update` adds the frame's counts to
// the totals and moves d by the frame's acceptance: d += (accepted / mutations - 0.234) / t at
// frame t since the chains started (Robbins-Monro, the paper's target rate 0.234).

// The side of a visibility cell: the first frame's query diameter 2 r_0.
fn appm_cell_side() -> f32 {
    return 2.0 * PM_RADIUS * scene.radius;
}

// The bit of the cell `c` (integer coordinates).
fn appm_cell_bit(c: vec3<i32>) -> u32 {
    let h = rng_hash(bitcast<u32>(c.x) ^ rng_hash(bitcast<u32>(c.y) ^ rng_hash(bitcast<u32>(c.z))));
    return h % (AMC_MARK_WORDS * 32u);
}

// The integer coordinates of the cell holding `position`.
fn appm_cell(position: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(floor((position - pm_origin()) / appm_cell_side()));
}

// Whether a photon at `position` is in a marked cell.
fn appm_visible(position: vec3<f32>) -> bool {
    let bit = appm_cell_bit(appm_cell(position));
    return (atomicLoad(&appm_marks[bit / 32u]) & (1u << (bit % 32u))) != 0u;
}

// Pass `appm_mark` (Loop over MergePath, after `pm_vertex`): in the first AMC_MARK_FRAMES
// frames, a pending density estimation marks the 2 x 2 x 2 cells that its ball of radius r_0
// meets (the cells nearest its position along each axis).
fn appm_mark(p: ptr<function, MergePath>) -> bool {
    if (frame.index >= AMC_MARK_FRAMES || ((*p).flags & MERGE_PENDING) == 0u) {
        return true;
    }
    let q = ((*p).merge.position - pm_origin()) / appm_cell_side();
    let base = vec3<i32>(floor(q - vec3<f32>(0.5)));
    for (var k = 0u; k < 8u; k += 1u) {
        let c = base + vec3<i32>(i32(k & 1u), i32((k >> 1u) & 1u), i32(k >> 2u));
        let bit = appm_cell_bit(c);
        atomicOr(&appm_marks[bit / 32u], 1u << (bit % 32u));
    }
    return true;
}

// Whether this frame judges visibility: from AMC_MARK_FRAMES on, when the marks are complete.
fn appm_judging() -> bool {
    return frame.index >= AMC_MARK_FRAMES && !PM_MEASURING;
}

// Where photon `i` of slot `slot` (0 or 1: the state's and a proposal's) of chain `chain` is
// kept in `appm_paths` (slot-major, so that a warp's chains touch neighbouring photons).
fn appm_path_at(chain: u32, slot: u32, i: u32) -> u32 {
    return (slot * MAX_PATH_LENGTH + i) * MLT_CHAINS + chain;
}

// A traced photon path: its photons (in a slot of the chain's in `appm_paths`) and its
// visibility.
struct AppmPath {
    photons: u32,
    visible: bool,
}

// Traces the photon path of the samples `src` into slot `slot` of chain `chain`.
fn appm_trace(src: PrimarySamples, chain: u32, slot: u32) -> AppmPath {
    count(COUNTER_PM_PATHS, 1u);
    streams_read(src);
    var rng = stream_start(0u);
    var r = AppmPath(0u, false);
    var light: LightPath;
    if (scene.num_lights == 0u || !light_path_start_stratified(&light, &rng, LightStratum(0u, 1u, 0u))) {
        return r;
    }
    light.rng = rng;
    var p = photon_path(light);
    loop {
        light_path_trace(&light);
        let a = light_path_land(&light);
        p.light = light;
        if (!a.alive) {
            break;
        }
        let here = pm_light_arrive(&p, a);
        if (here.stored && r.photons < MAX_PATH_LENGTH) {
            appm_paths[appm_path_at(chain, slot, r.photons)] = here.photon;
            r.photons += 1u;
            r.visible = r.visible || (appm_judging() && appm_visible(here.photon.position));
        }
        if (!pm_light_scatter(&p, a)) {
            break;
        }
        light = p.light;
    }
    return r;
}

// Deposits the `n` photons of slot `slot` of chain `chain` into the frame's photons, their
// throughputs times `scale` (the overflow counted as `pm_overflow`).
fn appm_deposit(chain: u32, slot: u32, n: u32, scale: f32) {
    if (n == 0u || PM_MEASURING) {
        return;
    }
    let first = atomicAdd(&pm_count, n);
    for (var i = 0u; i < n; i += 1u) {
        if (first + i >= arrayLength(&pm_staging)) {
            count(COUNTER_PM_OVERFLOW, n - i);
            return;
        }
        var photon = appm_paths[appm_path_at(chain, slot, i)];
        photon.throughput *= scale;
        pm_staging[first + i] = photon;
    }
}

// A chain between frames (`appm_chains`): whether it has a state, the slot of `appm_paths`
// holding its state's photons, and how many.
struct AppmState {
    seeded: u32,
    slot: u32,
    photons: u32,
}

// The item of `appm_photons`: a chain.
struct AppmChain {
    index: u32,
}

// The totals of `appm_totals`: uniform paths and visible ones (each 64 bits: high, low),
// the mutation size d (its bits) and the frames of adaptation so far.
const AMC_UNIFORM: u32 = 0u;
const AMC_VISIBLE: u32 = 2u;
const AMC_STRENGTH: u32 = 4u;
const AMC_ADAPTED: u32 = 5u;

// The frame's counts (`appm_frame`): uniform paths, visible ones, mutations, accepted ones.
const AMC_FRAME_UNIFORM: u32 = 0u;
const AMC_FRAME_VISIBLE: u32 = 1u;
const AMC_FRAME_MUTATIONS: u32 = 2u;
const AMC_FRAME_ACCEPTED: u32 = 3u;

// The 64-bit total at `at` as a float.
fn appm_total(at: u32) -> f32 {
    return f32(appm_totals[at]) * 4294967296.0 + f32(appm_totals[at + 1u]);
}

// The mutation size d of this frame (AMC_STRENGTH_START before the first adaptation).
fn appm_strength() -> f32 {
    if (appm_totals[AMC_ADAPTED] == 0u) {
        return AMC_STRENGTH_START;
    }
    return bitcast<f32>(appm_totals[AMC_STRENGTH]);
}

// F: the fraction of uniform paths found visible in the frames before (0 before any).
fn appm_visible_fraction() -> f32 {
    let uniform = appm_total(AMC_UNIFORM);
    return select(0.0, appm_total(AMC_VISIBLE) / uniform, uniform > 0.0);
}

// A chain's run through one frame: its state, the iterations its photons stood for since
// they were last deposited, and F.
struct AppmRun {
    chain: u32,
    state: AppmState,
    repeats: u32,
    fraction: f32,
}

// Pass `appm_photons` (Start over MLT_CHAINS): chain `index`'s iterations of the frame.
fn appm_photons(item: ptr<function, AppmChain>, index: u32) -> bool {
    primary_strength = appm_strength();
    var run = AppmRun(index, appm_chains[index], 0u, appm_visible_fraction());
    let chains = run.fraction > 0.0 && !PM_MEASURING;
    for (var k = 0u; k < AMC_CHAIN_STEPS; k += 1u) {
        let iteration = index * AMC_CHAIN_STEPS + k;
        if (iteration >= PM_LIGHT_PATHS) {
            break;
        }
        appm_iterate(&run, frame.index * AMC_CHAIN_STEPS + k, chains);
    }
    if (chains && run.state.seeded != 0u) {
        appm_deposit_state(&run);
    }
    appm_chains[index] = run.state;
    return false;
}

// One iteration of the chain `run` (`step` numbers its streams): the uniform path, then the
// chain's move, then its state counted once more. Without `chains` (no F yet) or a state,
// the uniform path is deposited whole, and seeds the chain when visible (from the frame
// AMC_MARK_FRAMES on, when the marks are complete and visibility is judged).
fn appm_iterate(run: ptr<function, AppmRun>, step: u32, chains: bool) {
    let chain = (*run).chain;
    let proposal = 1u - (*run).state.slot;
    let key = primary_key(4u, step, chain);
    let u = appm_trace(PrimarySamples(PRIMARY_STREAM, 0u, key, 0u, 0u), chain, proposal);
    if (appm_judging()) {
        count(COUNTER_AMC_UNIFORM, 1u);
        count(COUNTER_AMC_VISIBLE, u32(u.visible));
        atomicAdd(&appm_frame[AMC_FRAME_UNIFORM], 1u);
        atomicAdd(&appm_frame[AMC_FRAME_VISIBLE], u32(u.visible));
    }
    if (!chains || (*run).state.seeded == 0u) {
        appm_deposit(chain, proposal, u.photons, 1.0);
        if (u.visible) {
            appm_take(run, proposal, u.photons, key, false);
        }
        return;
    }
    if (u.visible) {
        appm_take(run, proposal, u.photons, key, false);
    } else {
        appm_deposit(chain, proposal, u.photons, 1.0);
        appm_mutate(run, step);
    }
    (*run).repeats += 1u;
}

// The chain's small step: a proposal of the adaptive size, taken when it is visible.
fn appm_mutate(run: ptr<function, AppmRun>, step: u32) {
    let proposal = 1u - (*run).state.slot;
    let key = primary_key(5u, step, (*run).chain);
    let m = appm_trace(PrimarySamples(PRIMARY_PROPOSAL, (*run).chain, key, 0u, 0u), (*run).chain, proposal);
    count(COUNTER_AMC_MUTATIONS, 1u);
    atomicAdd(&appm_frame[AMC_FRAME_MUTATIONS], 1u);
    if (m.visible) {
        count(COUNTER_AMC_ACCEPTED, 1u);
        atomicAdd(&appm_frame[AMC_FRAME_ACCEPTED], 1u);
        appm_take(run, proposal, m.photons, key, true);
    }
}

// The chain takes the path in slot `slot` (`n` photons, the stream `key`; `mutated`: a small
// step of its state, else the uniform stream) as its state: the old state's photons are
// deposited for the iterations they stood for, and the new state's samples stored.
fn appm_take(run: ptr<function, AppmRun>, slot: u32, n: u32, key: u32, mutated: bool) {
    if ((*run).state.seeded != 0u && (*run).repeats > 0u) {
        appm_deposit_state(run);
    }
    if (mutated) {
        primary_accept((*run).chain, key, false);
    } else {
        primary_seed((*run).chain, key);
    }
    (*run).state = AppmState(1u, slot, n);
    (*run).repeats = 0u;
}

// Deposits the state's photons for the iterations they stood for, times F.
fn appm_deposit_state(run: ptr<function, AppmRun>) {
    let state = (*run).state;
    appm_deposit((*run).chain, state.slot, state.photons, f32((*run).repeats) * (*run).fraction);
}

// The item of `appm_update`.
struct AppmUpdate {
    index: u32,
}

// Pass `appm_update` (Start over 1, after the photons): the frame's counts into the totals,
// and the mutation size moved towards the acceptance rate AMC_ACCEPTANCE.
fn appm_update(item: ptr<function, AppmUpdate>, index: u32) -> bool {
    appm_add_total(AMC_UNIFORM, atomicLoad(&appm_frame[AMC_FRAME_UNIFORM]));
    appm_add_total(AMC_VISIBLE, atomicLoad(&appm_frame[AMC_FRAME_VISIBLE]));
    let mutations = atomicLoad(&appm_frame[AMC_FRAME_MUTATIONS]);
    if (mutations > 0u) {
        let rate = f32(atomicLoad(&appm_frame[AMC_FRAME_ACCEPTED])) / f32(mutations);
        let t = appm_totals[AMC_ADAPTED] + 1u;
        let d = appm_strength() + (rate - AMC_ACCEPTANCE) / f32(t);
        appm_totals[AMC_STRENGTH] = bitcast<u32>(clamp(d, AMC_STRENGTH_MIN, 1.0));
        appm_totals[AMC_ADAPTED] = t;
    }
    return false;
}

// Adds `n` to the 64-bit total at `at`.
fn appm_add_total(at: u32, n: u32) {
    let low = appm_totals[at + 1u] + n;
    appm_totals[at] += select(0u, 1u, low < n);
    appm_totals[at + 1u] = low;
}
