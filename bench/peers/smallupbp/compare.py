#!/usr/bin/env python3
"""Checks that lightgraph's path tracer and SmallUPBP's volumetric path tracer agree on a scene.

  compare.py SCENE_NUMBER SCENE.ron --sup SmallUPBP --lg lightgraph [options]

Renders SmallUPBP's built-in scene SCENE_NUMBER with its unbiased volumetric path tracer
(`-a vptmis`) RUNS times on one thread, each run with its own seed (`-seed`, which seeds the
path tracer's Mersenne twister: thread k of a run gets seed + k), and lightgraph's `render` of
SCENE.ron (the same scene in lightgraph's format; with --graph, another estimator than pt) with each seed of --lg-seeds. SmallUPBP's
standard errors come from the spread of its runs (Student t, RUNS - 1 degrees of freedom),
lightgraph's from the films' `variance` channel (the per-pixel variance of the mean).

Compared, per channel, over the pixels that see no light source (both images below
--light-threshold in every channel: the light's own radiance would swamp the means; with
--light-margin N, nor within N pixels of such a pixel): the image
mean, and the means of BLOCK x BLOCK pixel blocks, each by Welch's t. The verdict is
"agree" unless the image mean or a block rejects at ALPHA, with Holm's correction over the
blocks. It first checks that the images are aligned (neither flipped nor mirrored) and writes
SmallUPBP | lightgraph side by side as OUT/side.png. Prints a Markdown table row; exit status
1 when they disagree, 2 on a usage or run error.
"""
import argparse
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import exr_image  # noqa: E402  (SmallUPBP's EXRs; lightgraph's are tiled: OpenEXR reads them)


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", type=int, help="SmallUPBP's scene number (-s)")
    ap.add_argument("ron", type=Path, help="the same scene in lightgraph's format")
    ap.add_argument("--sup", required=True, type=Path, help="SmallUPBP executable")
    ap.add_argument("--lg", required=True, type=Path, help="lightgraph executable")
    ap.add_argument("--graph", default="pt",
                    help="lightgraph's estimator (default pt; any graph that handles media)")
    ap.add_argument("--res", default="64x64", help="image size WxH (default 64x64)")
    ap.add_argument("--runs", type=int, default=8, help="SmallUPBP runs (default 8)")
    ap.add_argument("--iterations", type=int, default=1000,
                    help="SmallUPBP iterations (samples per pixel) per run (default 1000)")
    ap.add_argument("--frames", type=int, default=4096,
                    help="lightgraph frames (1 spp each) per seed (default 4096)")
    ap.add_argument("--lg-seeds", default="1", help="lightgraph seeds, comma-separated (default 1)")
    ap.add_argument("--max-length", type=int, default=10,
                    help="maximum path length in segments, both sides (-l, --max-path-length; default 10)")
    ap.add_argument("--block", type=int, default=8, help="block size in pixels (default 8)")
    ap.add_argument("--alpha", type=float, default=0.01, help="test level (default 0.01)")
    ap.add_argument("--light-margin", type=int, default=0,
                    help="also leave out the pixels within this many pixels of a light pixel (default 0; "
                         "1 for light tracing, which misses the light seen directly: the pixels at the "
                         "light's edge see a part of it below the threshold)")
    ap.add_argument("--light-threshold", type=float, default=1.0,
                    help="pixels at or above this in a channel are the light's (default 1.0)")
    ap.add_argument("--out", type=Path, default=Path("out/smallupbp-compare"),
                    help="folder for the images (default out/smallupbp-compare)")
    ap.add_argument("--reuse", action="store_true",
                    help="use the images already in --out instead of rendering them again")
    a = ap.parse_args()
    if not re.fullmatch(r"[1-9]\d*x[1-9]\d*", a.res):
        ap.error(f"--res {a.res}: expected WxH, e.g. 64x64")
    w, h = map(int, a.res.split("x"))
    if w % a.block or h % a.block:
        ap.error(f"--res {a.res}: not a multiple of --block {a.block}")
    if a.runs < 2:
        ap.error("--runs: at least 2 (SmallUPBP's standard error is the spread of its runs)")
    try:
        a.lg_seeds = [int(s) for s in a.lg_seeds.split(",")]
    except ValueError:
        ap.error(f"--lg-seeds {a.lg_seeds}: expected integers separated by commas")
    for exe in (a.sup, a.lg):
        if not (exe.is_file() and os.access(exe, os.X_OK)):
            ap.error(f"{exe}: not an executable file")
    if not a.ron.is_file():
        ap.error(f"{a.ron}: no such scene file")
    if a.reuse:
        wanted = [a.out / f"sup-s{a.scene}-seed{1000 + k}.exr" for k in range(a.runs)]
        wanted += [lg_image(a, s) for s in a.lg_seeds]
        missing = [str(p) for p in wanted if not p.is_file()]
        if missing:
            ap.error(f"--reuse: missing {', '.join(missing)}")
    try:
        import OpenEXR  # noqa: F401
    except ImportError:
        ap.error("the Python module OpenEXR is missing (pip install OpenEXR)")
    return a


