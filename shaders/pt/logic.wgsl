// Pass `logic` (Loop, the logic stage): what the traced ray found. An escaped ray adds the
// background, a ray that hits an area light adds its emission (MIS-weighted against light
// sampling), and the path ends at the length cap or on a black material.
//
// MIS (two strategies for lights of finite extent): a light hit by BSDF sampling with
// density p_bsdf is weighted w(p_bsdf, p_light * pick), pick being the light's selection
// probability (`light_pmf`); the same light sampled directly in `material` is weighted
// w(p_light * pick, p_bsdf).

fn logic(path: ptr<function, CameraPath>) -> bool {
    if ((*path).hit_t < 0.0) {
        let bg = background_radiance((*path).direction);
        if (!is_black(bg.xyz)) {
            var w = 1.0;
            if ((*path).last_specular == 0u) {
                w = mis_weight((*path).last_pdf, bg.w * light_pmf(u32(scene.background)));
            }
            film_add((*path).pixel, (*path).throughput * w * bg.xyz);
        }
        return false;
    }
    let s = path_surface(*path);
    let bsdf = surface_bsdf(s, -(*path).direction);
    if (!bsdf.valid) {
        return false;
    }
#if TEXTURES
    path_vertex = PathVertex(s, bsdf, true);
#endif
    if (s.light >= 0) {
        let le = area_light_radiance(u32(s.light), (*path).direction);
        if (le.w > 0.0) {
            var w = 1.0;
            if ((*path).last_specular == 0u) {
                let light_pdf = le.w * (*path).hit_t * (*path).hit_t / abs(bsdf.fix.z);
                w = mis_weight((*path).last_pdf, light_pdf * light_pmf(u32(s.light)));
            }
            film_add((*path).pixel, (*path).throughput * w * le.xyz);
        }
    }
    return (*path).length < MAX_PATH_LENGTH && bsdf.continuation > 0.0;
}
