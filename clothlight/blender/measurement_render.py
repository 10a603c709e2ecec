"""Renders meant to be measured: fixed Cycles settings and float pixels read back from disk.

Background Blender has no pixels in the Render Result, so every measurement
render is written as a 32-bit float OpenEXR file and read back.
"""

from __future__ import annotations

import pathlib

import numpy as np

from .render_setup import use_cycles_osl_on_cpu


def configure_measurement_render(scene, *, resolution: tuple[int, int], samples: int, seed: int = 0,
                                 pixel_average: bool = False) -> None:
    """Cycles OSL on the CPU, no denoising, no adaptive sampling, fixed seed, linear 'Standard' output.

    ``pixel_average``: a one-pixel box filter, so that each pixel holds the mean radiance over its
    own square, as a calibration that weights pixels by the area they cover assumes."""
    use_cycles_osl_on_cpu(scene)
    cycles = scene.cycles
    if pixel_average:
        cycles.pixel_filter_type = "BOX"
        cycles.filter_width = 1.0
    cycles.samples = samples
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = seed
    cycles.use_animated_seed = False
    render = scene.render
    render.resolution_x, render.resolution_y = resolution
    render.resolution_percentage = 100
    render.film_transparent = True
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    render.image_settings.exr_codec = "ZIP"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0


def render_to_array(scene, path: str | pathlib.Path) -> np.ndarray:
    """Render ``scene`` to the EXR file ``path`` and return its pixels, shape (H, W, 4), top row first."""
    import bpy

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True, scene=scene.name)
    image = bpy.data.images.load(str(path), check_existing=False)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
    finally:
        bpy.data.images.remove(image)
    # Blender stores images bottom row first.
    return pixels.reshape(height, width, 4)[::-1]


def render_passes_to_arrays(scene, path: str | pathlib.Path) -> dict:
    """Render ``scene`` with the passes its view layer enables to the multilayer EXR file ``path``;
    returns each pass's pixels by its name in the file ("Combined", "Diffuse Color", …), (H, W, C),
    top row first."""
    import bpy
    import OpenEXR

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    settings = scene.render.image_settings
    single_layer = settings.media_type
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    try:
        scene.render.filepath = str(path)
        bpy.ops.render.render(write_still=True, scene=scene.name)
    finally:
        settings.media_type = single_layer
        settings.file_format = "OPEN_EXR"
    with OpenEXR.File(str(path)) as exr:
        # One part per pass, its channel group named "<view layer>.<pass>".
        return {name.split(".", 1)[-1]: np.array(channel.pixels, dtype=np.float32)
                for part in exr.parts for name, channel in part.channels.items()}


def add_orthographic_camera(scene, name: str, clip_end: float):
    """A new orthographic camera object ``name`` in ``scene``, made its camera (clip 0.01 … ``clip_end``)."""
    import bpy

    camera = bpy.data.objects.new(name, bpy.data.cameras.new(name))
    camera.data.type = "ORTHO"
    camera.data.clip_start = 0.01
    camera.data.clip_end = clip_end
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera


def remove_data_blocks(blocks) -> None:
    """Delete the data blocks a measurement created (scenes, objects, meshes, lights, cameras,
    materials), last created first; blocks already gone (e.g. removed by the user) are skipped."""
    import bpy

    collections = {"SCENE": bpy.data.scenes, "OBJECT": bpy.data.objects, "MESH": bpy.data.meshes,
                   "LIGHT": bpy.data.lights, "CAMERA": bpy.data.cameras, "MATERIAL": bpy.data.materials}
    for block in reversed(list(blocks)):
        try:
            collections[block.id_type].remove(block)
        except ReferenceError:
            pass


def worker_threads() -> int:
    """The threads of the dask worker running the current task: what its Cycles renders use (a
    worker runs one task at a time, precompute.distributed)."""
    from distributed import get_worker

    return max(1, get_worker().state.nthreads)

