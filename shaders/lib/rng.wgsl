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

// Hook: the random-number source, the next 32 random bits of the stream `*state` (seeded by
// `rng_seed`, advanced here). Every sampling function draws through it (`rng_f32`,
// `rng_vec2`). Default: the PCG step; a Markov chain's graph whose evaluator draws so reads
// the chain's primary samples there instead (shaders/mlt/stream_rng.wgsl).
fn rng_u32(state: ptr<function, u32>) -> u32 {
    return rng_pcg_u32(state);
}

// The PCG step: the next 32 random bits of the stream `*state`.
fn rng_pcg_u32(state: ptr<function, u32>) -> u32 {
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
