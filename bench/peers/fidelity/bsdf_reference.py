#!/usr/bin/env python3
"""Mitsuba 3's own BSDF values, as reference data for lightgraph's tests (issue 57).

  python3 bench/peers/fidelity/bsdf_reference.py diffuse > tests/data/mitsuba/roughplastic-diffuse.txt
  python3 bench/peers/fidelity/bsdf_reference.py eval > tests/data/mitsuba/bsdf-eval.txt
  python3 bench/peers/fidelity/bsdf_reference.py monte-carlo > tests/data/mitsuba/roughplastic-coating.txt

`diffuse`: `roughplastic`'s diffuse lobe alone (`BSDFContext.component = 1`) at pairs of cosines,
for both distributions, alphas 0.001-1 and relative indices 1.0001-3 (ext_ior 1): the values hold
its tabulated rough-coating transmittance and internal reflectance. `eval`: whole BSDFs
(`bsdf.eval`, all lobes) of `roughplastic`, `roughdielectric` and `roughconductor` at pairs of
directions. Values are Mitsuba's (f cos(wo), wi towards the previous vertex, radiance
transport), variant scalar_rgb, first channel or RGB. `monte-carlo`: the rough coating's
transmittance T(mu) and reflectance from inside R(mu) (relative index 1 / eta) that roughplastic
tabulates, as means over 2^24 normals drawn by Mitsuba's own visible-normal sampler (variant
llvm_ad_rgb), with their standard errors: the integrals Mitsuba's tables approximate (by a
32 x 32 Gauss-Legendre rule over the sampler's square, 128 x 128 for eta < 1).
"""
import math
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

ALPHAS = [0.001, 0.01, 0.1, 0.3, 0.6, 1.0]
IORS = [1.0001, 1.1, 1.33, 1.5, 2.0, 3.0]
COSINE_PAIRS = [(1.0, 1.0), (0.9, 0.05), (0.5, 0.73), (0.2, 0.37), (0.013, 0.6), (0.0021, 0.999)]

# Whole BSDFs: the <bsdf> element as lightgraph's test loads it through the Mitsuba importer.
EVAL_CASES = [
    '<bsdf type="roughplastic"/>',
    '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/>'
    '<float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>',
    '<bsdf type="roughplastic"><float name="alpha" value="1"/><float name="int_ior" value="3"/>'
    '<float name="ext_ior" value="1"/><rgb name="diffuse_reflectance" value="0.9, 0.9, 0.9"/></bsdf>',
    '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.01"/>'
    '<float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf>',
    '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>'
    '<rgb name="diffuse_reflectance" value="0.2, 0.5, 0.8"/><boolean name="nonlinear" value="true"/></bsdf>',
    '<bsdf type="roughplastic"><float name="alpha" value="0.001"/><float name="int_ior" value="2"/>'
    '<float name="ext_ior" value="1"/></bsdf>',
    '<bsdf type="roughplastic"><float name="alpha" value="0.5"/><float name="int_ior" value="1.0001"/>'
    '<float name="ext_ior" value="1"/></bsdf>',
    '<bsdf type="roughdielectric"/>',
    '<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/></bsdf>',
    '<bsdf type="roughconductor"/>',
    '<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>'
    '<rgb name="eta" value="0.143, 0.374, 1.442"/><rgb name="k" value="3.983, 2.385, 1.603"/></bsdf>',
    '<bsdf type="roughconductor"><rgb name="eta" value="1.657, 0.880, 0.521"/>'
    '<rgb name="k" value="9.224, 6.270, 4.837"/></bsdf>',
]


def direction(cos_theta, phi):
    """A unit vector in float32 (as Mitsuba evaluates it, and printed so that it reads back
    exactly)."""
    s = math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
    return [float(np.float32(x)) for x in (s * math.cos(phi), s * math.sin(phi), cos_theta)]


def evaluate(bsdf, wi, wo, component=None):
    ctx = mi.BSDFContext()
    if component is not None:
        ctx.component = component
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi)
    return bsdf.eval(ctx, si, mi.Vector3f(*wo))


def diffuse():
    print("# roughplastic's diffuse lobe (diffuse_reflectance 0.5, ext_ior 1): Mitsuba", mi.__version__)
    print("# case DISTRIBUTION ALPHA INT_IOR, then rows: cos_i cos_o value (f cos_o)")
    for distribution in ["beckmann", "ggx"]:
        for alpha in ALPHAS:
            for ior in IORS:
                bsdf = mi.load_dict({"type": "roughplastic", "distribution": distribution, "alpha": alpha,
                                     "int_ior": ior, "ext_ior": 1.0,
                                     "diffuse_reflectance": {"type": "rgb", "value": [0.5] * 3}})
                print(f"case {distribution} {alpha} {ior}")
                for ci, co in COSINE_PAIRS:
                    value = evaluate(bsdf, direction(ci, 0.0), direction(co, 2.0), component=1)[0]
                    print(f"{ci} {co} {value:.8e}")


