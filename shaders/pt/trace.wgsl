// Pass `trace` (Loop, the ray-cast stage): finds the closest hit of the path's ray.

fn trace(path: ptr<function, CameraPath>) -> bool {
    count(select(COUNTER_RAYS_EXTENSION, COUNTER_RAYS_PRIMARY, (*path).length == 0u), 1u);
    let hit = trace_closest((*path).origin, (*path).direction, INFINITE_DISTANCE);
    (*path).hit = path_hit(hit);
    (*path).length += 1u;
#if MEDIA
    // The path's next vertex: a scattering in its medium, or a surface beyond index-matched
    // boundaries (shaders/pt/flight.wgsl).
    path_through_media(path);
#endif
    return true;
}
