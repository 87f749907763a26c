// No cached light vertex found is merged.
fn vcm_merges_vertex(m: Merge, v: LightVertex) -> bool {
    return false;
}
