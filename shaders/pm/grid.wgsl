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
//
// A query with a cell whose bucket holds more than PM_SPLIT_ENTRIES entries (a dense spot: a
// lamp's shade, a caustic) would hold its warp for as long as one thread walks them all, so
// NaiveQuery splits it (`grid_split`): the thread walks the cells before that one, ends its
// part of the estimate, and leaves the rest of the walk to `grid_split_gather` in parts of
// PM_SPLIT_CHUNK entries, one thread a part; each part ends on its own (the estimate is a sum,
// so the parts add up to it in the pixel). A split query k records its item
// (`grid_split_paths[k]`), its parts (`grid_split_sizes[k]`) and the entries of its walk before
// them (`grid_split_skip[k]`); a Scan of the sizes gives each query its first part
// (`grid_split_first`), and the thread of part i finds its query by binary search there. Room:
// PM_SPLIT_QUERIES queries and PM_SPLIT_PARTS parts a frame; a query that finds none walks its
// cells itself. PM_SPLIT_ENTRIES 0 never splits; WhileQuery does not.

// A part of a split query, the item of `grid_split_gather`.
struct SplitPart {
    index: u32,
}

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
            grid_naive_query(&m, box, p);
        }
        merge_end(p, m);
    }
    return true;
}

// NaiveQuery: every cell's photons in turn, four at a time (as `grid_walk_entries`). At the
// first cell whose bucket holds more than PM_SPLIT_ENTRIES entries the rest of the walk is
// split over threads (`grid_split`, which records the query's item `path`), or walked on where
// there is no room.
fn grid_naive_query(m: ptr<function, Merge>, box: CellBox, path: ptr<function, MergePath>) {
    var walk = cell_walk(box);
    var split = PM_SPLIT_ENTRIES;
    loop {
        let range = grid_reached_bucket(walk.cell, *m);
        if (split > 0u && range.y - range.x > split) {
            if (grid_split(*path, *m, walk.cell)) {
                return;
            }
            split = 0u;
        }
        // `grid_walk_entries` written out: called here, it made the camera kernel 12-20% slower
        // on ModernHall on an H100 (docs/performance.md, "Queries split over threads").
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

// Entries `first` .. `end` of the bucket of `cell`, four at a time: their positions are read
// together (four loads in flight at once, not one round trip after another), then the photons
// in range are merged in order.
fn grid_walk_entries(m: ptr<function, Merge>, first: u32, end: u32, box: CellBox, cell: vec3<i32>) {
    for (var i = first; i < end; i += 4u) {
        let at = grid_four(i, end);
        var found = grid_four_kept(
            grid_photons[at.x].position, grid_photons[at.y].position, grid_photons[at.z].position, grid_photons[at.w].position,
            i, end, (*m).position, (*m).radius, box, cell,
        );
        while (found != 0u) {
            let k = firstTrailingBit(found);
            found &= found - 1u;
            merge_photon(m, grid_photons[i + k], 1.0);
        }
    }
}

// Splits the rest of query `m`'s walk, from cell `from_cell` on, into parts of PM_SPLIT_CHUNK
// entries for `grid_split_gather`, recording the query's item `path`; false when there is no
// room for the query or its parts.
fn grid_split(path: MergePath, m: Merge, from_cell: vec3<i32>) -> bool {
    let query = atomicAdd(&grid_split_count, 1u);
    if (query >= PM_SPLIT_QUERIES) {
        return false;
    }
    let walked = grid_entries_before(m, from_cell);
    let parts = (walked.y + PM_SPLIT_CHUNK - 1u) / PM_SPLIT_CHUNK;
    let first = atomicAdd(&grid_split_parts, parts);
    let fits = first < PM_SPLIT_PARTS && parts <= PM_SPLIT_PARTS - first;
    grid_split_sizes[query] = select(0u, parts, fits);
    if (fits) {
        grid_split_skip[query] = walked.x;
        grid_split_paths[query] = path;
        count(COUNTER_PM_SPLIT, 1u);
        count(COUNTER_PM_SPLIT_PARTS, parts);
    }
    return fits;
}

// The entries of query `m`'s walk before cell `cell` and from it on.
fn grid_entries_before(m: Merge, cell: vec3<i32>) -> vec2<u32> {
    var walk = cell_walk(cell_box(m.position, m.radius));
    var entries = vec2<u32>(0u);
    var rest = false;
    loop {
        rest = rest || all(walk.cell == cell);
        let range = grid_reached_bucket(walk.cell, m);
        entries[u32(rest)] += range.y - range.x;
        if (!cell_walk_next(&walk)) {
            break;
        }
    }
    return entries;
}

// Pass `grid_split_gather` (Start over the parts of split queries): the part's PM_SPLIT_CHUNK
// entries of its query's walk (the cells in `grid_naive_query`'s order), ended as an estimate
// of its own.
fn grid_split_gather(part: ptr<function, SplitPart>, index: u32) -> bool {
    (*part).index = index;
    let query = grid_split_query(index);
    let j = index - grid_split_first[query];
    if (j >= grid_split_sizes[query]) {
        return false;
    }
    var path = grid_split_paths[query];
    var m = merge_resume(path);
    let box = cell_box(m.position, m.radius);
    var walk = cell_walk(box);
    var skip = grid_split_skip[query] + j * PM_SPLIT_CHUNK;
    var left = PM_SPLIT_CHUNK;
    loop {
        let range = grid_reached_bucket(walk.cell, m);
        let size = range.y - range.x;
        if (skip >= size) {
            skip -= size;
        } else {
            let first = range.x + skip;
            let end = range.x + min(size, skip + left);
            grid_walk_entries(&m, first, end, box, walk.cell);
            left -= end - first;
            skip = 0u;
        }
        if (left == 0u || !cell_walk_next(&walk)) {
            break;
        }
    }
    merge_end(&path, m);
    return false;
}

// The split query whose parts hold part `index`: the last with its first part at or before it
// (queries without parts share their successor's first part and are passed over), the last
// query when `index` is past all parts (whose size then rules it out).
fn grid_split_query(index: u32) -> u32 {
    var lo = 0u;
    var hi = max(min(atomicLoad(&grid_split_count), PM_SPLIT_QUERIES), 1u);
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (grid_split_first[mid] <= index) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
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