def run(cmd, env):
    """Runs cmd at nice 10; returns its stdout, or stops with its output on failure."""
    done = subprocess.run(["nice", "-n", "10", *map(str, cmd)], env=env, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"compare.py: {' '.join(map(str, cmd))} failed ({done.returncode}):\n"
                 f"{done.stdout}{done.stderr}")
    return done.stdout


def render_smallupbp(a, seed):
    """SmallUPBP's image (H x W x 3) of one run."""
    path = a.out / f"sup-s{a.scene}-seed{seed}.exr"
    if not a.reuse:
        env = dict(os.environ, OMP_NUM_THREADS="1")
        out = run([a.sup, "-s", a.scene, "-a", "vptmis", "-r", a.res, "-i", a.iterations, "-th", 1,
                   "-l", a.max_length, "-seed", seed, "-o", path], env)
        print(f"compare.py: SmallUPBP seed {seed}: {out.strip().splitlines()[-1]}", file=sys.stderr)
    img = exr_image.read(str(path))
    return np.dstack([img[c] for c in "RGB"])


def lg_image(a, seed):
    """lightgraph's film of one seed: lg-sN-seedS.exr for pt, lg-GRAPH-sN-seedS.exr for another graph."""
    graph = "" if a.graph == "pt" else f"{a.graph}-"
    return a.out / f"lg-{graph}s{a.scene}-seed{seed}.exr"


def render_lightgraph(a, seed):
    """lightgraph's film: (mean, variance of the mean), each H x W x 3."""
    import OpenEXR

    path = lg_image(a, seed)
    if not a.reuse:
        env = dict(os.environ)
        env.setdefault("XDG_RUNTIME_DIR", "/tmp")
        run([a.lg, "render", "--scene", a.ron, "--graph", a.graph, "--res", a.res, "--frames", a.frames, "--seed", seed,
             "--max-path-length", a.max_length, "--out", path, "--force"], env)
        print(f"compare.py: lightgraph {a.graph} seed {seed}: {a.frames} frames", file=sys.stderr)
    ch = OpenEXR.File(str(path)).channels()
    return ch["RGB"].pixels.astype(np.float64), ch["variance"].pixels.astype(np.float64)


def betainc(x, a, b):
    """The regularised incomplete beta function I_x(a, b) (continued fraction, Lentz)."""
    if x <= 0.0 or x >= 1.0:
        return min(max(x, 0.0), 1.0)
    if x > (a + 1) / (a + b + 2):
        return 1.0 - betainc(1.0 - x, b, a)
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
                     + a * math.log(x) + b * math.log1p(-x)) / a
    tiny, c, d = 1e-300, 1.0, 0.0
    f = 1.0
    for i in range(400):
        m = i // 2
        if i == 0:
            num = 1.0
        elif i % 2 == 0:
            num = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
        else:
            num = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))
        d = 1.0 + num * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + num / c
        c = c if abs(c) > tiny else tiny
        f *= c * d
        if abs(c * d - 1.0) < 1e-14:
            break
    return front * (f - 1.0)


def t_pvalue(t, df):
    """Two-sided p-value of Student's t with df degrees of freedom."""
    return betainc(df / (df + t * t), df / 2.0, 0.5)


def t_threshold(p, df):
    """|t| whose two-sided p-value is p (bisection)."""
    lo, hi = 0.0, 1e4
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if t_pvalue(mid, df) > p else (lo, mid)
    return 0.5 * (lo + hi)


def welch(m1, se1, df1, m2, se2, df2):
    """(t, Welch-Satterthwaite degrees of freedom, two-sided p) for the difference of two means."""
    v = se1 ** 2 + se2 ** 2
    if v == 0.0:
        return (0.0 if m1 == m2 else math.inf), math.inf, (1.0 if m1 == m2 else 0.0)
    t = (m1 - m2) / math.sqrt(v)
    df = v ** 2 / (se1 ** 4 / df1 + se2 ** 4 / df2)
    return t, df, t_pvalue(t, df)


def region_stats(sup_runs, lg_mean, lg_var, sel):
    """Per channel: (SmallUPBP mean, se), (lightgraph mean, se) over the pixels sel selects."""
    per_run = sup_runs[:, sel].mean(axis=1)  # runs x 3
    n = int(sel.sum())
    return ((per_run.mean(axis=0), per_run.std(axis=0, ddof=1) / math.sqrt(len(sup_runs))),
            (lg_mean[sel].mean(axis=0), np.sqrt(lg_var[sel].sum(axis=0)) / n))


