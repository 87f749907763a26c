// Scene data as the host uploads it (mirrored in scenes/src/gpu.rs; a test compares the
// layouts), and robust ray origins.

struct SceneInfo {
    center: vec3<f32>,      // bounding sphere
    radius: f32,
    num_lights: u32,
    background: i32,        // index of the background light, or -1
    num_primitives: u32,
    num_materials: u32,
}

struct Camera {
    position: vec3<f32>,
    width: f32,
    forward: vec3<f32>,
    height: f32,
    right: vec3<f32>,       // scaled by tan(horizontal fov / 2)
    lens_radius: f32,       // THIN_LENS: the lens's radius (0: a pinhole)
    up: vec3<f32>,          // scaled by tan(vertical fov / 2)
    focus_distance: f32,    // THIN_LENS: the distance along `forward` to the plane in focus
}

const PRIMITIVE_TRIANGLE: u32 = 0u;
const PRIMITIVE_SPHERE: u32 = 1u;
const PRIMITIVE_ALPHA_MASKED: u32 = 2u;  // bit of a triangle whose material is alpha-masked

// A primitive's fields. `Primitive` is how the buffer holds them: the same 48 bytes as three
// 16-byte words, which `primitive_at` (intersect.wgsl) loads as three vector loads and unpacks
// (docs/performance.md, "Nodes and primitives loaded as 16-byte words").
struct PrimitiveFields {
    a: vec3<f32>,           // triangle v0, or sphere centre
    material: u32,
    b: vec3<f32>,           // triangle v1 - v0, or (radius, 0, 0)
    light: i32,             // area light index, or -1
    c: vec3<f32>,           // triangle v2 - v0
    kind: u32,
}

struct Primitive {
    w0: vec4<u32>,
    w1: vec4<u32>,
    w2: vec4<u32>,
}

#if CWBVH
// A compressed wide BVH node (Ylitie et al. 2017, as obvhs lays it out): up to eight children
// with boxes quantized to bytes on a grid of origin `p` and spacing 2^(e - 127) per axis. One
// byte per child, child i in byte i % 4 (bits 8 (i % 4) ..) of word i / 4 of a vec2 field.
// Meta byte: 0 for an empty slot; inner node: 0b00111iii, the node child_base + (the number of
// inner children in slots below i); leaf: the primitive count in unary in bits 5..8 and the
// offset of its first primitive from primitive_base in bits 0..5. `BvhNode` is how the buffer
// holds it: the same 80 bytes as five 16-byte words, which the traversal loads as five vector
// loads and unpacks (`cwbvh_node` in intersect.wgsl; docs/performance.md, "Nodes and
// primitives loaded as 16-byte words").
struct CwbvhNode {
    p: vec3<f32>,
    e_imask: u32,           // bytes 0..3: exponents e of x, y, z; byte 3: bit i set if child i is inner
    child_base: u32,
    primitive_base: u32,
    child_meta: vec2<u32>,
    child_min_x: vec2<u32>,
    child_max_x: vec2<u32>,
    child_min_y: vec2<u32>,
    child_max_y: vec2<u32>,
    child_min_z: vec2<u32>,
    child_max_z: vec2<u32>,
}

struct BvhNode {
    w0: vec4<u32>,
    w1: vec4<u32>,
    w2: vec4<u32>,
    w3: vec4<u32>,
    w4: vec4<u32>,
}
#else
// A BVH2 node with both children's boxes; a child with count 0 is the inner node `first`,
// otherwise the leaf of primitives first .. first + count.
struct BvhNode {
    left_min: vec3<f32>,
    left_first: u32,
    left_max: vec3<f32>,
    left_count: u32,
    right_min: vec3<f32>,
    right_first: u32,
    right_max: vec3<f32>,
    right_count: u32,
}
#endif

// A material. The SmallVCM lobes (diffuse, Phong, mirror or smooth dielectric) unless the
// PBR flag is set; then glTF's metallic-roughness model: `diffuse` is the base colour,
// with metallic, roughness (perceptual, GGX alpha = roughness^2) and transmission (through
// a dielectric of index `ior`). Textures (indices into the texture table, -1 for none)
// scale the factors; `material_at` resolves them at a surface point.
struct Material {
    diffuse: vec3<f32>,     // Lambertian reflectance, or the PBR base colour
    phong_exponent: f32,    // MATERIAL_ROUGH_PLASTIC: the offset of its table in plastic_tables
    phong: vec3<f32>,
    ior: f32,               // negative: perfect mirror
    mirror: vec3<f32>,
    flags: u32,             // MATERIAL_TWO_SIDED, MATERIAL_PBR, MATERIAL_ALPHA_MASK, MATERIAL_THIN_WALLED, ...
    emission: vec3<f32>,    // emitted radiance factor (glTF emissiveFactor x strength)
    metallic: f32,
    roughness: f32,
    transmission: f32,
    alpha: f32,             // base colour alpha factor
    alpha_cutoff: f32,      // MATERIAL_ALPHA_MASK: alpha below it is a hole
    base_color_texture: i32,
    metallic_roughness_texture: i32,
    emissive_texture: i32,
    normal_texture: i32,
}

