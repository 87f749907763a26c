// Pass `logic` (Loop, the logic stage): what the traced ray found. An escaped ray adds the
// background, a ray that hits an area light adds its emission (both MIS-weighted against
// light sampling: shaders/pt/bounce.wgsl), and the path ends at the length cap or on a black
// material.

fn logic(path: ptr<function, CameraPath>) -> bool {
#if MEDIA
    if ((*path).vertex == VERTEX_MEDIUM) {
        return (*path).length < MAX_PATH_LENGTH;
    }
#endif
    if (path_hit_escaped((*path).hit)) {
        let bg = path_background_found(*path);
        if (!is_black(bg)) {
            film_add((*path).pixel, bg);
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
    let le = path_light_found(*path, s, bsdf);
    if (!is_black(le)) {
        film_add((*path).pixel, le);
    }
    return (*path).length < MAX_PATH_LENGTH && bsdf.continuation > 0.0;
}
