// The full hash grid (Davidovic et al. 2014, Algorithm 1), built with the engine's operators:
// `grid_keys` writes each photon's bucket (shaders/pm/cells.wgsl), a Count gives each photon
// its slot in its bucket, a Scan of the counts each bucket's first place, and a Scatter puts
// the photon records themselves in bucket order in `grid_photons` (no index array), so a
// bucket's photons are contiguous: grid_first[b] .. grid_first[b + 1] (the photon total for the
// last). The gather visits the query's cells with NaiveQuery (cell by cell) or, with
// PM_WHILE_QUERY, WhileQuery (Algorithm 2: one loop that first finds the next photon in range,
// over all cells, then processes it); both find the same photons in the same order. NaiveQuery
// is the default: faster on an H100 (docs/performance.md), most since it reads four positions
// of a bucket at once. Both read a photon's position first and the rest of its record only
// when it is in range (most are not: a query's 8 cells cover about 5 times its disc).

// Pass `grid_keys` (Start over the stored photons): the photon's bucket.
fn grid_keys(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    grid_key[index] = cell_bucket(cell_of(pm_staging[index].position));
    return false;
}

// Pass `grid_copy_positions` (Start over the stored photons, after the scatter): the photon's
// position in `grid_positions`, beside its record in bucket order, so that a gather's reads of
// positions (most of them out of range) take 16 bytes each, not the record's 32.
fn grid_copy_positions(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    grid_positions[index] = vec4<f32>(grid_photons[index].position, 0.0);
    return false;
}

// The photons of bucket `b` in `grid_photons`: first and end.
fn grid_bucket(b: u32) -> vec2<u32> {
    if (b + 1u < PM_CELLS) {
        return vec2<u32>(grid_first[b], grid_first[b + 1u]);
    }
    return vec2<u32>(grid_first[b], photon_total());
}

// The photons of the bucket of `cell`, or none when the cell is out of the query's reach.
fn grid_reached_bucket(cell: vec3<i32>, m: Merge) -> vec2<u32> {
    if (cell_reaches(cell, m.position, m.radius)) {
        return grid_bucket(cell_bucket(cell));
    }
    return vec2<u32>(0u);
}

// Pass `grid_gather` (Loop over MergePath): the pending density estimation, if any.
fn grid_gather(p: ptr<function, MergePath>) -> bool {
    var m = merge_begin(*p);
    if (m.pending) {
        let box = cell_box(m.position, m.radius);
        if (PM_WHILE_QUERY) {
            grid_while_query(&m, box);
        } else {
            grid_naive_query(&m, box);
        }
        merge_end(p, m);
    }
    return true;
}

// NaiveQuery: every cell's photons in turn. In a box of at most 2 cells along each axis (the
// usual one) the 8 cells' bucket ranges are read first, all at once (eight loads in flight,
// not one round trip per cell); a wider box is walked cell by cell.
fn grid_naive_query(m: ptr<function, Merge>, box: CellBox) {
    if (box.distinct) {
        var ranges: array<vec2<u32>, 8>;
        grid_box_ranges(&ranges, *m, box);
        for (var k = 0u; k < 8u; k += 1u) {
            grid_cell_gather(m, ranges[k], box, box_cell(box, k));
        }
        return;
    }
    var walk = cell_walk(box);
    loop {
        grid_cell_gather(m, grid_reached_bucket(walk.cell, *m), box, walk.cell);
        if (!cell_walk_next(&walk)) {
            break;
        }
    }
}

// The bucket ranges of the 8 cells of a box of at most 2 cells along each axis (`box_cell`),
// each read without a branch so that the loads are in flight together; empty for a cell out of
// the box or of the query's reach.
fn grid_box_ranges(ranges: ptr<function, array<vec2<u32>, 8>>, m: Merge, box: CellBox) {
    let total = photon_total();
    (*ranges)[0] = grid_box_range(box, 0u, m, total);
    (*ranges)[1] = grid_box_range(box, 1u, m, total);
    (*ranges)[2] = grid_box_range(box, 2u, m, total);
    (*ranges)[3] = grid_box_range(box, 3u, m, total);
    (*ranges)[4] = grid_box_range(box, 4u, m, total);
    (*ranges)[5] = grid_box_range(box, 5u, m, total);
    (*ranges)[6] = grid_box_range(box, 6u, m, total);
    (*ranges)[7] = grid_box_range(box, 7u, m, total);
}

