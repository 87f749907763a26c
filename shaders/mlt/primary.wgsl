// Primary samples: the random numbers a path is made of, drawn from a replayable stream.
//
// Dimension d of the stream `key` is a hash of the two (`primary_uniform`), so any dimension
// can be drawn again in any order: a chain seeded from bootstrap path i replays that path's
// stream, and a proposal's mutated dimension d is a function of the chain's current value and
// the step's key alone, so the proposal is drawn lazily while the path is traced and written
// to the chain's state, all of it, only when the step is accepted. Every dimension is mutated
// at every step (Kelemen et al. 2002), also those the proposal's path does not use, which
// keeps the mutation symmetric. The chain stores its first MLT_DIMS dimensions, dimension d of
// chain c at mlt_samples[d * MLT_CHAINS + c] (a warp's chains side by side); dimensions past
// them are drawn fresh for every proposal, an independent proposal on those dimensions, which
// is symmetric too.

// Where `primary_next` takes its numbers from.
const PRIMARY_STREAM: u32 = 0u;    // the uniform stream `key`
const PRIMARY_PROPOSAL: u32 = 1u;  // chain `chain`'s state mutated with the numbers of `key`

// The size of the small steps of this thread's proposals: 0 for Kelemen's exponential steps
// (MLT_MUTATION_MIN to MLT_MUTATION_MAX), else Hachisuka and Jensen's (2011) adaptive size d,
// whose steps are xi^(1 / d + 1) (shaders/pm/adaptive.wgsl sets it).
var<private> primary_strength: f32 = 0.0;

// A source of primary samples for one path, and the next dimension it gives.
struct PrimarySamples {
    mode: u32,
    chain: u32,
    key: u32,
    large: u32,   // a proposal by a large step: every stored dimension drawn anew
    next: u32,
}

// A stream of a chain estimator: `stream` names its use (bootstrap, proposals), `step` the
// frame or mutation, `index` the path or chain; distinct from path tracing's streams.
fn primary_key(stream: u32, step: u32, index: u32) -> u32 {
    return rng_seed(frame.seed ^ rng_hash(stream + 0x4d4c5400u), step, index);
}

// The hash of dimension `d` of stream `key`: the dimension's own random bits.
fn primary_hash(key: u32, d: u32) -> u32 {
    return rng_hash(d ^ rng_hash(key));
}

// Random bits as a number in [0, 1) (24 bits, as rng_f32 converts them).
fn primary_unit(bits: u32) -> f32 {
    return f32(bits >> 8u) * (1.0 / 16777216.0);
}

// Dimension `d` of the uniform stream `key`.
fn primary_uniform(key: u32, d: u32) -> f32 {
    return primary_unit(primary_hash(key, d));
}

// Dimension `d`, at `current`, mutated with the numbers of `key`: drawn anew by a large step,
// else moved either way by a small step (`primary_step`), wrapped into [0, 1).
fn primary_mutated(current: f32, key: u32, d: u32, large: bool) -> f32 {
    let h = primary_hash(key, d);
    let a = primary_unit(h);
    if (large) {
        return a;
    }
    let b = primary_unit(rng_hash(h));
    let dv = primary_step(a);
    var v = current + select(-dv, dv, b < 0.5);
    v -= floor(v);
    return select(v, 0.0, v >= 1.0);
}

// A small step's size for the uniform number `a`: Kelemen's, between MLT_MUTATION_MIN and
// MLT_MUTATION_MAX, or with `primary_strength` d the adaptive a^(1 / d + 1).
fn primary_step(a: f32) -> f32 {
    if (primary_strength > 0.0) {
        return pow(a, 1.0 / primary_strength + 1.0);
    }
    return MLT_MUTATION_MAX * exp(-log(MLT_MUTATION_MAX / MLT_MUTATION_MIN) * a);
}

// Dimension `d` of the samples of `src`.
fn primary_at(src: PrimarySamples, d: u32) -> f32 {
    if (src.mode == PRIMARY_STREAM || d >= MLT_DIMS) {
        return primary_uniform(src.key, d);
    }
    return primary_mutated(mlt_samples[d * MLT_CHAINS + src.chain], src.key, d, src.large != 0u);
}

// The next primary sample of `src`.
fn primary_next(src: ptr<function, PrimarySamples>) -> f32 {
    let d = (*src).next;
    (*src).next = d + 1u;
    return primary_at(*src, d);
}

// Chain `chain` takes the proposal of `key`: its stored dimensions become the mutated ones.
fn primary_accept(chain: u32, key: u32, large: bool) {
    for (var d = 0u; d < MLT_DIMS; d += 1u) {
        let i = d * MLT_CHAINS + chain;
        mlt_samples[i] = primary_mutated(mlt_samples[i], key, d, large);
    }
}

// Chain `chain` takes the stream `key` as its state (its seed).
fn primary_seed(chain: u32, key: u32) {
    for (var d = 0u; d < MLT_DIMS; d += 1u) {
        mlt_samples[d * MLT_CHAINS + chain] = primary_uniform(key, d);
    }
}
