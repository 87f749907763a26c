// Stochastic hash grids (Hachisuka and Jensen 2010): one photon kept per bucket
// (shaders/pm/cells.wgsl), standing for all `sg_count[b]` photons of the bucket, so a query
// reads at most one photon per cell. The photons stay where the light pass stored them in
// `pm_staging`; a bucket holds the index of its kept photon (`sg_pick`), so no record is
// ever half-written by two threads.
// - Original (PM_STRUCTURE 2): the last photon written wins, during photon tracing
//   (`sg_insert_last`, right after the light pass stores it). Photons of longer sub-paths
//   come later and win more often: the bias Davidovic et al. 2014 show (Figure 8).
// - Rectified (PM_STRUCTURE 1, Davidovic et al. 2014, section 6.2): reservoir sampling
//   without races: every photon draws a random 32-bit key, `sg_keys` keeps each bucket's
//   largest with an atomic max, and `sg_pick` lets the photon holding it write its index.
//   Every photon of a bucket is kept with the same probability, whatever the order. The key
//   hashes the photon, not its slot, so the photons kept do not depend on the threads' order.

// Pass `sg_insert_last` (Loop over PhotonPath, after `pm_bounce`): the photon just stored
// replaces the bucket's.
fn sg_insert_last(p: ptr<function, PhotonPath>) -> bool {
    let i = (*p).stored;
    if (i != PM_NONE) {
        let b = cell_bucket(cell_of(pm_staging[i].position));
        atomicAdd(&sg_count[b], 1u);
        atomicStore(&sg_pick[b], i);
    }
    return true;
}

// The random key of a stored photon this frame: a hash of the frame and the photon's position
// and direction (not its slot: the light pass's atomics hand slots out in the threads' order).
fn sg_key_of(photon: Photon) -> u32 {
    let bits = bitcast<vec3<u32>>(photon.position);
    var key = rng_seed(frame.seed ^ 0x85ebca6bu, frame.index, bits.x);
    key = rng_hash(key ^ bits.y);
    key = rng_hash(key ^ bits.z);
    return rng_hash(key ^ photon.direction_length);
}

// Pass `sg_keys` (Start over the stored photons): counts the photon in its bucket and offers
// its key.
fn sg_keys(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    let photon = pm_staging[index];
    let b = cell_bucket(cell_of(photon.position));
    atomicAdd(&sg_count[b], 1u);
    atomicMax(&sg_key[b], sg_key_of(photon));
    return false;
}

// Pass `sg_pick` (Start over the stored photons): the photon with its bucket's largest key
// writes its index (equal keys, 2^-32 apart or of photons at one point from one direction,
// write one of them).
fn sg_pick_winner(p: ptr<function, PhotonSlot>, index: u32) -> bool {
    (*p).index = index;
    let photon = pm_staging[index];
    let b = cell_bucket(cell_of(photon.position));
    if (atomicLoad(&sg_key[b]) == sg_key_of(photon)) {
        atomicStore(&sg_pick[b], index);
    }
    return false;
}

// Pass `sg_gather` (Loop over MergePath): the pending density estimation, if any, from the
// kept photon of each cell's bucket.
fn sg_gather(p: ptr<function, MergePath>) -> bool {
    var m = merge_begin(*p);
    if (m.pending) {
        let box = cell_box(m.position, m.radius);
        var walk = cell_walk(box);
        loop {
            let b = cell_bucket(walk.cell);
            var n = 0u;
            if (cell_reaches(walk.cell, m.position, m.radius)) {
                n = atomicLoad(&sg_count[b]);
            }
            if (n > 0u) {
                let photon = pm_staging[atomicLoad(&sg_pick[b])];
                if (pm_in_range(photon.position, m.position, m.radius) && cell_owns(box, walk.cell, photon.position)) {
                    merge_photon(&m, photon, f32(n));
                }
            }
            if (!cell_walk_next(&walk)) {
                break;
            }
        }
        merge_end(p, m);
    }
    return true;
}
