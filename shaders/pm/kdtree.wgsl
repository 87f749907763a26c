// The kD-tree over the photons (PM_STRUCTURE 3), built on the GPU from a sort (Karras 2012,
// "Maximizing parallelism in the construction of BVHs, octrees and k-d trees"), queried
// without a stack. Passes in order (passes/kdtree.ron):
// - `kd_codes` (Start over the stored photons): each photon's 30-bit Morton code (10 bits an
//   axis) of its cell of a 1024^3 grid over the cube [pm_origin(), pm_origin() +
//   pm_extent()]^3, into `kd_codes`, and its index into `kd_index`;
// - the engine's `Sort` of the codes with the indices (stable, so equal codes keep the
//   photons' order);
// - `kd_build` (Start over the stored photons): thread i copies the i-th photon in code order
//   into `kd_photons` (leaf i) and, for i < n - 1, builds internal node i of the binary radix
//   tree over the sorted codes, the index breaking ties between equal codes. Each internal
//   node covers a range of leaves sharing a prefix of their codes and splits it where the
//   next bit changes: an axis-aligned plane through the middle of its cell, so the tree is a
//   kD-tree with midpoint splits whose node boxes follow from the prefixes;
// - `kd_gather` (Loop over MergePath): a depth-first walk in the leaves' order with escape
//   links instead of a stack: a node whose box meets the query's box goes on to its first
//   child, any other node, and every leaf, to the node after its subtree.
//
// Memory per photon: a 12-byte internal node (`KdNode`) in `kd_nodes` and the photon itself
// (32 bytes) in `kd_photons` for the gather; `kd_codes` and `kd_index` (4 bytes each) live
// only until `kd_build`. 1.8 M photons take a 21.6 MB tree besides the photons.
//
// A node reference (KdNode.child, KdNode.escape, the walk's position) is a u32: the internal
// node's index, or with KD_LEAF set a leaf's (the photon's place in `kd_photons`); KD_END
// (all ones) ends the walk. The root is internal node 0 (leaf 0 for a single photon).
//
// Exactness: the gather calls merge_photon for exactly the photons with pm_in_range. Cells
// are computed by one function that is monotone in each coordinate (photons outside the cube
// land in its border cells), and the query's box of cells is that of its bounding box widened
// by a margin above the rounding of the cell computations, so a photon in range is in a
// cell of the query's box, and every node holding it meets that box.

const KD_LEAF: u32 = 0x80000000u;
const KD_END: u32 = 0xffffffffu;
// KdNode.cell: set when the node's range of leaves starts at its own index.
const KD_STARTS: u32 = 0x80000000u;
// Cells of the Morton grid along each axis, and the bits of a code.
const KD_AXIS_CELLS: f32 = 1024.0;
const KD_CODE_BITS: u32 = 30u;

// An internal node (12 bytes):
// - `child`: bytes 0-3, its first child (a node reference): the lower half of its range;
// - `escape`: bytes 4-7, the node the walk visits after its subtree (a node reference):
//   internal node last + 1 if that node's range starts there, else leaf last + 1, or KD_END
//   after the last leaf (last: the range's last leaf);
// - `cell`: bytes 8-11, bit 31 KD_STARTS; bits 0-30 the prefix its leaves' codes share, of
//   L bits (0 to 30), below a marker bit: (code >> (30 - L)) | (1 << L). The node's box is
//   the cells whose codes have the prefix (a Morton cell: 2^(30 - L) cells of the grid).
struct KdNode {
    child: u32,
    escape: u32,
    cell: u32,
}

// Pass `kd_codes` (Start over the stored photons): the photon's Morton code and index.
fn kd_encode(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    let c = kd_cell(pm_staging[index].position, kd_scale());
    kd_codes[index] = morton_code(c);
    kd_index[index] = index;
    return false;
}

// Pass `kd_build` (Start over the stored photons, after the sort): leaf `index` and internal
// node `index`.
fn kd_build(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    let n = kd_total();
    kd_photons[index] = pm_staging[kd_index[index]];
    if (index + 1u < n) {
        kd_nodes[index] = kd_node(i32(index), n);
    }
    return false;
}

// Pass `kd_gather` (Loop over MergePath): the pending density estimation, if any.
fn kd_gather(p: ptr<function, MergePath>) -> bool {
    var m = merge_begin(*p);
    if (m.pending) {
        kd_query(&m);
        merge_end(p, m);
    }
    return true;
}

// The photons in the tree this frame.
fn kd_total() -> u32 {
    return min(atomicLoad(&pm_count), arrayLength(&kd_photons));
}

// Cells per unit length.
fn kd_scale() -> f32 {
    let e = pm_extent();
    return select(0.0, KD_AXIS_CELLS / e, e > 0.0);
}

// The cell of a point, clamped to the grid (monotone in each coordinate).
fn kd_cell(position: vec3<f32>, scale: f32) -> vec3<u32> {
    let c = floor((position - pm_origin()) * scale);
    return vec3<u32>(clamp(c, vec3<f32>(0.0), vec3<f32>(KD_AXIS_CELLS - 1.0)));
}

