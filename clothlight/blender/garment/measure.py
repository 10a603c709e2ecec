"""The cloth gonioreflectometer in Blender: the woven sample under every sun at once, one render
per view (layout and calibration: :mod:`.goniometry`).

A scene of its own (nothing of the user's is touched): a woven sample large enough for the
regions and their shadow rays, wearing the sun-mode yarn material with the sun direction read
from a face attribute, and one orthographic camera.  Render settings are the validation rig's
(:func:`clothlight.blender.measurement_render.configure_measurement_render`), with Cycles' box filter of
one pixel so that a pixel holds the mean radiance over its square, as the calibration assumes.
"""

from __future__ import annotations

import atexit
import contextlib
import dataclasses
import pathlib
import time
from collections.abc import Callable
from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix

from ..materials import SUN_MODE, build_yarn_material, shader_node
from ..measurement_render import (
    add_orthographic_camera,
    configure_measurement_render,
    remove_data_blocks,
    render_passes_to_arrays,
    render_to_array,
    worker_threads,
)
from ...render_bounds import (
    DEFAULT_GONIO_EXIT_RESOLUTION,
    DEFAULT_GONIO_INCIDENCE_RESOLUTION,
    DEFAULT_GONIO_PIXELS_PER_PATCH,
    DEFAULT_GONIO_SAMPLES,
    GONIO_EXIT_RESOLUTION,
    GONIO_INCIDENCE_RESOLUTION,
    GONIO_PATCH_REPEATS,
    GONIO_PIXELS_PER_PATCH,
    GONIO_SAMPLES,
    GONIO_SEED,
    check_render_memory,
)
from ..sample_object import build_sample_object
from ..validation.rig import VALIDATION_WEAVE, sample_bounds
from ...weave import WeaveParameters
from ...weave.record import weave_record
from ...garment.goniometry import (
    RAY_OFFSET_MM,
    SIDES,
    ClothMeasurement,
    OrthographicView,
    ParameterError,
    exit_directions,
    incidence_directions,
    patch_rho,
    patch_weights,
    plan_sample,
    view_of,
)
from ...garment.response import GarmentResponse, ResponseView, view_samples

SCENE_NAME = "ClothLight Cloth Gonioreflectometer"
#: The sun-mode shader's outputs a response renders (:func:`_emit_lookup`), and the node that emits them.
LOOKUP_OUTPUTS = ("LookupIncidence", "LookupExit")
LOOKUP_NODE = "ClothLight Lookup"
#: Face attribute: world direction toward the sun that lights the face's region.
SUN_DIRECTION_ATTRIBUTE = "clothlight_sun_direction"


@dataclass(frozen=True)
class GoniometerSettings:
    """What the cloth gonioreflectometer measures and how finely.

    Attributes
    ----------
    incidence_resolution
        N_i of the tables' incidence sphere grid (odd: no cell centre in the cloth plane).
    exit_resolution
        N_o of each side's exit hemisphere grid.
    pixels_per_patch
        Pixels across a patch's foreshortened side.
    samples
        Cycles samples per pixel.
    patch_repeats
        Weave repeats along a patch's side.
    seed
        Cycles' random seed.
    weave
        The weave measured (its yarn counts are set here, to fit the regions); None: the
        validation weave.
    """

    # The defaults and their reasons: clothlight/render_bounds.py (the command line reads them there).
    incidence_resolution: int = DEFAULT_GONIO_INCIDENCE_RESOLUTION
    exit_resolution: int = DEFAULT_GONIO_EXIT_RESOLUTION
    pixels_per_patch: int = DEFAULT_GONIO_PIXELS_PER_PATCH
    samples: int = DEFAULT_GONIO_SAMPLES
    patch_repeats: int = 1
    seed: int = 0
    weave: WeaveParameters | None = None

    def __post_init__(self):
        # Bounds as data (clothlight/render_bounds.py), shared with the command line.
        for name, bound in (("incidence_resolution", GONIO_INCIDENCE_RESOLUTION),
                            ("exit_resolution", GONIO_EXIT_RESOLUTION), ("pixels_per_patch", GONIO_PIXELS_PER_PATCH),
                            ("samples", GONIO_SAMPLES), ("patch_repeats", GONIO_PATCH_REPEATS), ("seed", GONIO_SEED)):
            value = getattr(self, name)
            if name == "incidence_resolution" and isinstance(value, int) and value % 2 == 0:
                raise ParameterError(name, value, f"{bound.allowed()} (an even grid puts cell centres in the "
                                                  "cloth plane)")
            bound.check(value, name)

    def to_dict(self) -> dict:
        """JSON-ready; the weave as the sample records it (its yarn counts are set at measurement)."""
        record = {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}
        record["weave"] = weave_record(_sample_weave(self))
        return record


