// No photon at any vertex.
fn pm_stores_photon(p: ptr<function, PhotonPath>, a: Arrival) -> bool {
    return false;
}