// Every third bit of `v` (from bit 0) into 10 bits: the inverse of morton_spread (shaders/lib/scene.wgsl).
fn kd_compact(v: u32) -> u32 {
    var x = v & 0x09249249u;
    x = (x | (x >> 2u)) & 0x030c30c3u;
    x = (x | (x >> 4u)) & 0x0300f00fu;
    x = (x | (x >> 8u)) & 0x030000ffu;
    x = (x | (x >> 16u)) & 0x3ffu;
    return x;
}

// Length of the prefix sorted keys i and j share (their places breaking ties between equal
// codes, 32 more), or -1 when j is not a key (of n).
fn kd_delta(i: i32, j: i32, n: u32) -> i32 {
    if (j < 0 || j >= i32(n)) {
        return -1;
    }
    let a = kd_codes[i];
    let b = kd_codes[j];
    if (a == b) {
        return 32 + i32(countLeadingZeros(u32(i ^ j)));
    }
    return i32(countLeadingZeros(a ^ b));
}

// +1 when internal node i's range starts at i, -1 when it ends there.
fn kd_direction(i: i32, n: u32) -> i32 {
    return select(-1, 1, kd_delta(i, i + 1, n) > kd_delta(i, i - 1, n));
}

// The node the walk visits after a range ending at leaf `last`.
fn kd_after(last: i32, n: u32) -> u32 {
    let next = last + 1;
    if (next >= i32(n)) {
        return KD_END;
    }
    if (next + 1 < i32(n) && kd_direction(next, n) > 0) {
        return u32(next);
    }
    return u32(next) | KD_LEAF;
}

// Internal node i of the tree over n sorted codes (Karras 2012, Figure 4): its range, then
// the split, found by binary searches over the shared prefix lengths.
fn kd_node(i: i32, n: u32) -> KdNode {
    let d = kd_direction(i, n);
    let outside = kd_delta(i, i - d, n);
    var reach = 2;
    while (kd_delta(i, i + reach * d, n) > outside) {
        reach *= 2;
    }
    var length = 0;
    for (var t = reach / 2; t > 0; t /= 2) {
        if (kd_delta(i, i + (length + t) * d, n) > outside) {
            length += t;
        }
    }
    let j = i + length * d;
    let prefix_length = kd_delta(i, j, n);
    var s = 0;
    var t = length;
    loop {
        t = (t + 1) / 2;
        if (kd_delta(i, i + (s + t) * d, n) > prefix_length) {
            s += t;
        }
        if (t <= 1) {
            break;
        }
    }
    let split = i + s * d + min(d, 0);
    let child = select(u32(split), u32(split) | KD_LEAF, min(i, j) == split);
    // Codes are 30 bits of 32: two leading zeros more than the prefix.
    let bits = u32(min(prefix_length - 2, i32(KD_CODE_BITS)));
    let prefix = (kd_codes[i] >> (KD_CODE_BITS - bits)) | (1u << bits);
    return KdNode(child, kd_after(max(i, j), n), prefix | select(0u, KD_STARTS, d > 0));
}

// The node the walk visits after leaf i (of n), from the flags of internal node i + 1.
fn kd_leaf_after(i: u32, n: u32) -> u32 {
    let next = i + 1u;
    if (next >= n) {
        return KD_END;
    }
    if (next + 1u < n && (kd_nodes[next].cell & KD_STARTS) != 0u) {
        return next;
    }
    return next | KD_LEAF;
}

// Whether the box of the node with `cell` meets the box of cells lo ..= hi.
fn kd_meets(cell: u32, lo: vec3<u32>, hi: vec3<u32>) -> bool {
    let prefix = cell & ~KD_STARTS;
    let bits = firstLeadingBit(prefix);
    let free = KD_CODE_BITS - bits;
    let first = (prefix ^ (1u << bits)) << free;
    let low = vec3<u32>(kd_compact(first), kd_compact(first >> 1u), kd_compact(first >> 2u));
    // The free bits of each axis: x holds code bits 0, 3, 6, ..., y 1, 4, ..., z 2, 5, ...
    let span = vec3<u32>((free + 2u) / 3u, (free + 1u) / 3u, free / 3u);
    let high = low + (vec3<u32>(1u) << span) - vec3<u32>(1u);
    return all(low <= hi) && all(high >= lo);
}

// Every photon within the query's radius, to merge_photon.
fn kd_query(m: ptr<function, Merge>) {
    let n = kd_total();
    let center = (*m).position;
    let radius = (*m).radius;
    // Above the rounding of center -+ reach and of the cell computations (a few ulps of the
    // coordinates), so the query's box of cells holds every photon in range.
    let size = abs(center);
    let margin = (max(max(size.x, size.y), size.z) + 2.0 * radius + pm_extent()) * 4e-6;
    let reach = vec3<f32>(radius + margin);
    let scale = kd_scale();
    let lo = kd_cell(center - reach, scale);
    let hi = kd_cell(center + reach, scale);
    var node = select(select(KD_END, KD_LEAF, n == 1u), 0u, n > 1u);
    loop {
        if (node == KD_END) {
            break;
        }
        let i = node & ~KD_LEAF;
        if ((node & KD_LEAF) != 0u) {
            if (pm_in_range(kd_photons[i].position, center, radius)) {
                merge_photon(m, kd_photons[i], 1.0);
            }
            node = kd_leaf_after(i, n);
        } else {
            let k = kd_nodes[i];
            node = select(k.escape, k.child, kd_meets(k.cell, lo, hi));
        }
    }
}
