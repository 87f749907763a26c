// Passes of the appends test graph.

struct Source {
    index: u32,
}

struct Part {
    source: u32,
    part: u32,
}

// Parts item `i` emits: 0 to EMIT (tests/appends.rs computes the same).
fn parts_of(i: u32) -> u32 {
    return ((i * 2654435761u) >> 16u) % (EMIT + 1u);
}

fn scatter(s: ptr<function, Source>, index: u32) -> bool {
    (*s).index = index;
    let n = parts_of(index);
    for (var j = 0u; j < n; j += 1u) {
        if ((index + j) % 3u == 0u) {
            emit_parts(Part(index, j));
        } else {
            emit_parts(Part(index, j));
        }
    }
    return false;
}

fn gather(p: ptr<function, Part>) -> bool {
    count(COUNTER_PARTS, 1u);
    atomicAdd(&seen[(*p).source * EMIT + (*p).part], 1u);
    return false;
}
