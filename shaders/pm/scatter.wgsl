// Continuing a photon-mapping sub-path (light or camera) from a vertex, with the MIS quantity
// of bidirectional photon mapping. PBPM (Vorba 2011) is VCM with merging alone (Georgiev et al.
// 2012, "Implementing vertex connection and merging", with the connection factor 0): a
// sub-path carries one quantity, dVM, which at a vertex is the sum over the merges at earlier
// vertices of the ratio of their densities to this one's (the power heuristic with MIS_POWER).
// It starts at 0, is divided by the cosine at each vertex it arrives at, and scatters as below.
// PPM and SPPM leave it at 0.

// A sub-path continued from a vertex: the next ray, the throughput and dVM after it, and
// whether the sampled lobe was a delta one.
struct PmScatter {
    origin: vec3<f32>,
    direction: vec3<f32>,
    throughput: vec3<f32>,
    d_vm: f32,
    specular: bool,
    alive: bool,
}

// Samples the next direction from `bsdf` (a full BSDF, or one of its parts for SPPM) with
// Russian roulette (its continuation probability), which ends the sub-path when it fails.
fn pm_scatter(bsdf: Bsdf, s: Surface, throughput: vec3<f32>, d_vm: f32, rng: ptr<function, u32>) -> PmScatter {
    var r = PmScatter(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false, false);
    let u = vec3<f32>(rng_vec2(rng), rng_f32(rng));
    let roulette_u = rng_f32(rng);
    if (!bsdf.valid) {
        return r;
    }
    let smp = bsdf_sample(bsdf, u);
    let q = bsdf.continuation;
    if (is_black(smp.f) || roulette_u >= q) {
        return r;
    }
    let pdf = smp.pdf * q;
    if (PM_MODE != PM_PBPM) {
        // PPM and SPPM never read dVM: no reverse density (a second BSDF evaluation).
    } else if (smp.specular) {
        r.d_vm = mis_clamp(d_vm * mis_pow(smp.cos_gen));
    } else {
        let reverse = bsdf_eval(bsdf, smp.direction).pdf_reverse * q;
        r.d_vm = mis_clamp(mis_pow(smp.cos_gen / pdf) * (d_vm * mis_pow(reverse) + 1.0));
    }
    r.throughput = throughput * smp.f * (smp.cos_gen / pdf);
    r.origin = offset_ray_origin(s.position, side_normal(s.normal, smp.direction), s.extent);
    r.direction = smp.direction;
    r.specular = smp.specular;
    r.alive = true;
    return r;
}
