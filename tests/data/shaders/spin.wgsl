// Passes of the test graph spin.ron.

struct Spinner {
    index: u32,
    steps: u32,
    value: u32,
}

fn start(s: ptr<function, Spinner>, index: u32) -> bool {
    (*s).index = index;
    (*s).steps = 0u;
    (*s).value = index;
    return true;
}

fn spin(s: ptr<function, Spinner>) -> bool {
    // An inner loop the compiler cannot remove: its result is stored.
    var v = (*s).value;
    for (var i = 0u; i < SPIN; i += 1u) {
        v = v * 1664525u + 1013904223u;
    }
    (*s).value = v;
    (*s).steps += 1u;
    if ((*s).steps < STEPS) {
        return true;
    }
    values[(*s).index] = v;
    atomicAdd(&done[0], 1u);
    return false;
}