def _sample_weave(settings: GoniometerSettings) -> WeaveParameters:
    return settings.weave or VALIDATION_WEAVE


class _GoniometerScene:
    """The measurement's scene (sample, yarn material driven per face, camera), built for one yarn
    and ``settings`` and removed by :meth:`close`: :meth:`render_view` measures one exit cell.

    With ``response_samples`` N, the scene renders the cloth response instead (:meth:`render_lookups`):
    the shader's lookup directions (:func:`_emit_lookup`) in the same regions, one camera sample per
    pixel on an N × N grid of pixels per patch, each pixel a square on the cloth in every view."""

    def __init__(self, tables, settings: GoniometerSettings, response_samples: int | None = None):
        self.n_i, self.n_o = n_i, n_o = settings.incidence_resolution, settings.exit_resolution
        self.lookups = response_samples is not None
        self.pixels_per_patch = response_samples if self.lookups else settings.pixels_per_patch
        plan = plan_sample(_sample_weave(settings), n_i, n_o, settings.pixels_per_patch, settings.patch_repeats)
        self.half_thickness, self.patch_mm, layout, weave = (plan.half_thickness_mm, plan.patch_mm, plan.layout,
                                                             plan.weave)
        # The largest image of the sweep (the most grazing view is the widest), before any render.
        largest = max(view.width * view.height
                      for view in (view_of(d, layout, self.pixels_per_patch, pixels_square_on_cloth=self.lookups)
                                   for side in SIDES for d in exit_directions(n_o, side)))
        check_render_memory(largest, "exit_resolution, incidence_resolution, pixels_per_patch, patch_repeats",
                            (n_o, n_i, settings.pixels_per_patch, settings.patch_repeats))

        self.scene = scene = bpy.data.scenes.new(SCENE_NAME)
        self._created = [scene]
        try:
            sample = build_sample_object(weave, name=f"{SCENE_NAME} Sample", collection=scene.collection)
            self._created += [sample.data, sample]
            self.bounds = sample_bounds(sample)
            self.layout = dataclasses.replace(layout, center=self.bounds.center)
            configure_measurement_render(scene, resolution=(16, 16), samples=settings.samples, seed=settings.seed,
                                         pixel_average=True)
            if self.lookups:
                _one_random_sample_a_pixel(scene)
            # The specular marks are diffuse closures that must stay dark: no world, no lamp, and
            # the yarns' emission neither sampled as light (configure_cycles_material) nor seen by
            # diffuse rays.
            scene.cycles.max_bounces = 0
            scene.world = None
            scene.render.use_persistent_data = True
            scene.view_layers[0].use_pass_diffuse_color = not self.lookups
            with bpy.context.temp_override(scene=scene):
                material = build_yarn_material(tables, name=f"{SCENE_NAME} Yarn", mode=SUN_MODE)
            self._created.append(material)
            shader = shader_node(material)
            shader.inputs["ShadowMinDistance"].default_value = RAY_OFFSET_MM
            if not self.lookups:
                shader.inputs["MarkSpecular"].default_value = 1
            # Even with no bounce Cycles follows a diffuse closure's sampled ray to find emitting
            # surfaces; hidden from diffuse rays, the yarns' emission cannot light the marks.
            sample.visible_diffuse = False
            self.specular_parameters = {"weight": shader.inputs["SpecularWeight"].default_value,
                                        "slope": shader.inputs["Slope"].default_value,
                                        "ior": shader.inputs["SpecularIOR"].default_value}
            _drive_sun_from_attribute(material)
            sample.data.materials.clear()
            sample.data.materials.append(material)
            self._sample = sample
            self._material = material
            self._attribute = sample.data.attributes.new(SUN_DIRECTION_ATTRIBUTE, "FLOAT_VECTOR", "FACE")
            centers = np.empty(3 * len(sample.data.polygons))
            sample.data.polygons.foreach_get("center", centers)
            region = self.layout.region_of(centers.reshape(-1, 3)[:, :2])
            # Faces outside the regions are never measured; any sun will do for them.
            self._region = np.where((region >= 0) & (region < n_i * n_i), region, 0)
            self._side = None
            self._distance = 10.0 + 2.0 * plan.half_size_mm
            self._camera = add_orthographic_camera(scene, f"{SCENE_NAME} Camera", clip_end=2.0 * self._distance)
            self._created += [self._camera.data, self._camera]
            self._warm_up()
        except BaseException:
            self.close()
            raise

    def _warm_up(self) -> None:
        """Render once, a few pixels: the first render of a new scene differs from every later one
        of the same view (by ~1 % of ρ in a few pixels: Cycles sets up its OSL shading then), so a
        view measures the same whichever views a scene rendered before it, and on whichever worker."""
        import tempfile

        render = self.scene.render
        render.resolution_x = render.resolution_y = 4
        with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as folder:
            render_passes_to_arrays(self.scene, pathlib.Path(folder) / "warm_up.exr")

    def _frame(self, side: str, exit_cell: int) -> OrthographicView:
        """Light the regions for ``side`` and aim the camera along its exit cell ``exit_cell``."""
        if side != self._side:
            suns = incidence_directions(self.n_i, side)
            self._attribute.data.foreach_set("vector", suns[self._region].astype(np.float32).ravel())
            self._sample.data.update()
            self._side = side
        view = view_of(exit_directions(self.n_o, side)[exit_cell], self.layout, self.pixels_per_patch,
                       pixels_square_on_cloth=self.lookups)
        self._camera.matrix_world = Matrix(view.camera_matrix(self._distance).tolist())
        self._camera.data.ortho_scale = view.ortho_scale
        render = self.scene.render
        render.resolution_x, render.resolution_y = view.width, view.height
        render.pixel_aspect_x, render.pixel_aspect_y = view.pixel_aspect
        # render_passes_to_arrays leaves the single-layer format at half floats after its first render:
        # a lookup direction in half precision would move the unscattered light's narrow cone.
        render.image_settings.color_depth = "32"
        return view

    def render_view(self, side: str, exit_cell: int, render_path) -> dict:
        """Exit cell ``exit_cell`` of ``side`` under all suns: ρ (N_i², 3), the specular term and its
        visibility (N_i²,) and the coverage (a float), rendered to ``render_path``."""
        n_i = self.n_i
        view = self._frame(side, exit_cell)
        passes = render_passes_to_arrays(self.scene, render_path)
        pixels = passes["Combined"]
        index, weight = patch_weights(view, self.layout)
        patch, cover = patch_rho(pixels, index, weight, view, self.layout, sun_irradiance=1.0)
        marks = np.concatenate([passes["Diffuse Color"][..., :2], pixels[..., 3:]], axis=-1)
        marked, _ = patch_rho(marks, index, weight, view, self.layout, sun_irradiance=1.0)
        return {"rho": patch[: n_i * n_i], "visibility": marked[: n_i * n_i, 0],
                "specular": marked[: n_i * n_i, 1], "coverage": float(np.mean(cover[: n_i * n_i]))}

    def render_lookups(self, side: str, exit_cell: int, render_path) -> ResponseView:
        """The response's view of exit cell ``exit_cell`` of ``side``: every lit camera sample's
        lookup directions, rendered to ``render_path`` (one file per output; a scene built with
        ``response_samples``).  One camera sample per pixel lands where it does whatever the pixel
        shows, so the two renders see the same points."""
        view = self._frame(side, exit_cell)
        path = pathlib.Path(render_path)
        lookup = {}
        for output in LOOKUP_OUTPUTS:
            _emit_lookup(self._material, output)
            lookup[output] = render_to_array(self.scene, path.with_name(f"{path.stem}_{output}{path.suffix}"))
        index, weight = patch_weights(view, self.layout)
        return view_samples(side, exit_cell, lookup["LookupIncidence"], lookup["LookupExit"],
                            lookup["LookupIncidence"][..., 3], index, weight, self.n_i * self.n_i)

    def close(self) -> None:
        remove_data_blocks(self._created)
        self._created = []


