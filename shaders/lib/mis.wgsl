// Multiple importance sampling.

// The multiple-importance weight of a strategy with pdf `a` against one with pdf `b`:
// balance heuristic, or the power heuristic (exponent 2) when MIS_POWER is set.
fn mis_weight(a: f32, b: f32) -> f32 {
    if (MIS_POWER) {
        let a2 = a * a;
        return a2 / (a2 + b * b);
    }
    return a / (a + b);
}
