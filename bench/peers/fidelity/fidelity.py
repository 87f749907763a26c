#!/usr/bin/env python3
"""The fidelity suite: lightgraph against Mitsuba 3 on small scenes of our own, each isolating
one importer feature or one emitter shape (scenes/*.xml; README.md says what each checks).

  reference [SCENE.xml ...] [--out tests/data/fidelity] [--res 64x64] [--spp 1024] [--passes 16]
            [--variant llvm_ad_rgb]
      Mitsuba 3's render of each scene (every scene of scenes/ when none is named) in
      independent passes, written as NAME.exr: R, G, B (the mean) and variance.R/G/B (the
      per-pixel variance of the mean, from the passes' spread), with the settings in
      `lightgraph.*` header attributes. tests/integration/fidelity.rs compares lightgraph on
      lavapipe with the ones in tests/data/fidelity, in CI, without Mitsuba.
  lightgraph [SCENE.xml ...] --out DIR [--bin lightgraph] [--res 64x64] [--time 10s | --frames N]
            [--graph pt] [--spp 4] [--runner CMD]
      lightgraph's render of each scene, DIR/NAME.exr (its film: mean and per-pixel variance).
  compare REFERENCE_DIR LIGHTGRAPH_DIR [--block 8] [--maps DIR]
      One Markdown table: per scene, the image mean's relative difference and z (both
      renders' noise), and the blocks whose z passes the critical value (peer_images.py);
      --maps: per scene, DIR/NAME-blocks.png (the blocks' z, red where lightgraph is brighter,
      blue where darker) and DIR/NAME-blocks.csv.

Run `reference` here (llvm_ad_rgb needs a libLLVM >= 17: Debian's libllvm19 and
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so) or on the GPU machine
(--variant cuda_ad_rgb); bench/peers/fidelity/gpu.sh runs the whole suite there at full size.
"""
import argparse
import glob
import os
import shlex
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import mitsuba_scenes  # noqa: E402
import peer_images  # noqa: E402


def scenes(named):
    """The scene files named, or every scene of the suite."""
    return named or sorted(glob.glob(os.path.join(HERE, "scenes", "*.xml")))


def size(res):
    width, height = (int(v) for v in res.lower().split("x"))
    return width, height


def reference(args):
    import drjit as dr
    import mitsuba as mi

    width, height = size(args.res)
    os.makedirs(args.out, exist_ok=True)
    # On one CPU (e.g. under `taskset -c 1`) Dr.Jit's pool has no worker thread, and Mitsuba's
    # EXR writer, which hands its work to that pool, waits forever: give it one.
    dr.set_thread_count(max(dr.thread_count(), 2))
    for path in scenes(args.scenes):
        name = peer_images.scene_name(path)
        start = time.monotonic()
        mean, variance = mitsuba_scenes.render_passes(path, width, height, args.spp, args.passes, args.variant,
                                                      progress=False)
        seconds = time.monotonic() - start
        image = mi.Bitmap(
            np.concatenate([mean, variance], axis=-1).astype(np.float32),
            channel_names=["R", "G", "B", "variance.R", "variance.G", "variance.B"],
        )
        meta = image.metadata()
        meta["lightgraph.passes"] = str(args.passes)
        meta["lightgraph.spp"] = str(args.spp)
        meta["lightgraph.renderer"] = f"Mitsuba {mi.MI_VERSION} ({args.variant})"
        meta["lightgraph.scene"] = f"bench/peers/fidelity/scenes/{os.path.basename(path)}"
        image.write(os.path.join(args.out, f"{name}.exr"))
        print(f"{name}: {args.passes} x {args.spp} spp in {seconds:.0f} s, mean {mean.mean():.5f}", flush=True)


def lightgraph(args):
    os.makedirs(args.out, exist_ok=True)
    budget = ["--time", args.time] if args.frames is None else ["--frames", str(args.frames)]
    runner = shlex.split(args.runner) if args.runner else []
    for path in scenes(args.scenes):
        name = peer_images.scene_name(path)
        out = os.path.join(args.out, f"{name}.exr")
        command = runner + [args.bin, "render", "--scene", path, "--graph", args.graph, "--res", args.res,
                            "--spp", str(args.spp), *budget, "--force", "--out", out]
        done = subprocess.run(command, capture_output=True, text=True)
        with open(os.path.join(args.out, f"{name}.log"), "w") as log:
            log.write(done.stdout + done.stderr)
        if done.returncode != 0:
            sys.exit(f"{name}: lightgraph failed ({done.returncode}):\n{done.stderr[-2000:]}")
        rate = [line for line in done.stdout.splitlines() + done.stderr.splitlines() if "samples/s" in line]
        print(f"{name}: {rate[-1] if rate else 'rendered'}", flush=True)


def write_maps(folder, name, result, block):
    """NAME-blocks.png (the blocks' z: red where lightgraph is brighter) and NAME-blocks.csv
    (every block: its pixel corner, relative difference and z) in `folder`."""
    os.makedirs(folder, exist_ok=True)
    peer_images.write_block_map(os.path.join(folder, f"{name}-blocks.png"), result)
    with open(os.path.join(folder, f"{name}-blocks.csv"), "w") as f:
        f.write("x,y,relative_difference,z\n")
        for j, line in enumerate(result["grid"]):
            for i, (z, relative) in enumerate(line):
                f.write(f"{i * block},{j * block},{relative:.6g},{z:.4g}\n")


def compare(args):
    print(peer_images.HEADER)
    for ref in sorted(glob.glob(os.path.join(args.reference, "*.exr"))):
        name = os.path.splitext(os.path.basename(ref))[0]
        ours = os.path.join(args.lightgraph, f"{name}.exr")
        if not os.path.exists(ours):
            print(f"| {name} | (no lightgraph render) |")
            continue
        result = peer_images.compare(peer_images.load(ours), peer_images.load(ref), args.block)
        print(peer_images.row(name, result), flush=True)
        if args.maps:
            write_maps(args.maps, name, result, args.block)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("reference")
    r.add_argument("scenes", nargs="*")
    r.add_argument("--out", default=os.path.join(HERE, "..", "..", "..", "tests", "data", "fidelity"))
    r.add_argument("--res", default="64x64")
    r.add_argument("--spp", type=int, default=1024)
    r.add_argument("--passes", type=int, default=16)
    r.add_argument("--variant", default="llvm_ad_rgb")
    lg = sub.add_parser("lightgraph")
    lg.add_argument("scenes", nargs="*")
    lg.add_argument("--out", required=True)
    lg.add_argument("--bin", default="lightgraph")
    lg.add_argument("--runner", help="a command the binary runs under, e.g. 'bash .gpu/run.sh'")
    lg.add_argument("--res", default="64x64")
    lg.add_argument("--time", default="10s")
    lg.add_argument("--frames", type=int)
    lg.add_argument("--graph", default="pt")
    lg.add_argument("--spp", type=int, default=4)
    c = sub.add_parser("compare")
    c.add_argument("reference")
    c.add_argument("lightgraph")
    c.add_argument("--block", type=int, default=8)
    c.add_argument("--maps", help="a folder for each scene's map of its blocks' z (PNG) and their table (CSV)")
    args = parser.parse_args()
    {"reference": reference, "lightgraph": lightgraph, "compare": compare}[args.command](args)


if __name__ == "__main__":
    main()
