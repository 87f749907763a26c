#!/usr/bin/env python3
"""Writes sky.exr: a small equirectangular environment map (64 x 32, RGB float) for the fidelity
scenes: a blue-to-white sky over a brown ground and a bright warm sun, all smooth (the sun a
Gaussian a few texels wide), so that both renderers' importance sampling of the map works on
the same bilinear radiance."""
import math

import numpy as np


def sky(width=64, height=32):
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    theta = v[:, None] * math.pi            # from +Y (row 0) down to -Y
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


if __name__ == "__main__":
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    mi.Bitmap(sky()).write("sky.exr")
