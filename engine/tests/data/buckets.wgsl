// Passes of the bucket-table test graph.

struct Candidate {
    point: vec2<f32>,
    slot: u32,
}

struct Mark {
    index: u32,
}

// A hash of the candidate's index and the frame's seed (the test repeats it on the CPU).
fn bucket_hash(x: u32) -> u32 {
    var h = x * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    return (h >> 22u) ^ h;
}

// A coordinate in [-1, 1): 24 random bits, exactly representable.
fn bucket_coordinate(h: u32) -> f32 {
    return f32(h >> 8u) * (2.0 / 16777216.0) - 1.0;
}

// Start: candidate `index`, kept when inside the unit disk.
fn keep_point(c: ptr<function, Candidate>, index: u32) -> bool {
    let p = vec2<f32>(
        bucket_coordinate(bucket_hash(2u * index + frame.seed)),
        bucket_coordinate(bucket_hash(2u * index + 1u + frame.seed)),
    );
    if (p.x * p.x + p.y * p.y >= 1.0) {
        return false;
    }
    let slot = atomicAdd(&stored, 1u);
    points[slot] = p;
    *c = Candidate(p, slot);
    return true;
}

// Step: the point's cell of the 8 x 8 grid over [-1, 1)^2.
fn locate(c: ptr<function, Candidate>) -> bool {
    let cell = vec2<u32>(((*c).point + 1.0) * 4.0);
    cells[(*c).slot] = cell.y * 8u + cell.x;
    return false;
}

// Start over the stored points.
fn mark(m: ptr<function, Mark>, index: u32) -> bool {
    *m = Mark(index);
    return true;
}

// Step: marks the stored point once.
fn confirm(m: ptr<function, Mark>) -> bool {
    marks[(*m).index] += 1u;
    count(COUNTER_MARKED, 1u);
    return false;
}
