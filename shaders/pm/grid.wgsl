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

// NaiveQuery: every cell's photons in turn, four at a time: their positions are read together
// (four loads in flight at once, not one round trip after another), then the photons in range
// are merged in order.
fn grid_naive_query(m: ptr<function, Merge>, box: CellBox) {
    var walk = cell_walk(box);
    loop {
        let range = grid_reached_bucket(walk.cell, *m);
        for (var i = range.x; i < range.y; i += 4u) {
            let at = grid_four(i, range.y);
            var found = grid_four_kept(
                grid_photons[at.x].position, grid_photons[at.y].position, grid_photons[at.z].position, grid_photons[at.w].position,
                i, range.y, (*m).position, (*m).radius, box, walk.cell,
            );
            while (found != 0u) {
                let k = firstTrailingBit(found);
                found &= found - 1u;
                merge_photon(m, grid_photons[i + k], 1.0);
            }
        }
        if (!cell_walk_next(&walk)) {
            break;
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
                let position = grid_photons[i].position;
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
