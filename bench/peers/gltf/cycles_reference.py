#!/usr/bin/env python3
"""A glTF reference: Blender's Cycles (PyPI `bpy`) renders a glTF file as lightgraph does.

  render MODEL.gltf OUT.npz --res WxH --spp N --batches K [--max-path-length 10]
         Imports the glTF with Blender's importer, matches lightgraph's choices for a bare glTF
         file (its camera, else one framing its bounds; a white background of radiance 1 when
         nothing emits; punctual lights at lightgraph's radiometric intensities), sets Cycles to
         plain path tracing (CPU, box pixel filter of 1 pixel, no denoising, no adaptive
         sampling, no clamping, no glossy filter, the same path length, single-scattering GGX)
         and renders K passes of N samples per pixel with different seeds. Writes the mean
         image and the per-pixel variance of the mean (from the passes' spread) as
         `bench/peers/mitsuba_scenes.py render` does, so that
         `python3 bench/peers/mitsuba_scenes.py compare LIGHTGRAPH.exr OUT.npz` compares them.

Run it with a Python that has `bpy` (Blender as a module; bpy 5.0.1 on CPython 3.11 here):
`python -m venv V && V/bin/pip install bpy` (docs/gltf.md).
"""
import argparse
import json
import math
import os
import tempfile

import numpy as np


def node_matrix(node):
    """A glTF node's local transform as a 4x4 numpy matrix."""
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    t = np.array(node.get("translation", [0.0, 0.0, 0.0]))
    x, y, z, w = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = r * np.array(node.get("scale", [1.0, 1.0, 1.0]))
    m[:3, 3] = t
    return m


def gltf_camera(path):
    """lightgraph's camera of a glTF file: the first perspective camera (by index) a node of
    the default scene holds, placed by that node (glTF coordinates: position, forward, up,
    vertical field of view in radians); None without one."""
    with open(path) as f:
        doc = json.load(f)
    scene = doc.get("scenes", [{}])[doc.get("scene", 0)]
    placed = {}
    stack = [(n, np.eye(4)) for n in scene.get("nodes", [])]
    while stack:
        index, parent = stack.pop()
        node = doc["nodes"][index]
        m = parent @ node_matrix(node)
        stack.extend((c, m) for c in node.get("children", []))
        if "camera" in node:
            placed.setdefault(node["camera"], m)
    for index, camera in enumerate(doc.get("cameras", [])):
        if index in placed and camera.get("type") == "perspective":
            m = placed[index]
            forward = m[:3, :3] @ np.array([0.0, 0.0, -1.0])
            up = m[:3, :3] @ np.array([0.0, 1.0, 0.0])
            return m[:3, 3], forward, up, camera["perspective"]["yfov"]
    return None


def blender(v):
    """glTF coordinates (+Y up) to Blender's (+Z up), as Blender's importer converts them."""
    return np.array([v[0], -v[2], v[1]])


def place_camera(bpy, gltf_path, width, height):
    """The scene's camera: the glTF's (vertical field of view), else lightgraph's default one
    framing the meshes' bounds from +Z (glTF) at 45 degrees on the smaller image axis."""
    from mathutils import Matrix, Vector

    found = gltf_camera(gltf_path)
    if found is None:
        points = [
            o.matrix_world @ v.co for o in bpy.context.scene.objects if o.type == "MESH" for v in o.data.vertices
        ]
        lo = np.min(np.array(points), axis=0)
        hi = np.max(np.array(points), axis=0)
        center, radius = (lo + hi) / 2, max(np.linalg.norm((hi - lo) / 2), 1e-6)
        distance = radius / math.sin(math.radians(45.0) / 2)
        position, forward, up = center - np.array([0, distance, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])
        fov, vertical = math.radians(45.0), height <= width
    else:
        p, f, u, fov = found
        position, forward, up, vertical = blender(p), blender(f), blender(u), True
    forward = forward / np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    # A Blender camera looks down its -Z with +Y up.
    rotation = Matrix([list(right), list(up), list(-forward)]).transposed()
    data = bpy.data.cameras.new("lightgraph")
    if vertical:
        data.sensor_fit, data.angle_y = "VERTICAL", fov
    else:
        data.sensor_fit, data.angle_x = "HORIZONTAL", fov
    # lightgraph clips nothing; Blender's default near plane (0.1 m) would hide small models.
    data.clip_start, data.clip_end = 1e-6, 1e9
    camera = bpy.data.objects.new("lightgraph", data)
    camera.matrix_world = Matrix.Translation(Vector(position)) @ rotation.to_4x4()
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera


