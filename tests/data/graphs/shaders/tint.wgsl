// Pass `tint` of the test graph pt-tint: adds SAMPLES_PER_PIXEL to each pixel's frame sum,
// so that the accumulated image is path tracing's plus 1.
fn tint(p: ptr<function, Pixel>, index: u32) -> bool {
    film_add(index, vec3<f32>(f32(SAMPLES_PER_PIXEL)));
    return false;
}
