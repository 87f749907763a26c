// Constants and small helpers shared by every light-transport pass.

const PI: f32 = 3.14159265358979;
const INV_PI: f32 = 0.318309886183791;
const EPS_COSINE: f32 = 1e-6;
const INFINITE_DISTANCE: f32 = 1e30;

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.212671, 0.71516, 0.072169));
}

fn max_component(c: vec3<f32>) -> f32 {
    return max(c.x, max(c.y, c.z));
}

fn is_black(c: vec3<f32>) -> bool {
    return c.x <= 0.0 && c.y <= 0.0 && c.z <= 0.0;
}

// An orthonormal basis around a unit normal (Duff et al. 2017, "Building an orthonormal
// basis, revisited").
struct Frame3 {
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
}

fn frame_from_z(n: vec3<f32>) -> Frame3 {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return Frame3(vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x), vec3<f32>(b, s + n.y * n.y * a, -n.y), n);
}

fn to_local(f: Frame3, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.t), dot(v, f.b), dot(v, f.n));
}

fn to_world(f: Frame3, v: vec3<f32>) -> vec3<f32> {
    return f.t * v.x + f.b * v.y + f.n * v.z;
}
