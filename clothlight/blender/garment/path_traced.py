"""The woven sample path-traced on the cloth gonioreflectometer: where the light of one sun goes
when yarns light each other (issue 44, "light scattered between yarns").

The cloth tables are measured as the paper's model has it (§7): a yarn is lit by the sun alone,
shadowed by other yarns, and the light it sends toward another yarn is lost.  Here the same
sample, regions and views (:mod:`.measure`) wear the yarn's general-lighting material instead
(the yarn mixture, ``build_yarn_material(mode=GENERAL_MODE)``), lit by one real sun lamp for every
region at once, and Cycles follows the light from yarn to yarn (the validation rig's
:data:`~clothlight.blender.validation.rig.SCENE_BOUNCES`, unclamped) or, for the like-for-like
reference, stops at the first yarn (:data:`~clothlight.blender.validation.rig.DIRECT_BOUNCES`).
Every patch sees the same sun, so a view's ρ is the mean over all of them.  The open weave's light
(1 − coverage along the sun) goes straight on and meets nothing: no view sees it, so the energy
adds it from the coverage, as :func:`clothlight.garment.tables.energy_balance` does.
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable

import bpy
import numpy as np
from mathutils import Vector

from ..materials import GENERAL_MODE, build_yarn_material
from ..measurement_render import render_to_array
from ..validation.rig import DIRECT_BOUNCES, SCENE_BOUNCES
from ...garment.goniometry import SIDES, patch_rho, patch_weights
from .measure import GoniometerSettings, _GoniometerScene, _views

SUN_NAME = "ClothLight Cloth Gonioreflectometer Sun"


def measure_path_traced(tables, toward_sun, settings: GoniometerSettings = GoniometerSettings(), *,
                        bounces: bool, render_dir, progress: Callable[[int, int, str], None] | None = None) -> dict:
    """ρ (1/sr) of the sample of ``settings.weave`` made of the yarn of ``tables``, lit by one sun
    from the world direction ``toward_sun`` (the front side's frame, z the front's normal), at
    every exit cell of both sides: ``{"rho": {side: (N_o², 3)}, "coverage": {side: (N_o²,)}}``.

    ``bounces``: light between yarns (full path tracing) or the first yarn only.  Renders go to
    ``render_dir``; ``progress(done, total, what)`` after each of the 2 N_o² renders."""
    direction = np.asarray(toward_sun, float)
    direction = direction / np.linalg.norm(direction)
    scene = _GoniometerScene(tables, settings)
    try:
        _light_with_a_sun(scene, tables, direction, bounces)
        n_o2 = settings.exit_resolution**2
        rho = {side: np.zeros((n_o2, 3)) for side in SIDES}
        coverage = {side: np.zeros(n_o2) for side in SIDES}
        views = _views(settings)
        for done, (side, cell) in enumerate(views, start=1):
            view = scene._frame(side, cell)
            pixels = render_to_array(scene.scene, pathlib.Path(render_dir) / f"{side}_exit{cell:03d}.exr")
            index, weight = patch_weights(view, scene.layout)
            patches, cover = patch_rho(pixels, index, weight, view, scene.layout, sun_irradiance=1.0)
            regions = scene.n_i**2
            rho[side][cell] = patches[:regions].mean(axis=0)
            coverage[side][cell] = float(np.mean(cover[:regions]))
            if progress is not None:
                progress(done, len(views), f"{side}: exit cell {cell + 1} of {n_o2}")
        return {"rho": rho, "coverage": coverage}
    finally:
        scene.close()


def _light_with_a_sun(scene: _GoniometerScene, tables, toward_sun: np.ndarray, bounces: bool) -> None:
    """Turn the goniometer's sun-mode scene into one lit by a sun lamp of 1 W/m², the sample in the
    yarn's general-lighting material, light paths as the validation rig's ``yarn_scene`` has them."""
    blender_scene = scene.scene
    with bpy.context.temp_override(scene=blender_scene):
        material = build_yarn_material(tables, name=f"{SUN_NAME} Yarn", mode=GENERAL_MODE)
    scene._created.append(material)
    sample = scene._sample
    sample.data.materials.clear()
    sample.data.materials.append(material)
    sample.visible_diffuse = True
    blender_scene.view_layers[0].use_pass_diffuse_color = False
    cycles = blender_scene.cycles
    for name, value in (SCENE_BOUNCES if bounces else DIRECT_BOUNCES).items():
        setattr(cycles, name, value)
    # Unbiased light between yarns: no clamping, no glossy blur, caustics kept (as the rig).
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.caustics_reflective = cycles.caustics_refractive = True
    sun_data = bpy.data.lights.new(SUN_NAME, "SUN")
    sun_data.energy = 1.0
    sun_data.color = (1.0, 1.0, 1.0)
    sun_data.angle = 0.0
    sun = bpy.data.objects.new(SUN_NAME, sun_data)
    scene._created += [sun_data, sun]
    blender_scene.collection.objects.link(sun)
    # A sun shines along its local −z.
    sun.rotation_euler = Vector(-toward_sun).to_track_quat("-Z", "Y").to_euler()
