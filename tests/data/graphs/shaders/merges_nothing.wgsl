// No photon found is merged.
fn pm_merges_photon(m: Merge, photon: Photon) -> bool {
    return false;
}
