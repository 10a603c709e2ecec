"""Measure a :class:`.response.ClothResponse` in Blender: one render per view of the sun-mode yarn
material's lookup directions, in the gonioreflectometer's rig (:mod:`.rig`, the same framing and
calibration as a sweep).

Each render takes one camera sample per pixel (a pixel then holds one lookup, not a blend of
several: the map stays exactly linear) at ``supersampling`` times the sweep's resolution per
side, so that a view is measured from as many camera samples as a sweep's render takes
(``samples`` per pixel at the sweep's resolution) when ``supersampling² = samples``.
"""

from __future__ import annotations

import math
import pathlib
import tempfile
from collections.abc import Callable

import bpy
import numpy as np
from mathutils import Matrix

from ..materials import SUN_MODE, build_yarn_material, shader_node, sync_sun
from ..measurement_render import render_to_array
from ...validation.framing import ParameterError, largest_patch_mm, pixel_aspect
from ...validation.response import ClothResponse, ResponseView
from .rig import RigSettings, SampleBounds, build_rig

#: The shader's lookup outputs (0.5 + 0.5 w, the incidence black where another yarn shadows).
LOOKUP_OUTPUTS = ("LookupIncidence", "LookupExit")


def _emit_output(material, output: str) -> None:
    """Make ``material`` emit one of its ClothLight node's lookup outputs (unit strength: the
    pixel holds the colour itself)."""
    tree = material.node_tree
    emission = tree.nodes.get("ClothLight Lookup") or tree.nodes.new("ShaderNodeEmission")
    emission.name = "ClothLight Lookup"
    emission.inputs["Strength"].default_value = 1.0
    tree.links.new(shader_node(material).outputs[output], emission.inputs["Color"])
    surface = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL").inputs["Surface"]
    tree.links.new(emission.outputs["Emission"], surface)


def _turned(theta_deg: float, azimuth_deg: float) -> Matrix:
    """Rotation taking +z to the direction at zenith θ (toward +x for θ > 0) turned by an azimuth
    about z: the frame of a camera or sun whose image x lies in its plane of incidence."""
    return (Matrix.Rotation(math.radians(azimuth_deg), 4, "Z")
            @ Matrix.Rotation(math.radians(theta_deg), 4, "Y"))


def measure_response(tables, views, sample=None, *, resolution: int = 128, supersampling: int = 4,
                     seed: int = 0, render_dir=None,
                     progress: Callable[[int, int], None] | None = None) -> ClothResponse:
    """Render the cloth response of ``sample`` at ``views``.

    ``tables``: any yarn tables (:class:`clothlight.yarn_tables.YarnTableFiles`): the lookup
    directions do not depend on the medium.  ``views``: (θi, θv, φv, α) in degrees
    (:mod:`.response`).  ``sample``: as :func:`.rig.build_rig` (None: the validation weave).
    ``resolution`` and ``supersampling``: the sweep's pixels along the patch side and camera samples
    per pixel along each axis; ``seed``: Cycles' seed.  ``progress(done, total)`` after each render.
    """
    views = [tuple(float(a) for a in view) for view in views]
    if not views or any(len(view) != 4 for view in views):
        raise ParameterError("views", views, "(θi, θv, φv, α) tuples in degrees")
    samples_per_side = int(resolution) * int(supersampling)
    # The sun behind the cloth (θi > 90°, the swatch lit from behind) adds no framing constraint of its own.
    in_front = {min(v[0], 180.0 - v[0]) for v in views}
    settings = RigSettings(incidences_deg=tuple(sorted(in_front)),
                           views_deg=tuple(sorted({abs(v[1]) for v in views})),
                           resolution=samples_per_side, samples=1, seed=seed)
    rig = build_rig(sample, settings)
    material = None
    try:
        # A turned sample meets the constraints of the plane of incidence along its other axis.
        bounds = rig.bounds
        swapped = SampleBounds(bounds.center, bounds.half_size[::-1], bounds.half_thickness, bounds.edge_band,
                               bounds.period[::-1] if bounds.period else None)
        rig.patch_mm = min(rig.patch_mm, largest_patch_mm(swapped, samples_per_side, settings.max_view_deg,
                                                          settings.max_incidence_deg))
        rig.camera.data.ortho_scale = rig.patch_mm
        with bpy.context.temp_override(scene=rig.scene):
            material = build_yarn_material(tables, name="ClothLight Response", mode=SUN_MODE)
        rig.use_material(material)
        render = rig.scene.render
        measured = []
        with tempfile.TemporaryDirectory(prefix="clothlight-response-") as scratch:
            folder = pathlib.Path(render_dir or scratch)
            for done, (theta_i, theta_v, phi_v, azimuth) in enumerate(views, start=1):
                center = rig.patch_center
                rig.sun.matrix_world = Matrix.Translation(center) @ _turned(-theta_i, azimuth)
                sync_sun(material, rig.sun)
                rig.camera.matrix_world = (Matrix.Translation(center + rig._camera_distance
                                                              * (_turned(theta_v, azimuth + phi_v).col[2].xyz))
                                           @ _turned(theta_v, azimuth + phi_v))
                render.pixel_aspect_x, render.pixel_aspect_y = pixel_aspect(theta_v)
                stem = f"i{theta_i:+05.1f}_v{theta_v:+05.1f}_p{phi_v:05.1f}_a{azimuth:05.1f}"
                lookup = {}
                for output in LOOKUP_OUTPUTS:
                    _emit_output(material, output)
                    lookup[output] = render_to_array(rig.scene, folder / f"{stem}_{output}.exr")
                lit = (lookup["LookupExit"][..., 3] > 0.0) & (lookup["LookupIncidence"][..., :3].sum(axis=-1) > 0.0)
                incidence, exit_ = (2.0 * lookup[output][..., :3][lit] - 1.0 for output in LOOKUP_OUTPUTS)
                measured.append(ResponseView(theta_i, theta_v, phi_v, azimuth, incidence=incidence.astype(np.float32),
                                             exit=exit_.astype(np.float32), samples_per_side=samples_per_side))
                if progress is not None:
                    progress(done, len(views))
        return ClothResponse(measured, metadata={"resolution": int(resolution), "supersampling": int(supersampling),
                                                 "seed": int(seed), "patch_mm": float(rig.patch_mm)})
    finally:
        rig.remove()
        if material is not None:
            bpy.data.materials.remove(material)