const MATERIAL_TWO_SIDED: u32 = 1u;
const MATERIAL_PBR: u32 = 2u;
const MATERIAL_ALPHA_MASK: u32 = 4u;
const MATERIAL_THIN_WALLED: u32 = 8u;   // transmission through a thin sheet (PBR, BSDF_THIN_WALLED)
const MATERIAL_BECKMANN: u32 = 16u;     // PBR microfacets of Beckmann's distribution (BSDF_BECKMANN)
const MATERIAL_PLASTIC: u32 = 32u;      // Mitsuba's plastic: the diffuse base's internal scattering
const MATERIAL_PLASTIC_NONLINEAR: u32 = 64u;
const MATERIAL_CONDUCTOR: u32 = 128u;   // PBR metal of a complex index: eta in `mirror`, k in `phong`
const MATERIAL_SMITH_SEPARABLE: u32 = 256u; // PBR masking-shadowing G1(o) G1(i) (Mitsuba's)
const MATERIAL_ROUGH_PLASTIC: u32 = 512u;   // MATERIAL_PLASTIC with its rough coating's table (BSDF_ROUGH_PLASTIC)

#if MEDIA
const MATERIAL_NULL: u32 = 1024u;           // an index-matched boundary between media, crossed without a vertex

// A homogeneous participating medium, its coefficients scaled (`media` holds each as two
// vec4s: `medium_at` in shaders/lib/media.wgsl).
struct Medium {
    sigma_s: vec3<f32>,     // scattering coefficient per channel
    g: f32,                 // Henyey-Greenstein mean cosine (0: isotropic)
    sigma_t: vec3<f32>,     // extinction coefficient per channel
    kind: u32,              // 0: homogeneous
}
#endif

// One material slot's texture: its image at texels[offset ..] (width x height, rows from the
// top, RGBA8 with R in the low byte), sampled at uv' = (dot(row0, (u, v, 1)),
// dot(row1, (u, v, 1))) (KHR_texture_transform).
struct TextureInfo {
    row0: vec3<f32>,
    offset: u32,
    row1: vec3<f32>,
    flags: u32,             // TEXTURE_SRGB; wrap modes at bits 1..3 (u) and 3..5 (v); TEXTURE_NEAREST; TEXTURE_CHECKER
    width: u32,
    height: u32,
    pad: vec2<u32>,
}

const TEXTURE_SRGB: u32 = 1u;
const TEXTURE_WRAP_S_SHIFT: u32 = 1u;
const TEXTURE_WRAP_T_SHIFT: u32 = 3u;
const TEXTURE_WRAP_REPEAT: u32 = 0u;
const TEXTURE_WRAP_CLAMP: u32 = 1u;
const TEXTURE_WRAP_MIRROR: u32 = 2u;
const TEXTURE_NEAREST: u32 = 32u;
const TEXTURE_CHECKER: u32 = 64u;  // a checkerboard: texels[offset ..] holds its two colours as f32 RGBA

// Vertex attributes of one primitive, in BVH order like the primitives: texture coordinates,
// and unit shading normals in octahedral encoding (snorm16 x, y; decode_octahedral).
struct TriangleAttributes {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    n0: u32,
    n1: u32,
    n2: u32,
    flags: u32,             // ATTRIBUTE_NORMALS: n0..n2 hold vertex normals
}

const ATTRIBUTE_NORMALS: u32 = 1u;

#if NORMAL_MAPS
// A normal-mapped triangle's attributes index (flags >> ATTRIBUTE_TANGENTS_SHIFT) an entry
// past the primitives' that holds its tangent frames: the corners' unit tangents in n0..n2
// (encoded as normals), the normal map's scale in uv0.x, and the corners' handedness w (+-1:
// the bitangent is w (normal x tangent)) in uv1.x, uv1.y and uv2.x.
const ATTRIBUTE_TANGENTS: u32 = 2u;
const ATTRIBUTE_TANGENTS_SHIFT: u32 = 2u;
#endif

