// Caustic photons only: a photon at the first non-delta vertex of a light sub-path, when a
// delta vertex came before it (the sub-path's length is then 2 or more). `met_rough`, a field
// ppm-caustic.ron adds to `PhotonPath` (zero when the sub-path starts), remembers that the
// sub-path met a non-delta vertex; the hook is asked at every non-delta vertex.
fn pm_stores_photon(p: ptr<function, PhotonPath>, a: Arrival) -> bool {
    let caustic = (*p).met_rough == 0u && (*p).light.length >= 2u;
    (*p).met_rough = 1u;
    return caustic;
}
