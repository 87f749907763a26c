// Marsaglia's 32-bit xorshift (shifts 13, 17, 5) as the random-number source. Its state must
// not be zero: a zero seed starts from another word.
fn rng_u32(state: ptr<function, u32>) -> u32 {
    var x = select(*state, 0x9e3779b9u, *state == 0u);
    x ^= x << 13u;
    x ^= x >> 17u;
    x ^= x << 5u;
    *state = x;
    return x;
}
