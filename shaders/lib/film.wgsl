// The frame film: three 32-bit words per pixel, summed with atomics from any thread (native
// f32 atomics where the device has them, a compare-exchange loop otherwise). A sample that is
// NaN, infinite or negative is rejected and counted. Needs the resource `film` and the
// counter `samples_rejected`.

#if FLOAT32_ATOMIC
alias FilmWord = atomic<f32>;

fn film_add_word(i: u32, v: f32) {
    atomicAdd(&film[i], v);
}

fn film_take_word(i: u32) -> f32 {
    return atomicExchange(&film[i], 0.0);
}
#else
alias FilmWord = atomic<u32>;

fn film_add_word(i: u32, v: f32) {
    var old = atomicLoad(&film[i]);
    loop {
        let r = atomicCompareExchangeWeak(&film[i], old, bitcast<u32>(bitcast<f32>(old) + v));
        if (r.exchanged) {
            break;
        }
        old = r.old_value;
    }
}

fn film_take_word(i: u32) -> f32 {
    return bitcast<f32>(atomicExchange(&film[i], 0u));
}
#endif

// True for a finite, non-negative value (checked on the bits: NaN compares are unreliable).
fn is_valid_sample(c: vec3<f32>) -> bool {
    let bits = bitcast<vec3<u32>>(c);
    let finite = (bits & vec3<u32>(0x7f800000u)) != vec3<u32>(0x7f800000u);
    let negative = ((bits >> vec3<u32>(31u)) != vec3<u32>(0u)) & ((bits & vec3<u32>(0x7fffffffu)) != vec3<u32>(0u));
    return all(finite) && !any(negative);
}

fn film_add(pixel: u32, c: vec3<f32>) {
    if (!is_valid_sample(c)) {
        count(COUNTER_SAMPLES_REJECTED, 1u);
        return;
    }
    if (c.x > 0.0) {
        film_add_word(3u * pixel, c.x);
    }
    if (c.y > 0.0) {
        film_add_word(3u * pixel + 1u, c.y);
    }
    if (c.z > 0.0) {
        film_add_word(3u * pixel + 2u, c.z);
    }
}

// With FILM_BIASED, adds `c` (light that `film_add` also added, from the graph's biased
// technique) to the pixel's biased-light words after the frame slots; nothing otherwise.
fn film_add_biased(pixel: u32, c: vec3<f32>) {
#if FILM_BIASED
    if (!is_valid_sample(c)) {
        return;
    }
    let base = 3u * (PIXELS * FRAMES_AT_ONCE + pixel);
    for (var k = 0u; k < 3u; k += 1u) {
        if (c[k] > 0.0) {
            film_add_word(base + k, c[k]);
        }
    }
#endif
}

// Index `index` of a start pass over PATHS * FRAMES_AT_ONCE indices (passes/film.ron): path
// `path` of frame k = index / PATHS of the frames run at once, whose random numbers are those
// of frame index `frame_index` and whose light goes to the film's pixels from `film_base` on.
struct FrameSlot {
    path: u32,
    frame_index: u32,
    film_base: u32,
}

fn frame_slot(index: u32) -> FrameSlot {
    let k = index / PATHS;
    return FrameSlot(index % PATHS, frame.index * FRAMES_AT_ONCE + k, k * PIXELS);
}

// The first film pixel of the frame slot that film pixel `pixel` lies in.
fn film_base_of(pixel: u32) -> u32 {
    return pixel / PIXELS * PIXELS;
}

// Reads a pixel's sum and sets it back to zero.
fn film_take(pixel: u32) -> vec3<f32> {
    return vec3<f32>(film_take_word(3u * pixel), film_take_word(3u * pixel + 1u), film_take_word(3u * pixel + 2u));
}