def _views(settings: GoniometerSettings) -> list[tuple[str, int]]:
    """Every (side, exit cell) the measurement renders, in order."""
    return [(side, cell) for side in SIDES for cell in range(settings.exit_resolution ** 2)]


def measure_cloth(tables, settings: GoniometerSettings = GoniometerSettings(), *, render_dir,
                  progress: Callable[[int, int, str], None] | None = None, scheduler=None,
                  table_folder=None) -> ClothMeasurement:
    """Measure the cloth BSDF of ``settings.weave`` made of the yarn of ``tables`` (a
    :class:`clothlight.yarn_tables.YarnTableFiles`); renders go to ``render_dir``.

    ``progress(done, total, what)`` is called after every render (2 N_o² of them).  ``scheduler``
    (:mod:`precompute.distributed`: ``"local"``, a cluster's address or a cluster already open with
    ``open_executor(..., code=CLUSTER_CODE)``; None renders here) spreads
    the renders over workers, one view a task, each worker rendering in a scene of its own built
    from the yarn bake ``table_folder`` (whose files reach each worker once); the result is the
    same wherever the views rendered."""
    views = _views(settings)
    n_i, n_o = settings.incidence_resolution, settings.exit_resolution
    start = time.perf_counter()
    measured, shape = _render_views(tables, settings, None, render_dir, progress, scheduler, table_folder)
    rho = {side: np.zeros((n_i * n_i, n_o * n_o, 3)) for side in SIDES}
    specular = {side: np.zeros((n_i * n_i, n_o * n_o)) for side in SIDES}
    visibility = {side: np.zeros((n_i * n_i, n_o * n_o)) for side in SIDES}
    coverage = {side: np.zeros(n_o * n_o) for side in SIDES}
    for (side, cell), view in zip(views, measured):
        rho[side][:, cell] = view["rho"]
        visibility[side][:, cell] = view["visibility"]
        specular[side][:, cell] = view["specular"]
        coverage[side][cell] = view["coverage"]
    return ClothMeasurement(rho, specular, visibility, shape["specular_parameters"], coverage, shape["patch_mm"],
                            shape["sample_size_mm"], shape["half_thickness_mm"], time.perf_counter() - start)


