// The Light Vertex Cache in sub-path order: vertices arrive in `lvc_staging` in whatever order
// the light phase's threads stored them; `lvc_place` moves each to its place in sub-path
// order (sub-path index, then rank along the sub-path), so that a camera vertex's random
// numbers pick the same cache vertices in every layout. The places come from an exclusive
// prefix sum of the vertices stored per sub-path (`lvc_path_count`), taken in three levels of
// LVC_SCAN_BLOCK: sums of blocks of sub-paths, sums of groups of blocks, one thread scanning
// the group sums, then the scan carried back down to blocks and sub-paths.

const LVC_SCAN_BLOCK: u32 = 64u;

// Light sub-paths whose vertices are ordered (none while measuring the average length).
fn lvc_ordered_paths() -> u32 {
    return select(PATHS, 0u, LVC_MEASURING);
}

// Blocks of LVC_SCAN_BLOCK sub-paths.
fn lvc_blocks() -> u32 {
    return (lvc_ordered_paths() + LVC_SCAN_BLOCK - 1u) / LVC_SCAN_BLOCK;
}

// Pass `lvc_sum_blocks` (Start over the blocks): vertices stored by block `b`'s sub-paths.
fn lvc_sum_blocks(item: ptr<function, LvcOnce>, b: u32) -> bool {
    let end = min((b + 1u) * LVC_SCAN_BLOCK, lvc_ordered_paths());
    var sum = 0u;
    for (var i = b * LVC_SCAN_BLOCK; i < end; i += 1u) {
        sum += lvc_path_count[i];
    }
    lvc_block_sum[b] = sum;
    return false;
}

// Pass `lvc_sum_groups` (Start over the groups of blocks): vertices stored by group `g`.
fn lvc_sum_groups(item: ptr<function, LvcOnce>, g: u32) -> bool {
    let end = min((g + 1u) * LVC_SCAN_BLOCK, lvc_blocks());
    var sum = 0u;
    for (var b = g * LVC_SCAN_BLOCK; b < end; b += 1u) {
        sum += lvc_block_sum[b];
    }
    lvc_group_sum[g] = sum;
    return false;
}

// Pass `lvc_scan_groups` (Start over 1): the group sums become their exclusive prefix sums.
fn lvc_scan_groups(item: ptr<function, LvcOnce>, index: u32) -> bool {
    let groups = (lvc_blocks() + LVC_SCAN_BLOCK - 1u) / LVC_SCAN_BLOCK;
    var running = 0u;
    for (var g = 0u; g < groups; g += 1u) {
        let sum = lvc_group_sum[g];
        lvc_group_sum[g] = running;
        running += sum;
    }
    return false;
}

// Pass `lvc_scan_blocks` (Start over the groups): group `g`'s block sums become the first
// place of each block.
fn lvc_scan_blocks(item: ptr<function, LvcOnce>, g: u32) -> bool {
    let end = min((g + 1u) * LVC_SCAN_BLOCK, lvc_blocks());
    var running = lvc_group_sum[g];
    for (var b = g * LVC_SCAN_BLOCK; b < end; b += 1u) {
        let sum = lvc_block_sum[b];
        lvc_block_sum[b] = running;
        running += sum;
    }
    return false;
}

// Pass `lvc_scan_paths` (Start over the blocks): block `b`'s counts become the first place
// of each sub-path's vertices.
fn lvc_scan_paths(item: ptr<function, LvcOnce>, b: u32) -> bool {
    let end = min((b + 1u) * LVC_SCAN_BLOCK, lvc_ordered_paths());
    var running = lvc_block_sum[b];
    for (var i = b * LVC_SCAN_BLOCK; i < end; i += 1u) {
        let n = lvc_path_count[i];
        lvc_path_count[i] = running;
        running += n;
    }
    return false;
}

// Pass `lvc_place` (Start over the cache): stored vertex `i` to its place in sub-path order.
fn lvc_place(item: ptr<function, LvcOnce>, i: u32) -> bool {
    if (!LVC_MEASURING && i < min(atomicLoad(&lvc_count), arrayLength(&lvc_cache))) {
        let key = lvc_keys[i];
        lvc_cache[lvc_path_count[key.x] + key.y] = lvc_staging[i];
    }
    return false;
}
