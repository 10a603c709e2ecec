"""Shared set-up of the material render-cost benchmarks (bench_yarn_material, bench_garment_material,
bench_closeup): the lit scene, the reference material they are timed against and their ratios."""

import pathlib
import time

import bpy
import numpy as np
import OpenEXR

from clothlight.blender.reference_material import principled_sheen

REFERENCE = "Principled BSDF + sheen"


def light_and_camera(scene, camera_location, camera_rotation):
    """A grey world, a 3 W/m² sun and a camera; returns the sun object."""
    world = bpy.data.worlds.new("grey")
    world.color = (0.3, 0.3, 0.3)
    scene.world = world
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.6, 0.2, 0.0)
    scene.collection.objects.link(sun)
    camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    camera.location = camera_location
    camera.rotation_euler = camera_rotation
    scene.collection.objects.link(camera)
    scene.camera = camera
    return sun


def principled_with_sheen():
    """The reference: a red Principled BSDF with full sheen (:mod:`clothlight.blender.reference_material`)."""
    return principled_sheen(REFERENCE, (0.5, 0.02, 0.03))


def print_render_cost(scene, obj, materials: dict, out: pathlib.Path, repeats: int = 5) -> dict:
    """Render ``obj`` with the reference and each of ``materials`` (label → material): a warm-up
    each (shader compile, BVH), then ``repeats`` rounds of one timed render per material, taken in
    turn so that a machine whose speed drifts slows them alike; print the medians and ratios.  The
    reference renders under Cycles' default SVM, as a user would render it, and so does every
    material without a script node; the others under OSL, which their shaders need.  Returns the
    seconds of each round per label, for :func:`paired_ratio` against another anchor."""
    every = {REFERENCE: principled_with_sheen(), **materials}
    shading_systems = {label: any(node.type == "SCRIPT" for node in material.node_tree.nodes)
                       for label, material in every.items()}
    runs = {label: [] for label in every}
    for round_index in range(repeats + 1):
        for label, material in every.items():
            obj.data.materials.clear()
            obj.data.materials.append(material)
            scene.cycles.shading_system = shading_systems[label]
            scene.render.filepath = str(out / f"{label}.exr")
            start = time.perf_counter()
            bpy.ops.render.render(write_still=True)
            if round_index:
                runs[label].append(time.perf_counter() - start)
    for label, seconds in runs.items():
        median = sorted(seconds)[len(seconds) // 2]
        print(f"{label:36s} {median:6.2f} s   {paired_ratio(runs, label, REFERENCE)}   (median of {repeats})")
    return runs


def paired_ratio(runs: dict, label: str, anchor: str) -> str:
    """``label``'s render time over ``anchor``'s as the median over the rounds of each round's own
    ratio, with their range (``runs``: label → seconds per round).  Renders seconds apart share the
    machine's speed of the moment, which drifts by ±10 % between rounds on a shared 2-core machine."""
    ratios = sorted(a / b for a, b in zip(runs[label], runs[anchor]))
    return f"{ratios[len(ratios) // 2]:4.2f}x (rounds {ratios[0]:.2f}–{ratios[-1]:.2f})"


def read_rgb(path: pathlib.Path) -> np.ndarray:
    """The RGB radiance (H, W, 3) of a rendered EXR image, top row first."""
    with OpenEXR.File(str(path)) as image:
        return np.asarray(image.channels()["RGBA"].pixels[..., :3], float)
