#!/usr/bin/env python3
"""Writes the fidelity suite's small assets into scenes/assets/ (deterministic; run once, the
outputs are committed): sky.exr, a 64 x 32 sky of a blue-to-white gradient with a warm sun
25 degrees across; sun-sky.exr, 64 x 32, smooth throughout (a Gaussian sun about 6 degrees
wide: both renderers' importance sampling of the map works on the same bilinear radiance), under
the rough plastic sphere; grid.png, an 8 x 8 sRGB texture of distinct colours (its texels tell
filters and wrap modes apart); sphere.obj, a unit sphere of 16 x 32 quads with the sphere's
normals at its vertices; star.obj, a flat six-pointed star (a concave mesh emitter); blob.vol,
a 24^3 density grid (Mitsuba's .vol format) of three overlapping smooth lobes, zero at its faces,
peak 1, for media-grid-blob. It also writes the built-in scene media-cloud's grid,
scenes/media/cloud.vol: 24^3, eight random lobes (seeded), peak 1.

    python3 bench/peers/fidelity/assets.py      # needs numpy and mitsuba (for the EXR/PNG writers)
"""
import math
import os
import struct

import numpy as np

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenes", "assets")


def sky():
    w, h = 64, 32
    img = np.zeros((h, w, 3), dtype=np.float32)
    sun = np.array([math.cos(math.radians(40)) * math.cos(math.radians(30)), math.sin(math.radians(40)),
                    math.cos(math.radians(40)) * math.sin(math.radians(30))])
    for j in range(h):
        theta = math.pi * (j + 0.5) / h
        for i in range(w):
            phi = 2 * math.pi * (i + 0.5) / w
            d = np.array([math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)])
            up = max(d[1], 0.0)
            img[j, i] = (1 - up) * np.array([0.9, 0.9, 1.0]) + up * np.array([0.2, 0.35, 0.9])
            if d[1] < 0:
                img[j, i] = np.array([0.25, 0.2, 0.15])
            if np.dot(d, sun) > math.cos(math.radians(12.5)):
                img[j, i] = np.array([12.0, 10.0, 7.0])
    return img


def sun_sky(width=64, height=32):
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    theta = v[:, None] * math.pi  # from +Y (row 0) down to -Y
    phi = u[None, :] * 2 * math.pi
    up = np.cos(theta)
    horizon = np.clip(up, 0, 1)
    rgb = np.empty((height, width, 3))
    for c, (zenith, low, ground) in enumerate([(0.25, 0.9, 0.25), (0.45, 0.95, 0.18), (0.9, 1.0, 0.1)]):
        above = low + (zenith - low) * horizon ** 0.5
        rgb[:, :, c] = np.where(up > 0, above, ground * (1 + up)) * np.ones_like(phi)
    # The sun: 40 degrees up, a Gaussian of about 6 degrees.
    sun = np.array([math.cos(math.radians(40)) * math.cos(1.0), math.sin(math.radians(40)),
                    math.cos(math.radians(40)) * math.sin(1.0)])
    d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta) * np.ones_like(phi), np.sin(theta) * np.sin(phi)], -1)
    glow = np.exp(-(1 - d @ sun) / (1 - math.cos(math.radians(6))))
    rgb += glow[:, :, None] * np.array([40.0, 32.0, 22.0])
    return rgb.astype(np.float32)


def grid():
    rng = np.random.default_rng(57)
    return (rng.integers(20, 236, size=(8, 8, 3))).astype(np.uint8)


def lobes(n, centres, widths, weights):
    """An n^3 grid (z, y, x) of the sum of Gaussian lobes at voxel centres, less its largest
    value on the faces (so zero there and beyond), scaled to a peak of 1."""
    u = (np.arange(n) + 0.5) / n
    z, y, x = np.meshgrid(u, u, u, indexing="ij")
    d = np.zeros((n, n, n))
    for (cx, cy, cz), s, w in zip(centres, widths, weights):
        d += w * np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (2 * s * s))
    faces = max(d[0].max(), d[-1].max(), d[:, 0].max(), d[:, -1].max(), d[:, :, 0].max(), d[:, :, -1].max())
    d = np.maximum(d - faces, 0.0)
    return d / d.max()


def vol_bytes(density):
    """Mitsuba's .vol format of a (z, y, x) grid: 'VOL', version 3, encoding 1 (float32), the
    resolution (x, y, z), one channel, the unit box, the densities x fastest."""
    nz, ny, nx = density.shape
    header = b"VOL" + bytes([3]) + struct.pack("<5i", 1, nx, ny, nz, 1) + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    return header + density.astype("<f4").tobytes()


def blob():
    return lobes(24, [(0.5, 0.45, 0.5), (0.33, 0.6, 0.42), (0.66, 0.58, 0.6)], [0.18, 0.11, 0.12], [1.0, 0.7, 0.6])


def cloud():
    rng = np.random.default_rng(59)
    centres = 0.3 + 0.4 * rng.random((8, 3))
    return lobes(24, centres, 0.08 + 0.06 * rng.random(8), 0.5 + 0.5 * rng.random(8))


def sphere_obj(rows=16, columns=32):
    lines = ["# unit sphere, 16 x 32 quads, vertex normals (bench/peers/fidelity/assets.py)"]
    for j in range(rows + 1):
        t = math.pi * j / rows
        for i in range(columns + 1):
            p = 2 * math.pi * i / columns
            x, y, z = math.sin(t) * math.cos(p), math.cos(t), math.sin(t) * math.sin(p)
            lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
            lines.append(f"vn {x:.6f} {y:.6f} {z:.6f}")
    for j in range(rows):
        for i in range(columns):
            a = j * (columns + 1) + i + 1
            b, c, d = a + 1, a + columns + 2, a + columns + 1
            # Outward facing: counter-clockwise seen from outside.
            lines.append(f"f {a}//{a} {b}//{b} {c}//{c} {d}//{d}")
    return "\n".join(lines) + "\n"


def star_obj():
    lines = ["# a flat six-pointed star in the xy plane facing +z (bench/peers/fidelity/assets.py)"]
    points = []
    for k in range(12):
        r = 1.0 if k % 2 == 0 else 0.45
        a = math.pi * k / 6
        points.append((r * math.cos(a), r * math.sin(a)))
    lines.append("v 0 0 0")
    lines += [f"v {x:.6f} {y:.6f} 0" for x, y in points]
    for k in range(12):
        lines.append(f"f 1 {k + 2} {(k + 1) % 12 + 2}")
    return "\n".join(lines) + "\n"


def main():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    os.makedirs(HERE, exist_ok=True)
    mi.Bitmap(sky()).write(os.path.join(HERE, "sky.exr"))
    mi.Bitmap(sun_sky()).write(os.path.join(HERE, "sun-sky.exr"))
    mi.Bitmap(grid()).write(os.path.join(HERE, "grid.png"))
    with open(os.path.join(HERE, "sphere.obj"), "w") as f:
        f.write(sphere_obj())
    with open(os.path.join(HERE, "star.obj"), "w") as f:
        f.write(star_obj())
    with open(os.path.join(HERE, "blob.vol"), "wb") as f:
        f.write(vol_bytes(blob()))
    with open(os.path.join(HERE, "..", "..", "..", "..", "..", "scenes", "media", "cloud.vol"), "wb") as f:
        f.write(vol_bytes(cloud()))


if __name__ == "__main__":
    main()