// The photons of the bucket of cell k of the box (`box_cell`), `total` photons in all, or none
// where the cell is out of the box or of the query's reach. The loads are made either way.
fn grid_box_range(box: CellBox, k: u32, m: Merge, total: u32) -> vec2<u32> {
    let cell = box_cell(box, k);
    let b = cell_bucket(cell);
    let range = vec2<u32>(grid_first[b], select(total, grid_first[min(b + 1u, PM_CELLS - 1u)], b + 1u < PM_CELLS));
    return select(vec2<u32>(0u), range, box_holds(box, cell) && cell_reaches(cell, m.position, m.radius));
}

// The photons of `range`, the bucket of `cell`, four at a time: their positions are read
// together (four loads in flight at once, not one round trip after another), then those in
// range are merged in order.
fn grid_cell_gather(m: ptr<function, Merge>, range: vec2<u32>, box: CellBox, cell: vec3<i32>) {
    for (var i = range.x; i < range.y; i += 4u) {
        let at = grid_four(i, range.y);
        var found = grid_four_kept(
            grid_positions[at.x].xyz, grid_positions[at.y].xyz, grid_positions[at.z].xyz, grid_positions[at.w].xyz,
            i, range.y, (*m).position, (*m).radius, box, cell,
        );
        while (found != 0u) {
            let k = firstTrailingBit(found);
            found &= found - 1u;
            merge_photon(m, grid_photons[i + k], 1.0);
        }
    }
}

// The entries a gather reads at once from a bucket ending at `end`, from entry i < end on:
// i .. i + 3, those past the end replaced by the last (the loads need no branch; see
// `grid_four_kept`).
fn grid_four(i: u32, end: u32) -> vec4<u32> {
    return min(vec4<u32>(i) + vec4<u32>(0u, 1u, 2u, 3u), vec4<u32>(end - 1u));
}

// Of the positions p0 .. p3 of entries i .. i + 3 (`grid_four`) of the bucket of `cell`, ending
// at `end`: bit k set where entry i + k exists, is within `radius` of `center` and counts in
// this visit of `cell` (`cell_owns`).
fn grid_four_kept(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, p3: vec3<f32>, i: u32, end: u32, center: vec3<f32>, radius: f32, box: CellBox, cell: vec3<i32>) -> u32 {
    let exists = vec4<u32>(i) + vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>(end);
    let kept = exists & vec4<bool>(
        grid_keeps(p0, center, radius, box, cell), grid_keeps(p1, center, radius, box, cell),
        grid_keeps(p2, center, radius, box, cell), grid_keeps(p3, center, radius, box, cell),
    );
    return dot(select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), kept), vec4<u32>(1u));
}

// Whether an entry at `position` in the bucket of `cell` is within `radius` of `center` and
// counts in this visit of `cell`.
fn grid_keeps(position: vec3<f32>, center: vec3<f32>, radius: f32, box: CellBox, cell: vec3<i32>) -> bool {
    return pm_in_range(position, center, radius) && cell_owns(box, cell, position);
}

// WhileQuery: finds the next photon in range over all cells, then processes it, so threads
// of a warp process photons together whatever the cells' sizes.
fn grid_while_query(m: ptr<function, Merge>, box: CellBox) {
    var walk = cell_walk(box);
    var range = grid_reached_bucket(walk.cell, *m);
    var i = range.x;
    loop {
        var found = false;
        loop {
            if (i < range.y) {
                let position = grid_positions[i].xyz;
                i += 1u;
                if (grid_keeps(position, (*m).position, (*m).radius, box, walk.cell)) {
                    found = true;
                    break;
                }
                continue;
            }
            if (!cell_walk_next(&walk)) {
                break;
            }
            range = grid_reached_bucket(walk.cell, *m);
            i = range.x;
        }
        if (!found) {
            break;
        }
        merge_photon(m, grid_photons[i - 1u], 1.0);
    }
}
