// Items of path tracing.

// A camera path between stages: the ray to trace next, the hit `trace` found for it, and
// what the path carries.
struct CameraPath {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
    length: u32,            // segments traced so far
    throughput: vec3<f32>,
    rng: u32,
    last_pdf: f32,          // density of the last sampled direction, for MIS on hitting a light
    last_specular: u32,     // 1 after the camera or a delta lobe: no MIS on the next light hit
    hit: PathHit,           // the last traced ray's hit (t < 0: it escaped)
#if MEDIA
    medium: i32,            // the medium the ray travels in (-1: vacuum)
    vertex: u32,            // what `trace` found: VERTEX_SURFACE at the hit, or VERTEX_MEDIUM at hit.t in `medium`
    gap: f32,               // distance from the path's last vertex to `origin` (boundaries crossed), for MIS
#endif
}

#if MEDIA
// The kinds of a camera path's next vertex.
const VERTEX_SURFACE: u32 = 0u;
const VERTEX_MEDIUM: u32 = 1u;
#endif

// A next-event-estimation connection: if nothing blocks the segment, the contribution
// reaches the pixel.
struct ShadowRay {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
    distance: f32,
    contribution: vec3<f32>,
#if MEDIA
    medium: i32,            // the medium the ray starts in (-1: vacuum)
#endif
}

// The side of a surface that `towards` points to.
fn side_normal(n: vec3<f32>, towards: vec3<f32>) -> vec3<f32> {
    return select(-n, n, dot(n, towards) > 0.0);
}

// The shadow ray from surface `s` to the light point `ill` that light sampling picked (it
// starts off the side the light is on), carrying `contribution` to `pixel`.
fn light_sample_ray(s: Surface, ill: Illumination, pixel: u32, contribution: vec3<f32>) -> ShadowRay {
    let origin = offset_ray_origin(s.position, side_normal(s.normal, ill.direction), s.extent);
#if MEDIA
    return ShadowRay(origin, pixel, ill.direction, light_shadow_distance(s.position, origin, ill), contribution, VACUUM);
#else
    return ShadowRay(origin, pixel, ill.direction, light_shadow_distance(s.position, origin, ill), contribution);
#endif
}

// The surface and BSDF at a camera path's last hit as `logic` set them up, for `material` when
// it runs next in the same thread (the two passes fused in one kernel): the same values, not
// computed twice. `material` in a kernel of its own finds `valid` false (private memory starts
// zeroed) and sets them up itself; it clears `valid` when it takes them. Only in scenes with
// textures, whose set-up fetches texels: there holding the vertex made NaivePTsk and the
// streaming layouts 4.5-10.5% faster on Sponza on an H100 (RegenerationPTsk 4.8% slower), while
// without textures the registers it holds cost the one-kernel layouts 9-14% on the Cornell box
// (docs/performance.md, "A bounce's vertex set up once").
struct PathVertex {
    s: Surface,
    bsdf: Bsdf,
    valid: bool,
}
var<private> path_vertex: PathVertex;

// The surface the path's last ray hit.
fn path_surface(path: CameraPath) -> Surface {
    return path_hit_surface(path.hit, path.origin, path.direction);
}
