// Passes of primary sample space Metropolis light transport (Kelemen et al. 2002) over path
// tracing. A frame:
// 1. `mlt_bootstrap` traces MLT_BOOTSTRAP_PATHS paths of fresh uniform streams and stores
//    each one's weight (its luminance); the operator `mlt_cdf` scans them. Their mean b is an
//    unbiased estimate of the integral of the weight over primary sample space, independent
//    of the chains' states (the frame's own paths), so b times the chains' splat density is
//    an unbiased estimate of the image, whatever the chains' correlation.
// 2. `mlt_start` takes up each of MLT_CHAINS chains where its last frame left it. A chain not
//    yet seeded picks bootstrap path i with probability proportional to its weight
//    (stratified over the chains, by a binary search of the scan) and replays its stream.
// 3. `mlt_mutate` runs MLT_MUTATIONS steps of each chain: a proposal (a large step with
//    probability MLT_LARGE_STEP, else small steps of every dimension), accepted with
//    probability a = min(1, weight'/weight); both the proposal and the current state are
//    splatted with their expected weights a and 1 - a (Veach's expected values), scaled by
//    b / weight and by PATHS / (MLT_CHAINS MLT_MUTATIONS), so that a frame adds one
//    sample per pixel per SAMPLES_PER_PIXEL to the film, as path tracing does. With
//    FILM_BIASED (Metropolised VCM) each splat's biased part, the path's `biased` light (its
//    merges'), goes to the film's biased channel with the same factor: every path's light has
//    the same weight, so that channel is the chains' estimate of the biased technique's image.

// The bootstrap's item (it stores a weight and makes no item).
struct MltBootstrap {
    index: u32,
}

// A chain while it runs: its current path and the frame's splat scale.
struct MltChain {
    path: MltPath,
    weight: f32,
    chain: u32,
    step: u32,     // steps run this frame
    scale: f32,    // b PATHS / (MLT_CHAINS MLT_MUTATIONS)
}

// A chain between frames (mlt_states): its current path, and whether it was seeded.
struct MltState {
    path: MltPath,
    weight: f32,
    seeded: u32,
}

// Pass `mlt_bootstrap` (Start over MLT_BOOTSTRAP_PATHS): the weight of bootstrap path `index`;
// with MLT_INDEPENDENT the path is also a sample of the film, scaled to PATHS paths a frame.
fn mlt_bootstrap(item: ptr<function, MltBootstrap>, index: u32) -> bool {
    var src = PrimarySamples(PRIMARY_STREAM, 0u, primary_key(1u, frame.index, index), 0u, 0u);
    let p = mlt_path(&src);
    let weight = mlt_weight(p.radiance);
    mlt_weights[index] = weight;
    if (MLT_INDEPENDENT && weight > 0.0) {
        mlt_splat(p, f32(PATHS) / f32(MLT_BOOTSTRAP_PATHS));
    }
    return false;
}

// Pass `mlt_start` (Start over MLT_CHAINS): chain `index` resumes, or is seeded; no item in a
// frame whose bootstrap found no light (b = 0: the frame's estimate is 0), nor with
// MLT_INDEPENDENT.
fn mlt_start(c: ptr<function, MltChain>, index: u32) -> bool {
    if (MLT_INDEPENDENT) {
        return false;
    }
    let last = MLT_BOOTSTRAP_PATHS - 1u;
    let total = mlt_cdf[last] + mlt_weights[last];
    if (!(total > 0.0)) {
        return false;
    }
    var state = mlt_states[index];
    if (state.seeded == 0u) {
        state = mlt_seed(index, total);
        mlt_states[index] = state;
    }
    let b = total / f32(MLT_BOOTSTRAP_PATHS);
    let scale = b * f32(PATHS) / (f32(MLT_CHAINS) * f32(MLT_MUTATIONS));
    *c = MltChain(state.path, state.weight, index, 0u, scale);
    return true;
}

// Chain `chain`'s seed: the bootstrap path of this frame at the chain's stratum of the
// weights' total (the last one whose scan is at most that), replayed.
fn mlt_seed(chain: u32, total: f32) -> MltState {
    let jitter = primary_uniform(primary_key(3u, frame.index, chain), 0u);
    let goal = (f32(chain) + jitter) / f32(MLT_CHAINS) * total;
    var lo = 0u;
    var hi = MLT_BOOTSTRAP_PATHS - 1u;
    while (lo < hi) {
        let mid = (lo + hi + 1u) / 2u;
        if (mlt_cdf[mid] <= goal) {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    let key = primary_key(1u, frame.index, lo);
    var src = PrimarySamples(PRIMARY_STREAM, 0u, key, 0u, 0u);
    let p = mlt_path(&src);
    primary_seed(chain, key);
    return MltState(p, mlt_weight(p.radiance), 1u);
}

// Pass `mlt_mutate` (Loop): one Metropolis-Hastings step of the chain.
fn mlt_mutate(c: ptr<function, MltChain>) -> bool {
    let key = primary_key(2u, frame.index * MLT_MUTATIONS + (*c).step, (*c).chain);
    let h = primary_hash(key, 0xffffffffu);
    let large = primary_unit(h) < MLT_LARGE_STEP;
    let accept_u = primary_unit(rng_hash(h));
    var src = PrimarySamples(PRIMARY_PROPOSAL, (*c).chain, key, u32(large), 0u);
    let p = mlt_path(&src);
    let w = mlt_weight(p.radiance);
    let a = select(min(1.0, w / (*c).weight), 1.0, (*c).weight <= 0.0);
    count(COUNTER_MLT_STEPS, 1u);
    count(COUNTER_MLT_LARGE_STEPS, u32(large));
    if (w > 0.0) {
        mlt_splat(p, a * (*c).scale / w);
    }
    if ((*c).weight > 0.0 && a < 1.0) {
        mlt_splat((*c).path, (1.0 - a) * (*c).scale / (*c).weight);
    }
    if (accept_u < a) {
        count(COUNTER_MLT_ACCEPTED, 1u);
        primary_accept((*c).chain, key, large);
        (*c).path = p;
        (*c).weight = w;
        mlt_states[(*c).chain] = MltState(p, w, 1u);
    }
    (*c).step += 1u;
    return (*c).step < MLT_MUTATIONS;
}
