"""Images with per-pixel noise, and their comparison: what the peer scripts share.

An image is its mean radiance (H x W x 3) and the per-pixel variance of that mean, read from
  - lightgraph's film EXR (R, G, B plus residual.R/G/B, and variance.R/G/B: the variance of the
    mean from the frames' spread);
  - a reference EXR that `fidelity.py reference` writes (R, G, B and variance.R/G/B from the
    spread of independent passes, `lightgraph.passes` in its header);
  - the .npz that `mitsuba_scenes.py render` writes (mean, variance).

`compare` tests two such images as `lightgraph verify` tests two runs, in luminance: the image
mean's difference in units of both images' standard error (z), and per block of B x B pixels
the z of the blocks' difference, against the two-sided normal critical value of a family-wise
level of 0.01 over the blocks (Bonferroni), a block whose noise and difference are float
rounding counting as equal (`block_z`). Pixels are independent in a path tracer's image
(each pixel's samples are its own), so a region's variance is the sum of its pixels' over the
pixel count squared.
"""
import math
import os

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def load(path):
    """(mean, variance), each H x W x 3 float64, of an EXR or .npz image with noise."""
    if path.endswith(".npz"):
        data = np.load(path)
        return data["mean"], data["variance"]
    import mitsuba as mi

    if not mi.variant():
        set_any_variant(mi)
    bitmap = mi.Bitmap(path)
    names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
    data = np.array(bitmap, dtype=np.float64)
    channel = {name: data[:, :, i] for i, name in enumerate(names)}
    missing = [f"variance.{c}" for c in "RGB" if f"variance.{c}" not in channel]
    if missing:
        raise SystemExit(f"{path}: no {', '.join(missing)} channel: not an image with its noise")
    mean = np.stack([channel[c] + channel.get(f"residual.{c}", 0.0) for c in "RGB"], axis=-1)
    variance = np.stack([channel[f"variance.{c}"] for c in "RGB"], axis=-1)
    return mean, variance


def set_any_variant(mi):
    """Sets the first variant that works: reading EXRs needs one, any will do (the slim wheel of
    the GPU machine has no scalar_rgb; cuda_* needs a GPU, llvm_* a libLLVM)."""
    for variant in ["scalar_rgb", "cuda_ad_rgb", "llvm_ad_rgb", *mi.variants()]:
        try:
            mi.set_variant(variant)
            return
        except Exception:  # not installed, or not usable on this machine
            continue
    raise SystemExit(f"no Mitsuba variant of {mi.variants()} can be set to read EXRs with")


def normal_quantile(p):
    """The standard normal's upper quantile: z with P(Z > z) = p (bisection on erfc)."""
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if 0.5 * math.erfc(mid / math.sqrt(2.0)) > p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


# As `lightgraph verify` (src/verify/stats.rs): where both images' standard error of a block is
# below ROUNDING_RELATIVE of its value (a block that sees only a constant or deterministic
# background: every sample the same but for float rounding), a difference below
# DETERMINISTIC_RELATIVE is the renderers' arithmetic, not a difference of what they estimate.
# A difference below ROUNDING of the image's mean (black blocks that one renderer fills with
# 1e-24) is rounding too.
ROUNDING = 1e-6
ROUNDING_RELATIVE = 1e-5
DETERMINISTIC_RELATIVE = 1e-3


def block_z(d, se, value, floor):
    """The z of a block's difference `d` with standard error `se` at a value of `value`: 0 for
    float rounding (`floor`: ROUNDING of the image's mean)."""
    if abs(d) <= floor or se <= ROUNDING_RELATIVE * abs(value) and abs(d) <= DETERMINISTIC_RELATIVE * abs(value):
        return 0.0
    return d / se if se > 0 else (0.0 if d == 0 else math.inf)


def compare(a, b, block):
    """Tests image `a` against image `b` (each (mean, variance)); a dict of the results:
    mean (b's image mean luminance), difference (relative), z, blocks, beyond (blocks whose |z|
    passes the critical value), worst (z, relative difference of the block with the largest
    |z|), critical, and per block, row by row: grid (rows of (z, relative difference))."""
    (ma, va), (mb, vb) = a, b
    if ma.shape != mb.shape:
        raise SystemExit(f"sizes differ: {ma.shape} and {mb.shape}")
    la, lb = ma @ LUMINANCE, mb @ LUMINANCE
    sa, sb = va @ (LUMINANCE * LUMINANCE), vb @ (LUMINANCE * LUMINANCE)
    n = la.size
    diff = la.mean() - lb.mean()
    se = math.sqrt((sa.sum() + sb.sum()) / (n * n))
    h, w = la.shape
    floor = ROUNDING * 0.5 * (la.mean() + lb.mean())
    grid = []
    for y in range(0, h - block + 1, block):
        grid.append([])
        zs = grid[-1]
        for x in range(0, w - block + 1, block):
            sl = (slice(y, y + block), slice(x, x + block))
            m = block * block
            d = la[sl].mean() - lb[sl].mean()
            s = math.sqrt((sa[sl].sum() + sb[sl].sum()) / (m * m))
            zs.append((block_z(d, s, lb[sl].mean(), floor), d / max(lb[sl].mean(), 1e-12)))
    zs = [z for line in grid for z in line]
    critical = normal_quantile(0.01 / (2 * len(zs)))
    return {
        "mean": lb.mean(),
        "difference": diff / lb.mean() if lb.mean() > 0 else 0.0,
        "z": diff / se if se > 0 else 0.0,
        "blocks": len(zs),
        "beyond": sum(1 for z in zs if abs(z[0]) > critical),
        "worst": max(zs, key=lambda z: abs(z[0])),
        "critical": critical,
        "grid": grid,
    }


def write_block_map(path, result, scale=8):
    """A PNG of `compare`'s blocks, `scale` pixels each: red where the first image is brighter,
    blue where darker, by |z| up to three times the critical value; grey within it."""
    import mitsuba as mi

    z = np.array([[b[0] for b in line] for line in result["grid"]], dtype=np.float64)
    level = np.clip(np.abs(z) / (3 * result["critical"]), 0, 1)
    beyond = np.abs(z) > result["critical"]
    rgb = np.full(z.shape + (3,), 128.0)
    rgb[..., 0] = np.where(beyond, np.where(z > 0, 128 + 127 * level, 128 * (1 - level)), 128)
    rgb[..., 2] = np.where(beyond, np.where(z < 0, 128 + 127 * level, 128 * (1 - level)), 128)
    rgb[..., 1] = np.where(beyond, 128 * (1 - level), 128)
    image = np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1).astype(np.uint8)
    mi.Bitmap(image, mi.Bitmap.PixelFormat.RGB).write(path)


HEADER = (
    "| scene | mean | difference | z (mean) | blocks | beyond | worst block z (difference) | critical |\n"
    "|---|---:|---:|---:|---:|---:|---:|---:|"
)


def row(name, r):
    """One Markdown row of `HEADER` for the results `r` of `compare`."""
    return (
        f"| {name} | {r['mean']:.5f} | {r['difference']:+.4%} | {r['z']:+.2f} | {r['blocks']} | "
        f"{r['beyond']} | {r['worst'][0]:+.2f} ({r['worst'][1]:+.2%}) | {r['critical']:.2f} |"
    )


def scene_name(path):
    """A scene file's name without folder and extension (`scene.xml` files: their folder's)."""
    base = os.path.splitext(os.path.basename(path))[0]
    return os.path.basename(os.path.dirname(os.path.abspath(path))) if base == "scene" else base