// The 10 low bits of `v` spread to every third bit (bits 0, 3, ..., 27): one axis of a Morton
// code, which interleaves them with the other axes' (shifted by 1 and 2).
fn morton_spread(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

// The Morton code of a cell of a 3D grid (10 bits an axis): x, y, z interleaved from bit 0.
fn morton_code(c: vec3<u32>) -> u32 {
    return morton_spread(c.x) | (morton_spread(c.y) << 1u) | (morton_spread(c.z) << 2u);
}

// The octahedral code of a unit vector: snorm16 x, y (Meyer et al. 2010).
fn encode_octahedral(v: vec3<f32>) -> u32 {
    let p = v.xy / (abs(v.x) + abs(v.y) + abs(v.z));
    var e = p;
    if (v.z < 0.0) {
        e = (vec2<f32>(1.0) - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    return pack2x16snorm(e);
}

// The unit vector an octahedral code stands for (Meyer et al. 2010).
fn decode_octahedral(code: u32) -> vec3<f32> {
    let e = unpack2x16snorm(code);
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n = vec3<f32>((1.0 - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0)), n.z);
    }
    return normalize(n);
}

const LIGHT_AREA: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;
const LIGHT_BACKGROUND: u32 = 3u;
const LIGHT_SPOT: u32 = 4u;
const LIGHT_ENVIRONMENT: u32 = 5u;

struct Light {
    position: vec3<f32>,    // area v0, point and spot position, or directional direction of travel
    kind: u32,
    e1: vec3<f32>,          // area v1 - v0, or the spot's unit axis (direction of travel)
    inv_area: f32,
    e2: vec3<f32>,          // area v2 - v0; spot: x = 1 for Mitsuba's falloff, linear in the angle
    cos_inner: f32,         // spot: full intensity within this cone
    normal: vec3<f32>,      // area: the emitting side
    cos_outer: f32,         // spot: no light outside this cone
    radiance: vec3<f32>,    // radiance, intensity (point, spot), irradiance (directional) or environment scale
    pad2: f32,
}

// Light selection by Walker's alias method in integers: of the 2^24 values of a pick, slot i
// gets 2^24 / slots, `keep` of which pick light i and the rest light `other`; `pmf` is light
// i's overall pick probability (exact: a whole number of values over 2^24).
struct AliasEntry {
    keep: u32,
    other: u32,
    pmf: f32,
}

// The environment map's size (width 0: none), rotation about +Y and texel layout.
struct Environment {
    width: u32,
    height: u32,
    cos_rotation: f32,
    sin_rotation: f32,
    pole_to_pole: u32,      // 1: texel rows at v = j / (h - 1) (Mitsuba); 0: at their centres
}

// Moves `p` off its surface along `n` (which points to the side the new ray leaves on), by
// a few units in the last place of p's coordinates (Waechter and Binder, "A fast and robust
// method for avoiding self-intersection", Ray Tracing Gems, 2019). `extent` is the largest
// coordinate magnitude of the primitive `p` was computed from: near the origin, where float
// spacing is finer than the error of the computed point (a few times extent x 2^-23), the
// offset is extent x 2^-19 instead, about 16 such units, as 256 units of p are at the
// threshold |p| = extent / 32. Both scale with the primitive, so a scene scaled by any
// factor, or one with huge coordinates elsewhere, is offset the same way.
fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>, extent: f32) -> vec3<f32> {
    let of_i = vec3<i32>(256.0 * n);
    let p_i = bitcast<vec3<f32>>(bitcast<vec3<i32>>(p) + select(of_i, -of_i, p < vec3<f32>(0.0)));
    let origin = extent * (1.0 / 32.0);
    return select(p_i, p + (extent * (1.0 / 524288.0)) * n, abs(p) < vec3<f32>(origin));
}

// Shadow rays that end on a surface stop this fraction of their length short of it (1 - 2^-12):
// the offsets of their end points along the surfaces' normals shorten a ray that meets a
// surface at a grazing angle by only (offset x cos^2), less than the rounding of the hit
// distance, so the surface a ray ends on would otherwise block it (light leaking away from
// the grazing parts of area lights). Relative, so independent of the scene's scale.
const SHADOW_SHORTENING: f32 = 0.999755859375;

// The length of a shadow ray from `origin` to a surface point `end`.
fn shadow_distance(origin: vec3<f32>, end: vec3<f32>) -> f32 {
    return length(end - origin) * SHADOW_SHORTENING;
}

// The largest coordinate magnitude of a triangle with corner `a` and edges `b`, `c`.
fn triangle_extent(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let m = max(abs(a), max(abs(a + b), abs(a + c)));
    return max(m.x, max(m.y, m.z));
}

// The unit normal of a triangle with edges `e1`, `e2` (by its winding), computed on edges
// scaled to at most 1, so that neither huge (1e30) nor tiny triangles overflow or underflow.
fn triangle_normal(e1: vec3<f32>, e2: vec3<f32>) -> vec3<f32> {
    let m3 = max(abs(e1), abs(e2));
    let m = max(m3.x, max(m3.y, m3.z));
    let s = select(1.0 / m, 1.0, m == 0.0);
    return normalize(cross(e1 * s, e2 * s));
}
