// The random-number source (the hook `rng_u32`, shaders/lib/rng.wgsl) of a graph whose
// chains' evaluator draws with `rng_f32(&rng)`: once the evaluator has called `streams_read`
// (in that thread), the numbers come from the chain's primary samples, `*state` naming the
// stream and its next dimension (shaders/mlt/streams.wgsl); elsewhere, and before, the PCG
// step.
fn rng_u32(state: ptr<function, u32>) -> u32 {
    if (streams_on) {
        return primary_stream_u32(state);
    }
    return rng_pcg_u32(state);
}