def eval_pairs():
    """Pairs of directions: random ones above the surface, near the mirror direction, below it
    (transmission), from below, and grazing ones (a fixed generator: the file is reproducible)."""
    rng = __import__("random").Random(57)
    pairs = []
    for k in range(24):
        wi = direction(rng.uniform(0.02, 1.0), rng.uniform(0, 2 * math.pi))
        if k < 8:
            wo = direction(rng.uniform(0.02, 1.0), rng.uniform(0, 2 * math.pi))
        elif k < 14:
            # Near the mirror direction of wi.
            phi = math.atan2(wi[1], wi[0]) + math.pi + rng.uniform(-0.2, 0.2)
            wo = direction(min(1.0, max(0.02, wi[2] + rng.uniform(-0.15, 0.15))), phi)
        elif k < 18:
            wo = direction(-rng.uniform(0.05, 1.0), rng.uniform(0, 2 * math.pi))
        elif k < 21:
            wi = direction(-rng.uniform(0.05, 1.0), rng.uniform(0, 2 * math.pi))
            wo = direction(rng.choice([-1, 1]) * rng.uniform(0.05, 1.0), rng.uniform(0, 2 * math.pi))
        else:
            wi = direction(rng.uniform(0.01, 0.12), 0.3)
            wo = direction(rng.uniform(0.01, 0.5), 0.3 + math.pi + rng.uniform(-0.3, 0.3))
        pairs.append((wi, wo))
    return pairs


def eval_cases():
    print("# whole BSDFs (bsdf.eval, radiance): Mitsuba", mi.__version__)
    print("# case <bsdf .../>, then rows: wi_x wi_y wi_z wo_x wo_y wo_z r g b (f cos_o)")
    for xml in EVAL_CASES:
        bsdf = mi.load_string(xml.replace("<bsdf ", '<bsdf version="3.0.0" ', 1))
        print(f"case {xml}")
        for wi, wo in eval_pairs():
            v = evaluate(bsdf, wi, wo)
            numbers = " ".join(f"{x:.9g}" for x in wi + wo) + " " + " ".join(f"{v[c]:.8e}" for c in range(3))
            print(numbers)


MONTE_CARLO_CASES = [
    ("beckmann", 0.1, 1.5), ("beckmann", 0.3, 3.0), ("beckmann", 1.0, 1.1), ("beckmann", 0.01, 1.33),
    ("ggx", 0.001, 1.5), ("ggx", 0.3, 1.5), ("ggx", 0.3, 3.0), ("ggx", 1.0, 2.0), ("ggx", 0.1, 0.7),
    ("beckmann", 0.6, 0.7),
]
MONTE_CARLO_COSINES = [1e-6, 1 / 63, 0.2, 0.5, 0.9, 1.0]


def coating_means(distribution, alpha, eta, mu, reflection, n=1 << 24):
    """Mean and standard error of (1 - F) G1(wt) (refraction into eta) or F G1(wr)
    (reflection, eta the relative index beyond) over n normals visible from cosine mu."""
    import drjit as dr

    kind = mi.MicrofacetType.GGX if distribution == "ggx" else mi.MicrofacetType.Beckmann
    distr = mi.MicrofacetDistribution(kind, alpha, True)
    rng = np.random.default_rng(57)
    u = mi.Point2f(mi.Float(rng.random(n, dtype=np.float32)), mi.Float(rng.random(n, dtype=np.float32)))
    wi = mi.Vector3f(math.sqrt(1 - mu * mu), 0.0, mu)
    m = distr.sample(wi, u)[0]
    f, cos_t, _, eta_ti = mi.fresnel(dr.dot(wi, m), mi.Float(eta))
    if reflection:
        wo = mi.reflect(wi, m)
        value = dr.select(wo.z > 0, f * distr.smith_g1(wo, m), 0.0)
    else:
        wo = mi.refract(wi, m, cos_t, eta_ti)
        value = dr.select(wo.z < 0, (1 - f) * distr.smith_g1(wo, m), 0.0)
    v = np.array(value, dtype=np.float64)
    v = v[np.isfinite(v)]
    return v.mean(), v.std() / math.sqrt(len(v))


def monte_carlo():
    import os

    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
    mi.set_variant("llvm_ad_rgb")
    print("# roughplastic's coating by Monte Carlo over Mitsuba's visible-normal sampler: Mitsuba", mi.__version__)
    print("# rows: DISTRIBUTION ALPHA ETA MU T T_SE R R_SE (R: from inside, relative index 1 / ETA)")
    for distribution, alpha, eta in MONTE_CARLO_CASES:
        for mu in MONTE_CARLO_COSINES:
            t, t_se = coating_means(distribution, alpha, eta, mu, False)
            r, r_se = coating_means(distribution, alpha, 1.0 / eta, mu, True)
            print(f"{distribution} {alpha} {eta} {mu:.9g} {t:.8f} {t_se:.2e} {r:.8f} {r_se:.2e}")


if __name__ == "__main__":
    {"diffuse": diffuse, "eval": eval_cases, "monte-carlo": monte_carlo}[sys.argv[1]]()
