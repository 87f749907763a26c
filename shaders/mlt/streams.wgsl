// Random-number streams that read a chain's primary samples: in a graph that replaces the hook
// `rng_u32` with shaders/mlt/stream_rng.wgsl, `rng_u32` takes its numbers from here once an
// evaluator has called `streams_read` (in that thread; other passes, such as a light phase,
// keep their own random streams), so code written for path streams (`rng_f32(&rng)`: BPT's
// sub-paths, scatter, the camera's jitter) runs unchanged on a chain's samples. A stream's
// state is its next dimension: stream i of the graph's PRIMARY_STREAM_COUNT reads dimensions
// i, i + PRIMARY_STREAM_COUNT, i + 2 PRIMARY_STREAM_COUNT, ... of the chain's samples, so that
// a sub-path that draws more numbers does not move the other's.

// The samples the streams read, set by `streams_read`.
var<private> stream_source: PrimarySamples;

// Whether this thread's `rng_u32` reads `stream_source` (after `streams_read`).
var<private> streams_on: bool = false;

// The evaluator's streams read the samples of `src` from here on.
fn streams_read(src: PrimarySamples) {
    stream_source = src;
    streams_on = true;
}

// The state of stream `i`: its first dimension.
fn stream_start(i: u32) -> u32 {
    return i;
}

// The state of a stream past every stored dimension: numbers drawn anew for each proposal
// (and replayed with its key when a chain is seeded from it), never mutated.
fn stream_fresh() -> u32 {
    return 0x40000000u;
}

// The next number of the stream `*state` as 32 bits (24 significant: what rng_f32 keeps).
fn primary_stream_u32(state: ptr<function, u32>) -> u32 {
    let d = *state;
    *state = d + PRIMARY_STREAM_COUNT;
    return u32(primary_at(stream_source, d) * 16777216.0) << 8u;
}
