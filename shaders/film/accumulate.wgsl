// Pass `accumulate` (Start over PIXELS, after every frame's light transport): takes the
// frame's pixel sum, turns it into the frame's estimate (divided by SAMPLES_PER_PIXEL) and
// adds it to the running sums: a Kahan-compensated sum of estimates and a sum of squares,
// from which the host derives the mean and its standard error.

struct Pixel {
    index: u32,
}

fn accumulate(pixel: ptr<function, Pixel>, index: u32) -> bool {
    (*pixel).index = index;
    let v = film_take(index) * (1.0 / f32(SAMPLES_PER_PIXEL));
    let sum = accum[index].xyz;
    let y = v - accum_comp[index].xyz;
    let t = sum + y;
    accum_comp[index] = vec4<f32>((t - sum) - y, 0.0);
    accum[index] = vec4<f32>(t, 0.0);
    accum_sq[index] += vec4<f32>(v * v, 0.0);
    return false;
}
