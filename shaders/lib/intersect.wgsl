// Ray intersection: triangles (Moeller-Trumbore), spheres (the numerically careful form of
// Haines et al., Ray Tracing Gems ch. 7) and BVH traversal, closest hit and any hit: BVH2, or
// with the CWBVH flag a compressed wide BVH. With the ALPHA_MASK flag, alpha-masked triangles
// let rays through where their alpha is below the cutoff. Needs the resources `primitives`, `bvh`, `attributes`,
// `materials`, `textures` and `texels`, and the library file textures.wgsl.

struct Hit {
    t: f32,
    primitive: u32,         // index in BVH order
    uv: vec2<f32>,          // barycentrics of v1, v2 (triangles)
    found: bool,
}

// Returns (t, u, v); t < 0 when there is no hit in (0, t_max).
fn intersect_triangle(o: vec3<f32>, d: vec3<f32>, p: PrimitiveFields, t_max: f32) -> vec3<f32> {
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
fn intersect_sphere(o: vec3<f32>, d: vec3<f32>, p: PrimitiveFields, t_max: f32) -> f32 {
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

// ---- alpha mask: cut-outs rays pass through (only with the ALPHA_MASK flag, which the
// host sets for scenes with an alpha-masked material) ----
#if ALPHA_MASK

// Whether primitive `p` (at `index`) is solid at barycentrics `uv`: always, unless the host
// marked it PRIMITIVE_ALPHA_MASKED (its material is alpha-masked; the rest need no material
// load) and its alpha there is below the cutoff.
fn alpha_solid(p: PrimitiveFields, index: u32, uv: vec2<f32>) -> bool {
    if ((p.kind & PRIMITIVE_ALPHA_MASKED) == 0u) {
        return true;
    }
    let m = materials[p.material];
    return material_alpha(m, surface_tex(index, uv)) >= m.alpha_cutoff;
}

#endif
// ---- end of alpha mask ----

// Texture coordinates on primitive `index` at barycentrics `uv` ((0, 0) without attributes).
fn surface_tex(index: u32, uv: vec2<f32>) -> vec2<f32> {
    if (index >= attribute_count()) {
        return vec2<f32>(0.0);
    }
    let a = attribute_at(index);
    return (1.0 - uv.x - uv.y) * a.uv0 + uv.x * a.uv1 + uv.y * a.uv2;
}

// The shading normal of primitive `index` at barycentrics `uv`: its interpolated vertex
// normals, turned to the side of the geometric normal `ng`; `ng` without vertex normals.
fn shading_normal(index: u32, uv: vec2<f32>, ng: vec3<f32>) -> vec3<f32> {
    if (index >= attribute_count()) {
        return ng;
    }
    let a = attribute_at(index);
    if ((a.flags & ATTRIBUTE_NORMALS) == 0u) {
        return ng;
    }
    let n = (1.0 - uv.x - uv.y) * decode_octahedral(a.n0) + uv.x * decode_octahedral(a.n1) + uv.y * decode_octahedral(a.n2);
    let len = length(n);
    if (!(len > 0.0)) {
        return ng;
    }
    return select(n / len, -n / len, dot(n, ng) < 0.0);
}

#if NORMAL_MAPS
// The shading normal of primitive `index` at barycentrics `uv` and texture coordinates `tex`
// under its material's normal map (glTF normalTexture): normalize(t x s + b y s + n z) for
// the map's (x, y, z) = 2 texel - 1 and scale s, in the frame of the interpolated vertex
// normal n (`ng` without vertex normals), the interpolated tangent t orthonormalised against
// n, and the bitangent b = w (n x t) of the interpolated handedness w; turned to the side of
// `ng`. `shading_normal` where the primitive has no tangents. With NORMAL_MAPS, `surface_at`
// takes its shading normal from here.
fn mapped_shading_normal(index: u32, uv: vec2<f32>, ng: vec3<f32>, material: u32, tex: vec2<f32>) -> vec3<f32> {
    if (index >= attribute_count()) {
        return ng;
    }
    let a = attribute_at(index);
    if ((a.flags & ATTRIBUTE_TANGENTS) == 0u) {
        return shading_normal(index, uv, ng);
    }
    let w = vec3<f32>(1.0 - uv.x - uv.y, uv.x, uv.y);
    var n = ng;
    if ((a.flags & ATTRIBUTE_NORMALS) != 0u) {
        let vertex = w.x * decode_octahedral(a.n0) + w.y * decode_octahedral(a.n1) + w.z * decode_octahedral(a.n2);
        n = select(ng, normalize(vertex), length(vertex) > 0.0);
    }
    let f = attribute_at(a.flags >> ATTRIBUTE_TANGENTS_SHIFT);
    let along = w.x * decode_octahedral(f.n0) + w.y * decode_octahedral(f.n1) + w.z * decode_octahedral(f.n2);
    let t = along - dot(along, n) * n;
    let handedness = select(1.0, -1.0, dot(w, vec3<f32>(f.uv1, f.uv2.x)) < 0.0);
    let scale = f.uv0.x;
    let x = texture_sample(u32(materials[material].normal_texture), tex).xyz * 2.0 - 1.0;
    let tangent = select(vec3<f32>(0.0), normalize(t), length(t) > 0.0);
    let mapped = tangent * (x.x * scale) + handedness * cross(n, tangent) * (x.y * scale) + n * x.z;
    let len = length(mapped);
    let m = select(n, mapped / len, len > 0.0);
    return select(m, -m, dot(m, ng) < 0.0);
}
#endif

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let big = select(vec3<f32>(-1e30), vec3<f32>(1e30), d >= vec3<f32>(0.0));
    return select(1.0 / d, big, abs(d) < tiny);
}

// Primitive fields from the three 16-byte words of a `Primitive`.
fn primitive_fields(w0: vec4<u32>, w1: vec4<u32>, w2: vec4<u32>) -> PrimitiveFields {
    return PrimitiveFields(bitcast<vec3<f32>>(w0.xyz), w0.w, bitcast<vec3<f32>>(w1.xyz), bitcast<i32>(w1.w), bitcast<vec3<f32>>(w2.xyz), w2.w);
}

// ---- geometry split over several bindings (SPLIT_GEOMETRY, set by the host for scenes
// larger than one storage binding, scenes/src/split.rs): chunks of the first chunk's length,
// the last shorter, the chunks past the data empty (each bound as one zero element) ----
#if SPLIT_GEOMETRY

// The chunk (0 to 3) of element `i` of a resource split in chunks of `n` elements, and the
// element's index in it.
fn split_index(i: u32, n: u32) -> vec2<u32> {
    let k = select(0u, 1u, i >= n) + select(0u, 1u, i >= 2u * n) + select(0u, 1u, i >= 3u * n);
    return vec2<u32>(k, i - k * n);
}

// Primitive `i`, from its chunk, unpacked into its fields.
fn primitive_at(i: u32) -> PrimitiveFields {
    let c = split_index(i, arrayLength(&primitives));
    var p: Primitive;
    switch c.x {
        case 0u: { p = primitives[c.y]; }
        case 1u: { p = primitives_1[c.y]; }
        case 2u: { p = primitives_2[c.y]; }
        default: { p = primitives_3[c.y]; }
    }
    return primitive_fields(p.w0, p.w1, p.w2);
}

// Primitives `i` below this may have attributes (all primitives, or none: empty chunks hold
// one zero element each, which reads as no normals and texture coordinates 0).
fn attribute_count() -> u32 {
    return arrayLength(&attributes) + arrayLength(&attributes_1) + arrayLength(&attributes_2) + arrayLength(&attributes_3);
}

// The attributes of primitive `i` (below `attribute_count()`), from its chunk.
fn attribute_at(i: u32) -> TriangleAttributes {
    let c = split_index(i, arrayLength(&attributes));
    switch c.x {
        case 0u: { return attributes[c.y]; }
        case 1u: { return attributes_1[c.y]; }
        case 2u: { return attributes_2[c.y]; }
        default: { return attributes_3[c.y]; }
    }
}

#else

// Primitive `i`, loaded as three 16-byte words and unpacked into its fields.
fn primitive_at(i: u32) -> PrimitiveFields {
    return primitive_fields(primitives[i].w0, primitives[i].w1, primitives[i].w2);
}

// Primitives `i` below this have attributes (all primitives, or none: an empty buffer holds
// one zero element, which reads as no normals and texture coordinates 0).
fn attribute_count() -> u32 {
    return arrayLength(&attributes);
}

// The attributes of primitive `i` (below `attribute_count()`).
fn attribute_at(i: u32) -> TriangleAttributes {
    return attributes[i];
}

#endif
// ---- end of split geometry ----

fn intersect_primitive(o: vec3<f32>, d: vec3<f32>, index: u32, t_max: f32, hit: ptr<function, Hit>) {
#if TRACE_STATS
    trace_stats_add(1u);
#endif
    let p = primitive_at(index);
#if SPHERES
    if (p.kind == PRIMITIVE_SPHERE) {
        let t = intersect_sphere(o, d, p, t_max);
        if (t > 0.0) {
            *hit = Hit(t, index, vec2<f32>(0.0), true);
        }
    } else {
#else
    {
#endif
        let r = intersect_triangle(o, d, p, t_max);
#if ALPHA_MASK
        if (r.x > 0.0 && alpha_solid(p, index, r.yz)) {
#else
        if (r.x > 0.0) {
#endif
            *hit = Hit(r.x, index, r.yz, true);
        }
    }
}

#if CWBVH
// Compressed wide BVH traversal (Ylitie, Karras and Laine, HPG 2017, algorithm 1), children
// in the order of the ray's octant. A node group (x: index of the node's first inner child,
// y: bits 24..32 mark the hit inner children still to visit, at bit 24 + (slot ^ octant) so
// that the highest bit is the nearest child along the ray; bits 0..8 the node's imask) and a
// primitive group (x: first primitive, y: bit k set for primitive x + k still to test). Each
// level pushes at most one group, so the stack needs the tree's depth less one (the host
// builds no deeper trees than this, scenes/src/cwbvh.rs MAX_DEPTH).
const BVH_STACK_SIZE: u32 = 32u;

// Node `i`, loaded as five 16-byte words and unpacked into its fields.
fn cwbvh_node(i: u32) -> CwbvhNode {
#if TRACE_STATS
    trace_stats_add(0u);
#endif
    let w0 = bvh[i].w0;
    let w1 = bvh[i].w1;
    let w2 = bvh[i].w2;
    let w3 = bvh[i].w3;
    let w4 = bvh[i].w4;
    return CwbvhNode(bitcast<vec3<f32>>(w0.xyz), w0.w, w1.x, w1.y, w1.zw, w2.xy, w2.zw, w3.xy, w3.zw, w4.xy, w4.zw);
}

// The byte of child `i` in a packed pair of words.
fn cwbvh_byte(w: vec2<u32>, i: u32) -> u32 {
    return (w[i >> 2u] >> ((i & 3u) * 8u)) & 0xffu;
}

// Slots of a node's occupied children (meta byte not 0), slot k at bit 8 (k % 4) + 4 (k / 4):
// a byte is not 0 when its low 7 bits plus 0x7f carry into bit 7 or bit 7 is set.
fn cwbvh_occupied(child_meta: vec2<u32>) -> u32 {
    let nonzero = (((child_meta & vec2<u32>(0x7f7f7f7fu)) + vec2<u32>(0x7f7f7f7fu)) | child_meta) & vec2<u32>(0x80808080u);
    return (nonzero.x >> 7u) | (nonzero.y >> 3u);
}

// The planes of a node's children a ray meets first and last per axis, with the node's grid:
// the plane at quantized q lies at t = q s + b (b_near, b_far padded apart).
struct CwbvhRayGrid {
    near_x: vec2<u32>,
    near_y: vec2<u32>,
    near_z: vec2<u32>,
    far_x: vec2<u32>,
    far_y: vec2<u32>,
    far_z: vec2<u32>,
    s: vec3<f32>,
    b_near: vec3<f32>,
    b_far: vec3<f32>,
}

fn cwbvh_ray_grid(n: CwbvhNode, o: vec3<f32>, inv_d: vec3<f32>) -> CwbvhRayGrid {
    // s is exact (e is a power of two).
    let e = bitcast<vec3<f32>>(((vec3<u32>(n.e_imask) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(0xffu)) << vec3<u32>(23u));
    let s = e * inv_d;
    let rel = n.p - o;
    let b = rel * inv_d;
    // A margin in t that makes the test conservative, 8 u (|p - o| + 255 e) |inv_d| with
    // u = 2^-24: the rounding of 1 / d, p - o, b and q s + b is at most about
    // (6 u |p - o| + 3 u 255 e) |inv_d|, and the builder's boxes may fall short of their
    // contents by u 255 e (it rounds child - p before flooring or ceiling it to the grid).
    let pad = (4.0 * 1.1920929e-7) * (abs(rel) + 255.0 * e) * abs(inv_d);
    // Per axis, the planes the ray enters through: the minima for a non-negative direction.
    let neg = inv_d < vec3<f32>(0.0);
    return CwbvhRayGrid(
        select(n.child_min_x, n.child_max_x, neg.x),
        select(n.child_min_y, n.child_max_y, neg.y),
        select(n.child_min_z, n.child_max_z, neg.z),
        select(n.child_max_x, n.child_min_x, neg.x),
        select(n.child_max_y, n.child_min_y, neg.y),
        select(n.child_max_z, n.child_min_z, neg.z),
        s,
        b - pad,
        b + pad,
    );
}

// The hit bits child `i` (meta byte `child_meta`, not 0) of a node adds (see below): its node
// bit, or its leaf's unary primitive count at its primitive offset; 0 if the ray misses it.
fn cwbvh_child_hit(g: CwbvhRayGrid, i: u32, child_meta: u32, imask: u32, oct_inv: u32, t_max: f32) -> u32 {
    let q_near = vec3<f32>(vec3<u32>(cwbvh_byte(g.near_x, i), cwbvh_byte(g.near_y, i), cwbvh_byte(g.near_z, i)));
    let q_far = vec3<f32>(vec3<u32>(cwbvh_byte(g.far_x, i), cwbvh_byte(g.far_y, i), cwbvh_byte(g.far_z, i)));
    let t_near = q_near * g.s + g.b_near;
    let t_far = q_far * g.s + g.b_far;
    let t_enter = max(max(t_near.x, t_near.y), max(t_near.z, 0.0));
    let t_exit = min(min(t_far.x, t_far.y), min(t_far.z, t_max));
    if (!(t_enter <= t_exit)) {
        return 0u;
    }
    if (((imask >> i) & 1u) != 0u) {
        return 1u << (24u + (i ^ oct_inv));
    }
    return (child_meta >> 5u) << (child_meta & 31u);
}

// Intersects the children of `n` with o + t d, t in [0, t_max]: returns the hit bits of a node
// group (bits 24..32) and of a primitive group (each hit leaf's unary primitive count shifted
// to its primitive offset, bits 0..24). `oct_inv` has bit 2, 1, 0 set for a non-negative x, y,
// z direction. With CWBVH_CHILD_SCAN it visits the occupied slots found by bit scan, a loop
// the compiler keeps small; else all eight slots, a loop it unrolls (faster where a kernel
// traverses at one place, slower where it inlines several traversals: docs/performance.md).
fn cwbvh_intersect_children(n: CwbvhNode, o: vec3<f32>, inv_d: vec3<f32>, oct_inv: u32, t_max: f32) -> u32 {
    let g = cwbvh_ray_grid(n, o, inv_d);
    let imask = n.e_imask >> 24u;
    var hits = 0u;
    if (CWBVH_CHILD_SCAN) {
        var occupied = cwbvh_occupied(n.child_meta);
        while (occupied != 0u) {
            let bit = firstTrailingBit(occupied);
            occupied &= occupied - 1u;
            let i = (bit >> 3u) | (bit & 4u);
            hits |= cwbvh_child_hit(g, i, cwbvh_byte(n.child_meta, i), imask, oct_inv, t_max);
        }
    } else {
        for (var i = 0u; i < 8u; i += 1u) {
            let child_meta = cwbvh_byte(n.child_meta, i);
            if (child_meta != 0u) {
                hits |= cwbvh_child_hit(g, i, child_meta, imask, oct_inv, t_max);
            }
        }
    }
    return hits;
}

// The closest hit along o + t d, t in (0, t_max), or with `any_hit` the first hit found.
fn cwbvh_trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(t_max, 0u, vec2<f32>(0.0), false);
    let inv_d = safe_inverse(d);
    let pos = inv_d >= vec3<f32>(0.0);
    let oct_inv = select(0u, 4u, pos.x) | select(0u, 2u, pos.y) | select(0u, 1u, pos.z);
    var stack: array<vec2<u32>, BVH_STACK_SIZE>;
    var sp = 0u;
    // The root alone: bit 31 with an empty imask visits node 0 whatever the octant.
    var nodes = vec2<u32>(0u, 0x80000000u);
    var prims = vec2<u32>(0u, 0u);
    loop {
        // The last node's leaves first: their hits shorten the ray for its inner children.
        while (prims.y != 0u) {
            let k = firstTrailingBit(prims.y);
            prims.y &= prims.y - 1u;
            intersect_primitive(o, d, prims.x + k, hit.t, &hit);
            if (any_hit && hit.found) {
                return hit;
            }
        }
        if ((nodes.y & 0xff000000u) == 0u) {
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            nodes = stack[sp];
        }
        // Visit the group's nearest child; the rest of the group waits on the stack.
        let bit = firstLeadingBit(nodes.y);
        let slot = (bit - 24u) ^ oct_inv;
        let index = nodes.x + countOneBits(nodes.y & ((1u << slot) - 1u));
        nodes.y &= ~(1u << bit);
        if ((nodes.y & 0xff000000u) != 0u) {
            stack[sp] = nodes;
            sp += 1u;
        }
        let n = cwbvh_node(index);
        let hits = cwbvh_intersect_children(n, o, inv_d, oct_inv, hit.t);
        nodes = vec2<u32>(n.child_base, (hits & 0xff000000u) | (n.e_imask >> 24u));
        prims = vec2<u32>(n.primitive_base, hits & 0x00ffffffu);
    }
    return hit;
}

// The closest hit along o + t d, t in (0, t_max).
fn trace_closest(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> Hit {
    return cwbvh_trace(o, d, t_max, false);
}

// Whether anything lies along o + t d for t in (0, t_max).
fn trace_any(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    return cwbvh_trace(o, d, t_max, true).found;
}
#else
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

// Each level pushes at most one node, so the stack needs the tree's depth less one (the host
// builds no deeper trees than this, scenes/src/bvh.rs MAX_DEPTH).
const BVH_STACK_SIZE: u32 = 64u;

// The closest hit along o + t d, t in (0, t_max).
fn trace_closest(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> Hit {
    var hit = Hit(t_max, 0u, vec2<f32>(0.0), false);
    let inv_d = safe_inverse(d);
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node = 0u;
    loop {
#if TRACE_STATS
        trace_stats_add(0u);
#endif
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
#if TRACE_STATS
        trace_stats_add(0u);
#endif
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

#endif

// Where a ray hit: position (recomputed on the primitive for accuracy), unit geometric
// normal, material, area light, the primitive's extent (for offset_ray_origin), texture
// coordinates, and the unit shading normal (with SHADING_NORMALS, interpolated vertex normals
// on the geometric normal's side; the geometric normal on spheres, triangles without vertex
// normals, and in scenes without them).
struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: u32,
    light: i32,
    extent: f32,
    tex: vec2<f32>,
    shading_normal: vec3<f32>,
}

// Where a path's last traced ray hit, as the path items carry it between passes (a `Hit`
// without its bool, which cannot be stored): the distance, negative when the ray escaped, the
// primitive and its barycentrics. CameraPath, CameraSubpath, LightPath and MergePath hold one.
struct PathHit {
    t: f32,
    primitive: u32,
    uv: vec2<f32>,
}

// The record of `hit`, a closest hit `trace_closest` found or not.
fn path_hit(hit: Hit) -> PathHit {
    return PathHit(select(-1.0, hit.t, hit.found), hit.primitive, hit.uv);
}

// Whether the ray escaped (hit nothing).
fn path_hit_escaped(h: PathHit) -> bool {
    return h.t < 0.0;
}

// The surface of a hit that was found, of the ray from `o` along `d`.
fn path_hit_surface(h: PathHit, o: vec3<f32>, d: vec3<f32>) -> Surface {
    return surface_at(Hit(h.t, h.primitive, h.uv, true), o, d);
}

// The normals a surface vertex keeps when a pass stores it to set its BSDF up again later:
// the geometric normal and, in scenes with shading normals, the shading normal; elsewhere the
// shading normal is the geometric one and is not stored. `VertexNormals` keeps them as they
// are (CameraVertex, PendingMerge), in scalars, so that the record packs beside the fields
// around it as a vec3 does (4-byte aligned: a struct of vec3s would pad each to 16 bytes);
// `PackedNormals` keeps them octahedrally packed (LightVertex). This is the one place
// SHADING_NORMALS decides what a stored vertex holds.
#if SHADING_NORMALS
struct VertexNormals {
    geometric: array<f32, 3>,
    shading: array<f32, 3>,
}

struct PackedNormals {
    geometric: u32,
    shading: u32,
}

// The normals of surface `s` to store.
fn vertex_normals(s: Surface) -> VertexNormals {
    return VertexNormals(vertex_normal_words(s.normal), vertex_normal_words(s.shading_normal));
}

// The shading normal of stored normals.
fn vertex_shading_normal(n: VertexNormals) -> vec3<f32> {
    return vertex_normal_of(n.shading);
}

// The normals of surface `s` to store, packed.
fn packed_normals(s: Surface) -> PackedNormals {
    return PackedNormals(encode_octahedral(s.normal), encode_octahedral(s.shading_normal));
}

// Packed normals as a vertex's BSDF is set up from them.
fn unpacked_normals(n: PackedNormals) -> VertexNormals {
    return VertexNormals(
        vertex_normal_words(decode_octahedral(n.geometric)),
        vertex_normal_words(decode_octahedral(n.shading)),
    );
}
#else
struct VertexNormals {
    geometric: array<f32, 3>,
}

struct PackedNormals {
    geometric: u32,
}

fn vertex_normals(s: Surface) -> VertexNormals {
    return VertexNormals(vertex_normal_words(s.normal));
}

fn vertex_shading_normal(n: VertexNormals) -> vec3<f32> {
    return vertex_normal_of(n.geometric);
}

fn packed_normals(s: Surface) -> PackedNormals {
    return PackedNormals(encode_octahedral(s.normal));
}

fn unpacked_normals(n: PackedNormals) -> VertexNormals {
    return VertexNormals(vertex_normal_words(decode_octahedral(n.geometric)));
}
#endif

// The geometric normal of stored normals.
fn vertex_geometric_normal(n: VertexNormals) -> vec3<f32> {
    return vertex_normal_of(n.geometric);
}

// A normal as the scalars `VertexNormals` keeps, and back.
fn vertex_normal_words(v: vec3<f32>) -> array<f32, 3> {
    return array<f32, 3>(v.x, v.y, v.z);
}

fn vertex_normal_of(w: array<f32, 3>) -> vec3<f32> {
    return vec3<f32>(w[0], w[1], w[2]);
}

fn surface_at(hit: Hit, o: vec3<f32>, d: vec3<f32>) -> Surface {
    let p = primitive_at(hit.primitive);
#if SPHERES
    if (p.kind == PRIMITIVE_SPHERE) {
        let n = normalize(o + hit.t * d - p.a);
        let m = abs(p.a) + vec3<f32>(p.b.x);
        return Surface(p.a + p.b.x * n, n, p.material, p.light, max(m.x, max(m.y, m.z)), vec2<f32>(0.0), n);
    }
#endif
    let position = p.a + hit.uv.x * p.b + hit.uv.y * p.c;
    let ng = triangle_normal(p.b, p.c);
    let tex = surface_tex(hit.primitive, hit.uv);
#if NORMAL_MAPS
    let ns = mapped_shading_normal(hit.primitive, hit.uv, ng, p.material, tex);
#else
#if SHADING_NORMALS
    let ns = shading_normal(hit.primitive, hit.uv, ng);
#else
    let ns = ng;
#endif
#endif
    return Surface(position, ng, p.material, p.light, triangle_extent(p.a, p.b, p.c), tex, ns);
}