def measure_response(tables, settings: GoniometerSettings = GoniometerSettings(), *, samples_per_side: int,
                     render_dir, progress: Callable[[int, int, str], None] | None = None, scheduler=None,
                     table_folder=None) -> GarmentResponse:
    """Render the cloth response of ``settings.weave`` (:mod:`clothlight.garment.response`): the
    views of :func:`measure_cloth`, each as the shader's lookup directions at the centres of an
    ``samples_per_side`` × ``samples_per_side`` grid of pixels per patch, one camera sample a pixel.

    ``tables``: any yarn's (the lookups do not depend on the medium, and neither does the response);
    ``settings.pixels_per_patch`` and ``settings.samples`` are not used.  ``render_dir``,
    ``progress``, ``scheduler`` and ``table_folder`` as :func:`measure_cloth`'s."""
    start = time.perf_counter()
    views, shape = _render_views(tables, settings, samples_per_side, render_dir, progress, scheduler, table_folder)
    shape = {key: shape[key] for key in ("patch_mm", "sample_size_mm", "half_thickness_mm")}
    return GarmentResponse(views, settings.incidence_resolution, settings.exit_resolution, shape,
                           {"samples_per_side": samples_per_side, "render_seconds": time.perf_counter() - start})


def _render_views(tables, settings: GoniometerSettings, response_samples: int | None, render_dir, progress,
                  scheduler, table_folder) -> tuple[list, dict]:
    """Every view of :func:`_views` rendered (here or on ``scheduler``) and measured by the scene's
    :meth:`~_GoniometerScene.render_view` (``response_samples`` None) or its
    :meth:`~_GoniometerScene.render_lookups`; with the scene's shape."""
    views = _views(settings)
    if scheduler is not None:
        return _measure_on_cluster(table_folder, settings, views, scheduler, progress, response_samples)
    measured = []
    scene = _GoniometerScene(tables, settings, response_samples)
    try:
        for done, (side, cell) in enumerate(views, start=1):
            measured.append(_render_one(scene, side, cell, pathlib.Path(render_dir) / f"{side}_exit{cell:03d}.exr"))
            if progress is not None:
                progress(done, len(views), f"{side}: exit cell {cell + 1} of {settings.exit_resolution ** 2}")
        return measured, _scene_shape(scene)
    finally:
        scene.close()


