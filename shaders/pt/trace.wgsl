// Pass `trace` (Loop, the ray-cast stage): finds the closest hit of the path's ray (with MEDIA,
// the path's next vertex: a scattering in its medium, or a surface beyond index-matched
// boundaries; shaders/pt/media.wgsl).

fn trace(path: ptr<function, CameraPath>) -> bool {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*path).length == 0u), 1u);
    let hit = trace_closest((*path).origin, (*path).direction, INFINITE_DISTANCE);
    (*path).hit = path_hit(hit);
    (*path).length += 1u;
#if MEDIA
    path_through_media(path);
#endif
    return true;
}