def match_lights(bpy):
    """KHR_lights_punctual at lightgraph's units: it takes glTF's intensity as W/sr (point,
    spot) and W/m^2 (sun) unconverted; a Cycles point or spot of power P has intensity
    P / (4 pi), a sun's strength is its irradiance. Imported with lighting mode RAW, Blender
    holds glTF's intensity as is. Lights are points (no radius, no angle)."""
    for light in bpy.data.lights:
        if light.type in ("POINT", "SPOT"):
            light.energy *= 4 * math.pi
            light.shadow_soft_size = 0.0
        elif light.type == "SUN":
            light.angle = 0.0


def emits(bpy):
    """Whether any material of the scene emits (an emissive factor and strength above 0)."""
    for material in bpy.data.materials:
        for node in material.node_tree.nodes if material.node_tree else []:
            if node.type == "BSDF_PRINCIPLED":
                color = node.inputs["Emission Color"]
                strength = node.inputs["Emission Strength"].default_value
                if strength > 0 and (color.is_linked or max(color.default_value[:3]) > 0):
                    return True
    return False


def set_world(bpy, radiance):
    world = bpy.data.worlds.new("lightgraph")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (radiance, radiance, radiance, 1.0)
    background.inputs["Strength"].default_value = 1.0
    bpy.context.scene.world = world


def single_scattering(bpy):
    """glTF's specular BRDF is single-scattering GGX: Cycles' Principled BSDF's `GGX` rather
    than its default multiple-scattering GGX."""
    for material in bpy.data.materials:
        for node in material.node_tree.nodes if material.node_tree else []:
            if node.type == "BSDF_PRINCIPLED":
                node.distribution = "GGX"


def set_cycles(bpy, width, height, spp, max_path_length):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.light_sampling_threshold = 0.0
    c.use_animated_seed = False
    # lightgraph counts segments from the camera to the light: 2 is direct light, Cycles'
    # 0 bounces.
    bounces = max_path_length - 2
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = bounces
    c.volume_bounces = 0
    c.transparent_max_bounces = 64


def render_pass(bpy, seed, folder):
    """One pass of the scene's samples with `seed`: the linear RGB image, top row first."""
    bpy.context.scene.cycles.seed = seed
    path = os.path.join(folder, f"pass-{seed}.exr")
    bpy.context.scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    w, h = image.size
    pixels = np.array(image.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3]
    bpy.data.images.remove(image)
    return pixels


def render(args):
    import bpy
    import addon_utils  # Blender's, on the path once bpy is imported

    width, height = (int(v) for v in args.res.split("x"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("cycles")
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(args.model), export_import_convert_lighting_mode="RAW")
    match_lights(bpy)
    single_scattering(bpy)
    place_camera(bpy, args.model, width, height)
    lit = emits(bpy) or len(bpy.data.lights) > 0
    set_world(bpy, 0.0 if lit else 1.0)
    set_cycles(bpy, width, height, args.spp, args.max_path_length)
    total = total2 = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for k in range(args.batches):
            image = render_pass(bpy, 1000 + k, folder)
            total, total2 = total + image, total2 + image * image
            print(f"pass {k + 1}/{args.batches}", flush=True)
    n = args.batches
    mean = total / n
    variance = np.maximum(total2 / n - mean * mean, 0.0) * n / (n - 1) / n
    np.savez_compressed(args.out, mean=mean, variance=variance, spp=args.spp * n)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render")
    r.add_argument("model")
    r.add_argument("out")
    r.add_argument("--res", default="96x96")
    r.add_argument("--spp", type=int, default=64)
    r.add_argument("--batches", type=int, default=8)
    r.add_argument("--max-path-length", type=int, default=10)
    args = parser.parse_args()
    render(args)


if __name__ == "__main__":
    main()
