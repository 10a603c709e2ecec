"""Weave detail for close-ups: a tileable normal and coverage texture of one weave repeat, rendered
from the woven sample, so the weave reads on a garment without yarn geometry.

One orthographic render straight down on the sample frames exactly one repeat (any square of one
repeat's side tiles the cloth, so the texture tiles), with a material that emits the surface
normal: RGB is the normal where yarn is seen, film alpha the fraction of each texel covered by
yarn.  Stored as ``weave_detail.exr`` (RGBA float32): RGB the tangent-space normal as (n + 1)/2
(x = warp, z = the cloth normal, 0.5, 0.5, 1 in the gaps), A the coverage.  The garment material
(:func:`.material.build_garment_material`, ``weave_repeats_per_uv``) bends its closures' normals
with it and scales the closure weights by coverage / mean coverage, so the mean over a repeat is
the measured BSDF's.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import tempfile

import bpy
import numpy as np
import OpenEXR
from mathutils import Matrix

from ..measurement_render import (
    add_orthographic_camera,
    configure_measurement_render,
    remove_data_blocks,
    render_to_array,
)
from ...weave.record import weave_record
from ..sample_object import build_sample_object
from ..validation.rig import sample_bounds

DEFAULT_RESOLUTION = 128
#: Repeats of the weave along each side of the rendered sample (the middle one is framed).
SAMPLE_REPEATS = 3


def render_weave_detail(weave, path, *, resolution: int = DEFAULT_RESOLUTION, samples: int = 16) -> dict:
    """Render the detail texture of ``weave`` (a WeaveParameters) to ``path``; returns its
    description (repeat in mm, mean coverage, resolution), also in the file's header."""
    if not (isinstance(resolution, int) and resolution >= 8 and isinstance(samples, int) and samples >= 1):
        raise ValueError(f"resolution ≥ 8 and samples ≥ 1 (integers), not {resolution!r}, {samples!r}")
    rows, columns = np.asarray(weave.interlacing).shape
    weave = dataclasses.replace(weave, warp_count=SAMPLE_REPEATS * max(rows, columns),
                                weft_count=SAMPLE_REPEATS * max(rows, columns))
    scene = bpy.data.scenes.new("ClothLight Weave Detail")
    created = [scene]
    try:
        sample = build_sample_object(weave, name="ClothLight Weave Detail Sample", collection=scene.collection)
        created += [sample.data, sample]
        bounds = sample_bounds(sample)
        repeat = max(bounds.period)
        material = _normal_emission()
        created.append(material)
        sample.data.materials.append(material)
        configure_measurement_render(scene, resolution=(resolution, resolution), samples=samples, pixel_average=True)
        scene.cycles.shading_system = False
        scene.cycles.max_bounces = 0
        scene.world = None
        camera = add_orthographic_camera(scene, "ClothLight Weave Detail Camera", clip_end=100.0)
        created += [camera.data, camera]
        camera.data.ortho_scale = repeat
        center = np.asarray(bounds.center)
        camera.matrix_world = Matrix.Translation((center[0], center[1], center[2] + 10.0))
        with tempfile.TemporaryDirectory(prefix="clothlight-detail-") as folder:
            pixels = render_to_array(scene, pathlib.Path(folder) / "detail.exr").astype(np.float64)
    finally:
        remove_data_blocks(created)
    coverage = np.clip(pixels[..., 3], 0.0, 1.0)
    seen = coverage > 1e-6
    normal = np.zeros(pixels.shape[:2] + (3,))
    normal[..., 2] = 1.0
    # Film RGB is premultiplied by coverage; the emitted colour is (n + 1)/2.
    normal[seen] = 2.0 * pixels[seen, :3] / coverage[seen, None] - 1.0
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    description = {"repeat_mm": repeat, "mean_coverage": float(coverage.mean()), "resolution": resolution,
                   "weave": weave_record(weave), "encoding": "RGB (n + 1)/2, tangent space x = warp; A coverage"}
    image = np.concatenate([(normal + 1.0) / 2.0, coverage[..., None]], axis=-1).astype(np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "clothlight_weave_detail": json.dumps(description)}
    with OpenEXR.File(header, {"RGBA": np.ascontiguousarray(image)}) as exr:
        exr.write(str(path))
    return description


def _normal_emission():
    """A material emitting (n + 1)/2 of the shading normal: the normal as a colour."""
    material = bpy.data.materials.new("ClothLight Weave Detail Normal")
    tree = material.node_tree
    tree.nodes.clear()
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    encode = tree.nodes.new("ShaderNodeVectorMath")
    encode.operation = "MULTIPLY_ADD"
    tree.links.new(geometry.outputs["Normal"], encode.inputs[0])
    encode.inputs[1].default_value = (0.5, 0.5, 0.5)
    encode.inputs[2].default_value = (0.5, 0.5, 0.5)
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(encode.outputs[0], emission.inputs["Color"])
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material
