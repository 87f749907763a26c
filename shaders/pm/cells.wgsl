// The hash grid's cells, shared by the full and the stochastic hash grids: the space is cut
// into cubes of side 2 pm_cell_radius() from pm_origin(), and cell c goes to bucket
// 8 hash(c >> 1) mod PM_CELLS / 8 + (the parities of c's coordinates), with a multiply-xor
// hash (`hash_cell`). A query of radius r <= pm_cell_radius() covers at most 2 cells along each
// axis, whose parities differ, so its (at most) 8 cells land in distinct buckets and no
// bucket is read twice. Coordinates are relative to the origin (no bounds: the hash takes
// any cell), and the query's box of cells is widened by a margin above the rounding error
// of the cell computations, so a photon within r is never in a cell the query skips.

// A query's box of cells, and whether its cells' buckets are distinct (at most 2 cells along
// each axis). Otherwise a bucket may hold several of the box's cells, and a gather keeps a
// photon only in the visit of its own cell.
struct CellBox {
    lo: vec3<i32>,
    hi: vec3<i32>,
    distinct: bool,
}

// The cell side.
fn cell_size() -> f32 {
    return 2.0 * pm_cell_radius();
}

// The cell of a point.
fn cell_of(position: vec3<f32>) -> vec3<i32> {
    return vec3<i32>(floor((position - pm_origin()) / cell_size()));
}

// Above the rounding error of the cell computations for a query of `radius`.
fn cell_margin(radius: f32) -> f32 {
    return radius * 1e-4 + pm_extent() * 1e-5;
}

// The cells a query of `radius` around `center` must visit.
fn cell_box(center: vec3<f32>, radius: f32) -> CellBox {
    let margin = cell_margin(radius);
    let c = center - pm_origin();
    let size = cell_size();
    let lo = vec3<i32>(floor((c - radius - margin) / size));
    let hi = vec3<i32>(floor((c + radius + margin) / size));
    return CellBox(lo, hi, all(hi - lo <= vec3<i32>(1)));
}

// A hash of three words: each times an odd constant, xored, then an xor-shift and a multiply
// to mix the high bits down. Its multiplies are independent, so a merge's walk waits a few
// instructions per cell where lookup3's final mix (21 dependent steps) took several times as
// long: on an H100 VCMsk 0.8% faster on Sponza, 0.4% on the diffuse box, PPMsk 0.5% on the
// box (docs/performance.md, "A gather a word a thread, a cheaper cell hash").
fn hash_cell(a: u32, b: u32, c: u32) -> u32 {
    var h = (a * 0x8da6b343u) ^ (b * 0xd8163841u) ^ (c * 0xcb1ab31fu);
    h ^= h >> 15u;
    return h * 0x2c1b3c6du;
}

// The bucket of cell `c` (PM_CELLS buckets, a multiple of 8).
fn cell_bucket(c: vec3<i32>) -> u32 {
    return cell_bucket_among(c, 0u, PM_CELLS / 8u);
}

// The bucket of cell `c` among the `groups` groups of 8 buckets from group `first` on (a grid
// of its own in part of the buckets, as each of VCM's iterations of a frame has).
fn cell_bucket_among(c: vec3<i32>, first: u32, groups: u32) -> u32 {
    let pair = vec3<u32>(c >> vec3<u32>(1u));
    let parity = vec3<u32>(c & vec3<i32>(1));
    let group = first + hash_cell(pair.x, pair.y, pair.z) % groups;
    return group * 8u + parity.x + 2u * parity.y + 4u * parity.z;
}

// Walks a box of cells in x, then y, then z order.
struct CellWalk {
    box: CellBox,
    cell: vec3<i32>,
}

fn cell_walk(box: CellBox) -> CellWalk {
    return CellWalk(box, box.lo);
}

// The next cell; false after the last.
fn cell_walk_next(w: ptr<function, CellWalk>) -> bool {
    var c = (*w).cell;
    c.x += 1;
    if (c.x > (*w).box.hi.x) {
        c.x = (*w).box.lo.x;
        c.y += 1;
        if (c.y > (*w).box.hi.y) {
            c.y = (*w).box.lo.y;
            c.z += 1;
        }
    }
    (*w).cell = c;
    return c.z <= (*w).box.hi.z;
}

// Whether `cell` comes within `radius` (and the margin) of `center`: the box's other cells
// (those only its corners touch) hold no photon in range and are skipped. Nothing in range
// is missed: their buckets differ from those of the cells that reach (a box wider than 2
// cells keeps a photon only in its own cell's visit, and its cell reaches).
fn cell_reaches(cell: vec3<i32>, center: vec3<f32>, radius: f32) -> bool {
    let size = cell_size();
    let lo = pm_origin() + vec3<f32>(cell) * size;
    let d = max(max(lo - center, center - (lo + size)), vec3<f32>(0.0));
    let reach = radius + cell_margin(radius);
    return dot(d, d) <= reach * reach;
}

// Whether a photon at `position`, found in the bucket of `cell`, counts in this visit.
fn cell_owns(box: CellBox, cell: vec3<i32>, position: vec3<f32>) -> bool {
    return box.distinct || all(cell_of(position) == cell);
}
