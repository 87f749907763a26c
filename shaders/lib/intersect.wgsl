// Ray intersection: triangles (Moeller-Trumbore), spheres (the numerically careful form of
// Haines et al., Ray Tracing Gems ch. 7) and BVH2 traversal, closest hit and any hit.
// Needs the resources `primitives` and `bvh`.

struct Hit {
    t: f32,
    primitive: u32,         // index in BVH order
    uv: vec2<f32>,          // barycentrics of v1, v2 (triangles)
    found: bool,
}

// Returns (t, u, v); t < 0 when there is no hit in (0, t_max).
fn intersect_triangle(o: vec3<f32>, d: vec3<f32>, p: Primitive, t_max: f32) -> vec3<f32> {
    let pv = cross(d, p.c);
    let det = dot(p.b, pv);
    if (det == 0.0) {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    let inv = 1.0 / det;
    let tv = o - p.a;
    let u = dot(tv, pv) * inv;
    let qv = cross(tv, p.b);
    let v = dot(d, qv) * inv;
    let t = dot(p.c, qv) * inv;
    if (u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0 || t >= t_max) {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    return vec3<f32>(t, u, v);
}

// Distance along a unit direction to the nearest sphere hit in (0, t_max), or -1.
fn intersect_sphere(o: vec3<f32>, d: vec3<f32>, p: Primitive, t_max: f32) -> f32 {
    let r = p.b.x;
    let f = o - p.a;
    let b = -dot(f, d);
    let l = f + b * d;
    let disc = r * r - dot(l, l);
    if (disc < 0.0) {
        return -1.0;
    }
    let c = dot(f, f) - r * r;
    let q = b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    var t0 = c / q;
    var t1 = q;
    if (t0 > t1) {
        let s = t0;
        t0 = t1;
        t1 = s;
    }
    if (t0 > 0.0 && t0 < t_max) {
        return t0;
    }
    if (t1 > 0.0 && t1 < t_max) {
        return t1;
    }
    return -1.0;
}

// Entry distance of the ray into a box, or a value > t_max when it misses. The exit distance
// is widened by 2 ulp-ish so that boxes touched at grazing angles are not missed (Ize 2013).
fn intersect_box(o: vec3<f32>, inv_d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let t_near = max(max(near.x, near.y), max(near.z, 0.0));
    let t_far = min(min(far.x, far.y), min(far.z, t_max)) * 1.00000024;
    return select(INFINITE_DISTANCE * 2.0, t_near, t_near <= t_far);
}

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let big = select(vec3<f32>(-1e30), vec3<f32>(1e30), d >= vec3<f32>(0.0));
    return select(1.0 / d, big, abs(d) < tiny);
}

fn intersect_primitive(o: vec3<f32>, d: vec3<f32>, index: u32, t_max: f32, hit: ptr<function, Hit>) {
    let p = primitives[index];
    if (p.kind == PRIMITIVE_SPHERE) {
        let t = intersect_sphere(o, d, p, t_max);
        if (t > 0.0) {
            *hit = Hit(t, index, vec2<f32>(0.0), true);
        }
    } else {
        let r = intersect_triangle(o, d, p, t_max);
        if (r.x > 0.0) {
            *hit = Hit(r.x, index, r.yz, true);
        }
    }
}

const BVH_STACK_SIZE: u32 = 64u;

// The closest hit along o + t d, t in (0, t_max).
fn trace_closest(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> Hit {
    var hit = Hit(t_max, 0u, vec2<f32>(0.0), false);
    let inv_d = safe_inverse(d);
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = bvh[node];
        var t_left = intersect_box(o, inv_d, n.left_min, n.left_max, hit.t);
        var t_right = intersect_box(o, inv_d, n.right_min, n.right_max, hit.t);
        if (t_left <= hit.t && n.left_count > 0u) {
            for (var i = n.left_first; i < n.left_first + n.left_count; i += 1u) {
                intersect_primitive(o, d, i, hit.t, &hit);
            }
            t_left = INFINITE_DISTANCE * 2.0;
        }
        if (t_right <= hit.t && n.right_count > 0u) {
            for (var i = n.right_first; i < n.right_first + n.right_count; i += 1u) {
                intersect_primitive(o, d, i, hit.t, &hit);
            }
            t_right = INFINITE_DISTANCE * 2.0;
        }
        let go_left = t_left <= hit.t;
        let go_right = t_right <= hit.t;
        if (go_left && go_right) {
            let left_first = t_left <= t_right;
            node = select(n.right_first, n.left_first, left_first);
            stack[sp] = select(n.left_first, n.right_first, left_first);
            sp += 1u;
        } else if (go_left) {
            node = n.left_first;
        } else if (go_right) {
            node = n.right_first;
        } else {
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            node = stack[sp];
        }
    }
    return hit;
}

// Whether anything lies along o + t d for t in (0, t_max).
fn trace_any(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    var hit = Hit(t_max, 0u, vec2<f32>(0.0), false);
    let inv_d = safe_inverse(d);
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = bvh[node];
        let t_left = intersect_box(o, inv_d, n.left_min, n.left_max, t_max);
        let t_right = intersect_box(o, inv_d, n.right_min, n.right_max, t_max);
        var go_left = t_left <= t_max;
        var go_right = t_right <= t_max;
        if (go_left && n.left_count > 0u) {
            for (var i = n.left_first; i < n.left_first + n.left_count; i += 1u) {
                intersect_primitive(o, d, i, t_max, &hit);
            }
            if (hit.found) {
                return true;
            }
            go_left = false;
        }
        if (go_right && n.right_count > 0u) {
            for (var i = n.right_first; i < n.right_first + n.right_count; i += 1u) {
                intersect_primitive(o, d, i, t_max, &hit);
            }
            if (hit.found) {
                return true;
            }
            go_right = false;
        }
        if (go_left && go_right) {
            node = n.left_first;
            stack[sp] = n.right_first;
            sp += 1u;
        } else if (go_left) {
            node = n.left_first;
        } else if (go_right) {
            node = n.right_first;
        } else {
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            node = stack[sp];
        }
    }
    return false;
}

// Where a ray hit: position (recomputed on the primitive for accuracy), unit geometric
// normal, material and area light.
struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: u32,
    light: i32,
}

fn surface_at(hit: Hit, o: vec3<f32>, d: vec3<f32>) -> Surface {
    let p = primitives[hit.primitive];
    if (p.kind == PRIMITIVE_SPHERE) {
        let n = normalize(o + hit.t * d - p.a);
        return Surface(p.a + p.b.x * n, n, p.material, p.light);
    }
    let position = p.a + hit.uv.x * p.b + hit.uv.y * p.c;
    return Surface(position, normalize(cross(p.b, p.c)), p.material, p.light);
}
