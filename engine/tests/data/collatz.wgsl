// Passes of the Collatz test graph.

struct Walk {
    index: u32,
    value: u32,
    steps: u32,
}

struct Done {
    index: u32,
    steps: u32,
}

struct Bin {
    index: u32,
}

fn seed(w: ptr<function, Walk>, index: u32) -> bool {
    *w = Walk(index, index + 1u, 0u);
    return true;
}

fn step(w: ptr<function, Walk>) -> bool {
    count(COUNTER_ITERATIONS, 1u);
    if ((*w).value == 1u) {
        emit_done(Done((*w).index, (*w).steps));
        return false;
    }
    if ((*w).value % 2u == 0u) {
        (*w).value = (*w).value / 2u;
    } else {
        (*w).value = 3u * (*w).value + 1u;
    }
    (*w).steps += 1u;
    return true;
}

fn record(d: ptr<function, Done>) -> bool {
    count(COUNTER_WALKS, 1u);
    steps[(*d).index] = (*d).steps;
    atomicAdd(&histogram[min((*d).steps, BINS - 1u)], 1u);
    return false;
}

fn summarize(b: ptr<function, Bin>, index: u32) -> bool {
    summary[index] = atomicLoad(&histogram[index]);
    return false;
}

fn unused(b: ptr<function, Bin>, index: u32) -> bool {
    scratch[index] = index;
    return false;
}
