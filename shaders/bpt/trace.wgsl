// Pass `bpt_trace` (Loop): finds the closest hit of the camera sub-path's ray.

fn bpt_trace(p: ptr<function, BptPath>) -> bool {
    var camera = (*p).camera;
    camera_subpath_trace(&camera);
    (*p).camera = camera;
    return true;
}
