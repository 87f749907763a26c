#!/usr/bin/env python3
"""lightgraph against Mitsuba 3 on variants of the fidelity suite's scenes: a scene with its
<default> values replaced (the rough plastic sphere's distribution, alpha, int_ior, nonlinear).

  python3 bench/peers/fidelity/variants.py OUT [--lightgraph BIN] [--variants NAME,...]
          [--res 64x64] [--spp 2048] [--batches 8] [--frames 1024] [--frame-spp 16]

Each variant is written to OUT (beside a copy of scenes/assets), rendered by Mitsuba
(llvm_ad_rgb, `--batches` x `--spp`; kept when OUT already holds it) and by lightgraph (pt,
`--frames` x `--frame-spp`), and compared with ../mitsuba_scenes.py compare (blocks of 8 x 8):
one Markdown row per variant.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "scenes")
PEER = os.path.join(HERE, "..", "mitsuba_scenes.py")

# name: (scene file, its <default> values)
VARIANTS = {
    "beckmann-0.1-1.49": ("roughplastic-sphere.xml", {}),
    "ggx-0.3-1.5": ("roughplastic-sphere.xml", {"distribution": "ggx", "alpha": "0.3", "int_ior": "1.5"}),
    "beckmann-0.5-2": ("roughplastic-sphere.xml", {"alpha": "0.5", "int_ior": "2"}),
    "ggx-0.05-1.33-nonlinear": (
        "roughplastic-sphere.xml",
        {"distribution": "ggx", "alpha": "0.05", "int_ior": "1.33", "nonlinear": "true"},
    ),
    "beckmann-1-3": ("roughplastic-sphere.xml", {"alpha": "1", "int_ior": "3"}),
}


def variant_xml(scene, defaults):
    text = open(os.path.join(SCENES, scene)).read()
    for name, value in defaults.items():
        text, n = re.subn(rf'(<default name="{name}" value=")[^"]*(")', rf"\g<1>{value}\g<2>", text)
        if n != 1:
            sys.exit(f"{scene}: no <default name=\"{name}\">")
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("--lightgraph", default="target/release/lightgraph")
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--res", default="64x64")
    parser.add_argument("--spp", type=int, default=2048)
    parser.add_argument("--batches", type=int, default=8)
    parser.add_argument("--frames", type=int, default=1024)
    parser.add_argument("--frame-spp", type=int, default=16)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    shutil.copytree(os.path.join(SCENES, "assets"), os.path.join(args.out, "assets"), dirs_exist_ok=True)
    rows = []
    for name in args.variants.split(","):
        scene, defaults = VARIANTS[name]
        xml = os.path.join(args.out, f"{name}.xml")
        with open(xml, "w") as f:
            f.write(variant_xml(scene, defaults))
        reference = os.path.join(args.out, f"{name}-mitsuba.npz")
        if not os.path.exists(reference):
            subprocess.run([sys.executable, PEER, "render", xml, reference, "--res", args.res, "--spp",
                            str(args.spp), "--batches", str(args.batches), "--variant", "llvm_ad_rgb"], check=True)
        image = os.path.join(args.out, f"{name}-lightgraph.exr")
        subprocess.run([args.lightgraph, "render", "--scene", xml, "--res", args.res, "--frames", str(args.frames),
                        "--spp", str(args.frame_spp), "--out", image, "--force"], check=True)
        row = subprocess.run([sys.executable, PEER, "compare", image, reference, "--block", "8", "--name", name],
                             check=True, capture_output=True, text=True).stdout.strip()
        print(row, flush=True)
        rows.append(row)
    print("| variant | Mitsuba mean luminance | lightgraph − Mitsuba (mean) | z (mean) | 8² blocks | blocks beyond critical | worst block z (relative) | critical |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
