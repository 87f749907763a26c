// Pass `accumulate` (Start over PIXELS, after every frame's light transport): takes the
// frame's pixel sum, turns it into the frame's estimate (divided by SAMPLES_PER_PIXEL) and
// adds it to the running sums: a Kahan-compensated sum of estimates and a sum of squares,
// from which the host derives the mean and its standard error. With FRAMES_AT_ONCE frames run
// as one it does so for each frame's slot in turn. With FILM_BIASED it also sums the biased
// light's estimates (passes/film.ron).

struct Pixel {
    index: u32,
}

fn accumulate(pixel: ptr<function, Pixel>, index: u32) -> bool {
    (*pixel).index = index;
    var sum = accum[index].xyz;
    var comp = accum_comp[index].xyz;
    var sq = accum_sq[index].xyz;
    for (var k = 0u; k < FRAMES_AT_ONCE; k += 1u) {
        let v = film_take(k * PIXELS + index) * (1.0 / f32(SAMPLES_PER_PIXEL));
        let y = v - comp;
        let t = sum + y;
        comp = (t - sum) - y;
        sum = t;
        sq += v * v;
    }
    accum_comp[index] = vec4<f32>(comp, 0.0);
    accum[index] = vec4<f32>(sum, 0.0);
    accum_sq[index] = vec4<f32>(sq, 0.0);
#if FILM_BIASED
    let biased = film_take(PIXELS * FRAMES_AT_ONCE + index) * (1.0 / f32(SAMPLES_PER_PIXEL));
    accum_biased[index] += vec4<f32>(biased, 0.0);
#endif
    return false;
}
