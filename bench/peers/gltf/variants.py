#!/usr/bin/env python3
"""glTF variants that isolate one feature for docs/gltf.md's comparison with Cycles.

  variants.py MODEL_DIR OUT_DIR
      Copies the model's folder (its .gltf, buffers and images) to OUT_DIR and writes beside it:
      NAME-lambertian.gltf (KHR_materials_specular 0: no specular layer), NAME-unlit.gltf (no
      emission), NAME-unlit-nonormal.gltf (neither emission nor normal maps), NAME-sun.gltf
      (no emission, a directional light of irradiance 3 from the default camera's side) and
      NAME-sun-nonormal.gltf.
  variants.py effect MAPPED.exr UNMAPPED.exr MAPPED.npz UNMAPPED.npz
      How the normal map changes lightgraph's image against how it changes Cycles': the
      correlation of the luminance differences per pixel and per 4x4 block, and the slope.
"""
import json
import math
import os
import shutil
import sys

import numpy as np


def write(doc, path, edit):
    d = json.loads(json.dumps(doc))
    edit(d)
    with open(path, "w") as f:
        json.dump(d, f)


def no_emission(d):
    for m in d.get("materials", []):
        m.pop("emissiveTexture", None)
        m.pop("emissiveFactor", None)


def no_normal_maps(d):
    for m in d.get("materials", []):
        m.pop("normalTexture", None)


def lambertian(d):
    for m in d.get("materials", []):
        m.setdefault("extensions", {})["KHR_materials_specular"] = {"specularFactor": 0.0}
    d.setdefault("extensionsUsed", []).append("KHR_materials_specular")


def sun(d):
    """A directional light travelling along (0.5, -0.7, -1): a node turning -Z onto it."""
    direction = np.array([0.5, -0.7, -1.0]) / np.linalg.norm([0.5, -0.7, -1.0])
    axis = np.cross([0.0, 0.0, -1.0], direction)
    angle = math.atan2(np.linalg.norm(axis), -direction[2])
    q = list(axis / np.linalg.norm(axis) * math.sin(angle / 2)) + [math.cos(angle / 2)]
    d.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
    d.setdefault("extensions", {})["KHR_lights_punctual"] = {
        "lights": [{"type": "directional", "color": [1, 1, 1], "intensity": 3.0}]
    }
    d["nodes"].append({"name": "sun", "rotation": q, "extensions": {"KHR_lights_punctual": {"light": 0}}})
    d["scenes"][d.get("scene", 0)]["nodes"].append(len(d["nodes"]) - 1)


def variants(model_dir, out):
    shutil.copytree(model_dir, out, dirs_exist_ok=True)
    (gltf,) = [f for f in os.listdir(model_dir) if f.endswith(".gltf")]
    name = gltf[: -len(".gltf")]
    with open(os.path.join(model_dir, gltf)) as f:
        doc = json.load(f)
    edits = {
        "lambertian": [lambertian],
        "unlit": [no_emission],
        "unlit-nonormal": [no_emission, no_normal_maps],
        "sun": [no_emission, sun],
        "sun-nonormal": [no_emission, no_normal_maps, sun],
    }
    for suffix, steps in edits.items():
        write(doc, os.path.join(out, f"{name}-{suffix}.gltf"), lambda d: [step(d) for step in steps])


def effect(mapped_exr, unmapped_exr, mapped_npz, unmapped_npz):
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    from mitsuba_scenes import read_lightgraph

    lum = np.array([0.2126, 0.7152, 0.0722])
    lightgraph = (read_lightgraph(mapped_exr)[0] - read_lightgraph(unmapped_exr)[0]) @ lum
    cycles = (np.load(mapped_npz)["mean"] - np.load(unmapped_npz)["mean"]) @ lum
    h, w = cycles.shape
    block = lambda a: a[: h // 4 * 4, : w // 4 * 4].reshape(h // 4, 4, w // 4, 4).mean(axis=(1, 3))
    bl, bc = block(lightgraph), block(cycles)
    print(
        f"correlation per pixel {np.corrcoef(lightgraph.ravel(), cycles.ravel())[0, 1]:.3f}, "
        f"per 4x4 block {np.corrcoef(bl.ravel(), bc.ravel())[0, 1]:.3f}, "
        f"slope lightgraph/Cycles {(bl * bc).sum() / (bc * bc).sum():.3f}"
    )


if __name__ == "__main__":
    if len(sys.argv) == 6 and sys.argv[1] == "effect":
        effect(*sys.argv[2:])
    elif len(sys.argv) == 3:
        variants(*sys.argv[1:])
    else:
        sys.exit(__doc__)
