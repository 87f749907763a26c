// Pass of the per-frame parameter test graph.

struct Cell {
    index: u32,
}

fn fill(c: ptr<function, Cell>, index: u32) -> bool {
    let sign = select(1.0, -1.0, NEGATE);
    values[index] = sign * f32(index) * SCALE + f32(frame.index);
    return false;
}