def check_alignment(sup, lg, unlit):
    """Stops unless lightgraph's image is closest to SmallUPBP's as it is (not flipped/mirrored)."""
    err = {name: np.abs(sup - img)[unlit].mean()
           for name, img in (("as is", lg), ("flipped", lg[::-1]), ("mirrored", lg[:, ::-1]))}
    if min(err, key=err.get) != "as is":
        sys.exit(f"compare.py: the images are not aligned: mean |difference| {err}")
    return err


def main():
    a = parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    sup_runs = np.stack([render_smallupbp(a, 1000 + k) for k in range(a.runs)])
    films = [render_lightgraph(a, s) for s in a.lg_seeds]
    n_lg = len(films)
    lg_mean = sum(f[0] for f in films) / n_lg
    lg_var = sum(f[1] for f in films) / n_lg ** 2
    df_sup, df_lg = a.runs - 1, n_lg * a.frames - 1
    sup_mean = sup_runs.mean(axis=0)
    unlit = (sup_mean.max(axis=2) < a.light_threshold) & (lg_mean.max(axis=2) < a.light_threshold)
    for _ in range(a.light_margin):
        lit = ~unlit
        grown = lit.copy()
        grown[1:] |= lit[:-1]
        grown[:-1] |= lit[1:]
        grown[:, 1:] |= lit[:, :-1]
        grown[:, :-1] |= lit[:, 1:]
        unlit = ~grown
    align = check_alignment(sup_mean, lg_mean, unlit)
    exr_image.write_png(str(a.out / f"side-s{a.scene}.png"),
                        np.concatenate([sup_mean, np.ones_like(sup_mean[:, :2]), lg_mean], axis=1))

    (s_m, s_se), (l_m, l_se) = region_stats(sup_runs, lg_mean, lg_var, unlit)
    image_tests = [welch(l_m[c], l_se[c], df_lg, s_m[c], s_se[c], df_sup) for c in range(3)]
    h, w = unlit.shape
    blocks = []
    for y in range(0, h, a.block):
        for x in range(0, w, a.block):
            sel = np.zeros_like(unlit)
            sel[y:y + a.block, x:x + a.block] = True
            sel &= unlit
            if sel.sum() == 0:
                continue
            (bs_m, bs_se), (bl_m, bl_se) = region_stats(sup_runs, lg_mean, lg_var, sel)
            for c in range(3):
                t, df, p = welch(bl_m[c], bl_se[c], df_lg, bs_m[c], bs_se[c], df_sup)
                blocks.append((p, t, df, x, y, "RGB"[c]))
    blocks.sort()
    m = len(blocks)
    holm_reject = False
    for i, (p, *_rest) in enumerate(blocks):
        if p > a.alpha / (m - i):
            break
        holm_reject = True
    worst = max(blocks, key=lambda b: abs(b[1]))
    threshold = t_threshold(a.alpha / m, worst[2])
    image_reject = any(p < a.alpha for _t, _df, p in image_tests)
    agree = not (holm_reject or image_reject)

    print(f"scene {a.scene} ({a.ron.name}), {a.res}, max length {a.max_length}: "
          f"{int(unlit.sum())} unlit pixels; alignment mean |diff| {align}")
    for c in range(3):
        t, df, p = image_tests[c]
        print(f"  image mean {'RGB'[c]}: lightgraph {l_m[c]:.6f} ± {l_se[c]:.6f}, SmallUPBP "
              f"{s_m[c]:.6f} ± {s_se[c]:.6f}, rel {l_m[c] / s_m[c] - 1:+.3%}, t {t:+.2f} (df {df:.0f}, p {p:.3g})")
    print(f"  blocks: {m} tests; largest |t| {abs(worst[1]):.2f} (block x {worst[3]} y {worst[4]} "
          f"{worst[5]}, df {worst[2]:.0f}, p {worst[0]:.3g}); Bonferroni threshold at "
          f"{a.alpha:g} for that df: {threshold:.2f}; Holm rejects: {'yes' if holm_reject else 'no'}")
    fmt = lambda v: "/".join(f"{x:.5f}" for x in v)  # noqa: E731
    print(f"| {a.scene} | {fmt(l_m)} ± {fmt(l_se)} | {fmt(s_m)} ± {fmt(s_se)} | "
          + "/".join(f"{l_m[c] / s_m[c] - 1:+.2%}" for c in range(3))
          + f" | {abs(worst[1]):.2f} | {threshold:.2f} | {'agree' if agree else 'DISAGREE'} |")
    sys.exit(0 if agree else 1)


if __name__ == "__main__":
    main()
