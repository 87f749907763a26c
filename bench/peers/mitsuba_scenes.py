#!/usr/bin/env python3
"""lightgraph against Mitsuba 3's own renders of Mitsuba scene files (issue 39's acceptance).

  render  SCENE.xml OUT.npz --res WxH --spp N --batches K [--variant cuda_ad_rgb]
          Renders the scene file with Mitsuba 3 (its own integrator and settings, the film
          resized to WxH with a box pixel filter, as lightgraph's pixels are boxes) in K
          independent batches of N samples per pixel, and writes the mean image and the
          per-pixel variance of the mean (from the batches' spread) as numpy arrays.
  compare LIGHTGRAPH.exr MITSUBA.npz [--block 16] [--name NAME]
          Compares lightgraph's EXR (its R, G, B and variance.R/G/B: the per-pixel variance of
          the mean) with Mitsuba's: the image mean's difference in units of its standard error
          (both renders' noise), and per block of BxB pixels the z-score of the difference of
          the block means; prints one Markdown table row.

The standard errors are measured, not assumed: lightgraph's from its frames, Mitsuba's from its
batches. A block test at family-wise level 0.01 uses the Bonferroni critical value for the
number of blocks (two-sided normal quantile of 0.01 / (2 blocks)).
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np


def prepared_xml(path, width, height, spp):
    """The scene file's text with its film at width x height, a box filter and `spp` samples,
    and Mitsuba's `path` integrator (another integrator, such as a path-guiding one, becomes
    `path` with the same maximum depth: lightgraph reads only the depth)."""
    tree = ET.parse(path)
    root = tree.getroot()
    integrator = root.find("integrator")
    if integrator is not None and integrator.get("type") != "path":
        depth = [c for c in integrator if c.get("name") in ("max_depth", "maxDepth")]
        for child in list(integrator):
            integrator.remove(child)
        integrator.set("type", "path")
        integrator.extend(depth)
    sensor = root.find(".//sensor")
    if sensor is None:
        sys.exit(f"{path}: no sensor")
    # A fresh film: Mitsuba 0.5's film properties (high_quality_edges, banner, ...) are not
    # Mitsuba 3's, and none changes the expected image.
    for film in sensor.findall("film"):
        sensor.remove(film)
    film = ET.SubElement(sensor, "film", {"type": "hdrfilm"})
    ET.SubElement(film, "integer", {"name": "width", "value": str(width)})
    ET.SubElement(film, "integer", {"name": "height", "value": str(height)})
    ET.SubElement(film, "rfilter", {"type": "box"})
    sampler = sensor.find("sampler")
    if sampler is None:
        sampler = ET.SubElement(sensor, "sampler", {"type": "independent"})
    for child in list(sampler):
        if child.get("name") in ("sample_count", "sampleCount"):
            sampler.remove(child)
    ET.SubElement(sampler, "integer", {"name": "sample_count", "value": str(spp)})
    return ET.tostring(root, encoding="unicode")


def render(args):
    import mitsuba as mi

    mi.set_variant(args.variant)
    width, height = (int(v) for v in args.res.split("x"))
    # Relative file names start at the scene file's folder.
    mi.Thread.thread().file_resolver().prepend(os.path.dirname(os.path.abspath(args.scene)))
    scene = mi.load_string(prepared_xml(args.scene, width, height, args.spp))
    total = None
    total2 = None
    for k in range(args.batches):
        image = np.array(mi.render(scene, seed=1000 + k), dtype=np.float64)[:, :, :3]
        total = image if total is None else total + image
        total2 = image * image if total2 is None else total2 + image * image
        print(f"batch {k + 1}/{args.batches}", flush=True)
    n = args.batches
    mean = total / n
    variance = np.maximum(total2 / n - mean * mean, 0.0) * n / (n - 1) / n
    np.savez_compressed(args.out, mean=mean, variance=variance, spp=args.spp * n)


def read_lightgraph(path):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    bitmap = mi.Bitmap(path)
    names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
    data = np.array(bitmap, dtype=np.float64)
    channel = {name: data[:, :, i] for i, name in enumerate(names)}
    mean = np.stack([channel[c] + channel.get(f"residual.{c}", 0.0) for c in "RGB"], axis=-1)
    variance = np.stack([channel[f"variance.{c}"] for c in "RGB"], axis=-1)
    return mean, variance


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


def compare(args):
    lg_mean, lg_var = read_lightgraph(args.lightgraph)
    ref = np.load(args.mitsuba)
    mi_mean, mi_var = ref["mean"], ref["variance"]
    if lg_mean.shape != mi_mean.shape:
        sys.exit(f"sizes differ: lightgraph {lg_mean.shape}, Mitsuba {mi_mean.shape}")
    lum = np.array([0.2126, 0.7152, 0.0722])
    a, b = lg_mean @ lum, mi_mean @ lum
    va, vb = lg_var @ (lum * lum), mi_var @ (lum * lum)
    n = a.size
    diff = a.mean() - b.mean()
    se = math.sqrt((va.sum() + vb.sum()) / (n * n))
    h, w = a.shape
    bs = args.block
    zs = []
    for y in range(0, h - bs + 1, bs):
        for x in range(0, w - bs + 1, bs):
            sl = (slice(y, y + bs), slice(x, x + bs))
            m = bs * bs
            d = a[sl].mean() - b[sl].mean()
            s = math.sqrt((va[sl].sum() + vb[sl].sum()) / (m * m))
            zs.append((d / s if s > 0 else (0.0 if d == 0 else math.inf), d / max(b[sl].mean(), 1e-12)))
    critical = normal_quantile(0.01 / (2 * len(zs)))
    beyond = [z for z in zs if abs(z[0]) > critical]
    worst = max(zs, key=lambda z: abs(z[0]))
    name = args.name or os.path.basename(args.lightgraph)
    print(
        f"| {name} | {b.mean():.5f} | {diff / b.mean():+.4%} | {diff / se:+.2f} | {len(zs)} | "
        f"{len(beyond)} | {worst[0]:+.2f} ({worst[1]:+.2%}) | {critical:.2f} |"
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render")
    r.add_argument("scene")
    r.add_argument("out")
    r.add_argument("--res", default="320x180")
    r.add_argument("--spp", type=int, default=256)
    r.add_argument("--batches", type=int, default=8)
    r.add_argument("--variant", default="cuda_ad_rgb")
    c = sub.add_parser("compare")
    c.add_argument("lightgraph")
    c.add_argument("mitsuba")
    c.add_argument("--block", type=int, default=16)
    c.add_argument("--name")
    args = parser.parse_args()
    render(args) if args.command == "render" else compare(args)


if __name__ == "__main__":
    main()
