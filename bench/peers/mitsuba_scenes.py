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
batches; the statistics are peer_images.py's (a block test at family-wise level 0.01 uses the
Bonferroni critical value for the number of blocks).
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

import peer_images


def prepared_xml(path, width, height, spp):
    """The scene file's text with its film at width x height, a box filter and `spp` samples,
    and Mitsuba's `path` integrator, or `volpath` where the file has it (the path tracer with
    participating media); another integrator, such as a path-guiding one, becomes `path` with
    the same maximum depth: lightgraph reads only the depth."""
    tree = ET.parse(path)
    root = tree.getroot()
    integrator = root.find("integrator")
    if integrator is not None and integrator.get("type") not in ("path", "volpath"):
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


def render_passes(path, width, height, spp, passes, variant, progress=True):
    """Mitsuba 3's render of the scene file `path` at width x height in `passes` independent
    passes (seeds 1000, 1001, ...) of `spp` samples per pixel: the mean image and the
    per-pixel variance of that mean from the passes' spread (H x W x 3 each)."""
    import mitsuba as mi

    mi.set_variant(variant)
    # Relative file names start at the scene file's folder.
    mi.file_resolver().prepend(os.path.dirname(os.path.abspath(path)))
    scene = mi.load_string(prepared_xml(path, width, height, spp))
    total = None
    total2 = None
    for k in range(passes):
        image = np.array(mi.render(scene, seed=1000 + k), dtype=np.float64)[:, :, :3]
        total = image if total is None else total + image
        total2 = image * image if total2 is None else total2 + image * image
        if progress:
            print(f"pass {k + 1}/{passes}", flush=True)
    mean = total / passes
    variance = np.maximum(total2 / passes - mean * mean, 0.0) / (passes - 1)
    return mean, variance


def render(args):
    width, height = (int(v) for v in args.res.split("x"))
    mean, variance = render_passes(args.scene, width, height, args.spp, args.batches, args.variant)
    np.savez_compressed(args.out, mean=mean, variance=variance, spp=args.spp * args.batches)


def compare(args):
    result = peer_images.compare(peer_images.load(args.lightgraph), peer_images.load(args.mitsuba), args.block)
    print(peer_images.row(args.name or os.path.basename(args.lightgraph), result))


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
