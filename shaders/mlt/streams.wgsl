// Random-number streams that read a chain's primary samples: in a graph that sets the constant
// PRIMARY_SAMPLE_STREAMS, `rng_u32` (shaders/lib/rng.wgsl) takes its numbers from here, so
// code written for path streams (`rng_f32(&rng)`: BPT's sub-paths, scatter, the camera's
// jitter) runs unchanged on a chain's samples. A stream's state is its next dimension: stream
// i of STREAMS reads dimensions i, i + STREAMS, i + 2 STREAMS, ... of the chain's samples, so
// that a sub-path that draws more numbers does not move the other's.

// Streams interleaved in a chain's samples.
const STREAMS: u32 = 2u;

// The samples the streams read, set by the evaluator before it draws.
var<private> stream_source: PrimarySamples;

// The state of stream `i`: its first dimension.
fn stream_start(i: u32) -> u32 {
    return i;
}

// The next number of the stream `*state` as 32 bits (24 significant: what rng_f32 keeps).
fn primary_stream_u32(state: ptr<function, u32>) -> u32 {
    let d = *state;
    *state = d + STREAMS;
    return u32(primary_at(stream_source, d) * 16777216.0) << 8u;
}
