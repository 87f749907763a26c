// Random numbers: a 32-bit PCG (RXS-M-XS) stream per path, seeded by hashing the run seed,
// the frame index and the path index, so every layout draws the same numbers for a path.

fn rng_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_seed(seed: u32, frame_index: u32, path: u32) -> u32 {
    return rng_hash(path ^ rng_hash(frame_index ^ rng_hash(seed)));
}

fn rng_u32(state: ptr<function, u32>) -> u32 {
#if PRIMARY_SAMPLE_STREAMS
    // A Markov chain's graph: in an evaluator the numbers come from the chain's primary
    // samples, `*state` naming the stream and its next dimension (shaders/mlt/streams.wgsl).
    if (streams_on) {
        return primary_stream_u32(state);
    }
#endif
    let s = *state;
    *state = s * 747796405u + 2891336453u;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1).
fn rng_f32(state: ptr<function, u32>) -> f32 {
    return f32(rng_u32(state) >> 8u) * (1.0 / 16777216.0);
}

fn rng_vec2(state: ptr<function, u32>) -> vec2<f32> {
    let x = rng_f32(state);
    return vec2<f32>(x, rng_f32(state));
}