def _render_one(scene: _GoniometerScene, side: str, cell: int, path):
    return (scene.render_lookups if scene.lookups else scene.render_view)(side, cell, path)


def _scene_shape(scene: _GoniometerScene) -> dict:
    """What a measurement records of its scene besides the views."""
    return {"specular_parameters": scene.specular_parameters, "patch_mm": scene.patch_mm,
            "sample_size_mm": (2 * scene.bounds.half_size[0], 2 * scene.bounds.half_size[1]),
            "half_thickness_mm": scene.half_thickness}


# -- on a cluster --------------------------------------------------------------------------------

#: The code a measurement's workers run, checked against this checkout's (precompute.distributed).
CLUSTER_CODE = {"entries": ("clothlight.blender.garment.measure",)}
#: A worker process's scene: a digest of (the yarn files, the settings, the response's samples) →
#: (scene, its table folder).
_worker_scene: dict = {}


def measure_views(table_files: dict, settings: GoniometerSettings, views: tuple,
                  response_samples: int | None = None) -> tuple[dict, list]:
    """A cluster task: ``views`` ((side, exit cell), ...) measured in this worker's scene for the
    yarn whose bake folder holds ``table_files`` (``precompute.distributed.folder_payload``), or
    with ``response_samples`` their response's lookups (:func:`measure_response`); with the scene's
    shape.

    The scene is built on a worker's first task and kept for the next ones; Cycles renders with
    the worker's threads."""
    from precompute import distributed
    import hashlib
    import pickle
    import tempfile

    from ...yarn_tables import yarn_tables_from_bake

    key = hashlib.sha256(pickle.dumps((table_files, settings, response_samples))).hexdigest()
    if key not in _worker_scene:
        _close_worker_scene()
        folder = tempfile.TemporaryDirectory(prefix="clothlight-gonio-tables-")
        distributed.write_payload(table_files, folder.name)
        _worker_scene[key] = (_GoniometerScene(yarn_tables_from_bake(folder.name), settings, response_samples),
                              folder)
    scene = _worker_scene[key][0]
    scene.scene.render.threads_mode = "FIXED"
    scene.scene.render.threads = worker_threads()
    with tempfile.TemporaryDirectory(prefix="clothlight-gonio-") as renders:
        measured = [_render_one(scene, side, cell, pathlib.Path(renders) / f"{side}_exit{cell:03d}.exr")
                    for side, cell in views]
    return _scene_shape(scene), measured


