#!/usr/bin/env python3
"""Time to equal error: SmallUPBP's runs against lightgraph's study, from what study.sh wrote.

  time_to_error.py OUT [--markdown]

Reads OUT/refs/<scene>.exr (lightgraph's reference), OUT/sup/runs.tsv and its images
(SmallUPBP's runs) and OUT/study/<scene>/curves.csv (lightgraph's error against time). For each
SmallUPBP image it computes the RMSE against the reference over every pixel and channel (as
lightgraph's `compare`: src/metrics.rs) and, for each lightgraph run, the time that run took to
reach that RMSE and stay at or below it (the study's rule, interpolated log-log between its last
sample above and the next). The ratio is SmallUPBP's seconds over lightgraph's. Where
lightgraph's first error sample is already below the target the time is an upper bound ("<")
and the ratio a lower bound (">"); where its curve never reaches it, "—".
Needs numpy and OpenEXR (`pip install OpenEXR`, which reads lightgraph's tiled EXRs).
"""
import argparse
import csv
import math
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import exr_image  # noqa: E402


def rmse(image, reference):
    return float(np.sqrt(np.mean((image.astype(np.float64) - reference) ** 2)))


def time_to(curve, target):
    """(seconds, is_upper_bound) when the curve reaches target and stays; None if it never does."""
    above = [i for i, (_t, e) in enumerate(curve) if e > target]
    if not above:
        return curve[0][0], True
    last = above[-1]
    if last == len(curve) - 1:
        return None
    (t0, e0), (t1, e1) = curve[last], curve[last + 1]
    f = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e1))
    return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))), False


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="the folder study.sh wrote")
    a = ap.parse_args()
    import OpenEXR

    refs = sorted((a.out / "refs").glob("*.exr"))
    if len(refs) != 1:
        sys.exit(f"time_to_error.py: expected one reference in {a.out / 'refs'}, found {len(refs)}")
    stem = refs[0].stem
    reference = OpenEXR.File(str(refs[0])).channels()["RGB"].pixels.astype(np.float64)
    curves_path = a.out / "study" / stem / "curves.csv"
    curves = defaultdict(list)
    floor = None
    with open(curves_path) as f:
        for row in csv.DictReader(f):
            curves[row["run"]].append((float(row["seconds"]), float(row["rmse"])))
            floor = math.sqrt(float(row["reference_floor_mse"]))
    with open(a.out / "sup" / "runs.tsv") as f:
        runs = list(csv.DictReader(f, delimiter="\t"))
    if not runs:
        sys.exit(f"time_to_error.py: {a.out / 'sup' / 'runs.tsv'} lists no run")

    names = sorted(curves)
    print(f"scene `{stem}`, reference `{refs[0].name}` (its own noise: RMSE {floor:.3e})\n")
    head = "| SmallUPBP | threads | seconds | iterations | RMSE |"
    rule = "|---|---:|---:|---:|---:|"
    for n in names:
        head += f" {n}: time to it | ratio |"
        rule += "---:|---:|"
    print(head)
    print(rule)
    for r in runs:
        img = exr_image.read(str(a.out / "sup" / r["image"]))
        image = np.dstack([img[c] for c in "RGB"])
        if image.shape != reference.shape:
            sys.exit(f"time_to_error.py: {r['image']} is {image.shape[:2]}, the reference {reference.shape[:2]}")
        target = rmse(image, reference)
        secs = float(r["seconds"])
        row = f"| `{r['algorithm']}` -t {r['budget_s']} | {r['threads']} | {secs:.2f} | {r['iterations']} | {target:.4e} |"
        for n in names:
            hit = time_to(curves[n], target)
            if hit is None:
                row += " — | — |"
            else:
                t, bound = hit
                row += f" {'<' if bound else ''}{t:.3g} s | {'>' if bound else ''}{secs / t:.0f}× |"
        print(row)


if __name__ == "__main__":
    main()