def _close_worker_scene() -> None:
    for scene, folder in _worker_scene.values():
        scene.close()
        folder.cleanup()
    _worker_scene.clear()


# At a worker's exit, before Blender's data is freed: a scene kept to the end would be deleted
# after it, and Cycles' persistent render engine prints a ReferenceError on the way out.
atexit.register(_close_worker_scene)


def _measure_on_cluster(table_folder, settings: GoniometerSettings, views, scheduler,
                        progress, response_samples: int | None = None) -> tuple[list, dict]:

    if table_folder is None:
        raise ParameterError("table_folder", table_folder, "the yarn bake's folder when a scheduler is given")
    from precompute import distributed
    table_files = distributed.folder_payload(table_folder)
    done = []

    def task_done(index: int) -> None:
        done.append(index)
        if progress is not None:
            side, cell = views[index]
            progress(len(done), len(views), f"{side}: exit cell {cell + 1} of {settings.exit_resolution ** 2}")

    with contextlib.ExitStack() as stack:
        executor = (scheduler if isinstance(scheduler, distributed.ClusterExecutor)
                    else stack.enter_context(distributed.open_executor(scheduler, code=CLUSTER_CODE)))
        shared = executor.share(table_files)
        results = executor.map(measure_views, [(shared, settings, (view,), response_samples) for view in views],
                               progress=task_done)
    shapes = [shape for shape, _ in results]
    if any(shape != shapes[0] for shape in shapes):
        raise RuntimeError("the workers built different measurement scenes: is their Blender the same?")
    return [measured for _, views_measured in results for measured in views_measured], shapes[0]


def _one_random_sample_a_pixel(scene) -> None:
    """Render one camera sample a pixel, at a random place in it: Cycles takes a pixel's first
    sample at its centre (a regular grid, which aliases with the weave: 0.61 coverage at normal view
    where the weave has 0.64), its second where its sampling pattern puts it, the same for every
    output of the view."""
    cycles = scene.cycles
    cycles.samples = 2
    cycles.use_sample_subset = True
    cycles.sample_offset = 1
    cycles.sample_subset_length = 1


def _emit_lookup(material, output: str) -> None:
    """Make ``material`` emit one of the sun-mode shader's lookup outputs (0.5 + 0.5 ω in the yarn
    frame, the incidence black where another yarn shadows the point) at unit strength, so that a
    pixel of one camera sample holds its sample's lookup exactly.  (Cycles writes no AOV from an
    OSL shader, and no multilayer EXR of pixels that are not square: one render per output.)"""
    tree = material.node_tree
    emission = tree.nodes.get(LOOKUP_NODE) or tree.nodes.new("ShaderNodeEmission")
    emission.name = LOOKUP_NODE
    emission.inputs["Strength"].default_value = 1.0
    tree.links.new(shader_node(material).outputs[output], emission.inputs["Color"])
    surface = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL").inputs["Surface"]
    tree.links.new(emission.outputs["Emission"], surface)


def _drive_sun_from_attribute(material) -> None:
    """Feed the sun-mode shader's SunDirection from the faces' sun attribute; irradiance 1 W/m²."""
    tree = material.node_tree
    shader = shader_node(material)
    node = tree.nodes.new("ShaderNodeAttribute")
    node.attribute_type = "GEOMETRY"
    node.attribute_name = SUN_DIRECTION_ATTRIBUTE
    node.location = (-200, 400)
    tree.links.new(node.outputs["Vector"], shader.inputs["SunDirection"])
    shader.inputs["SunIrradiance"].default_value = (1.0, 1.0, 1.0, 1.0)
