"""The virtual gonioreflectometer's Blender scene (paper §4 steps 2–3).

A scene of its own, so the user's scene is never touched: a copy of the sample (its mesh copied
too, so materials can be swapped freely), a sun of known irradiance at incidence θi in the plane
of incidence x-z, and one orthographic camera moved to each view θv.  Geometry and conventions:
:mod:`.framing`.

Object mask: the rig scene holds nothing the camera can see but the sample, the film is
transparent and there is no world, so alpha > 0 marks exactly the cloth pixels (alpha is the
sample's coverage of the pixel) and the background contributes neither light nor alpha.

Render settings (:func:`clothlight.blender.measurement_render.configure_measurement_render`): Cycles
on the CPU with OSL, no denoising, no adaptive sampling, a fixed seed, "Standard" view transform,
32-bit float EXR read back from disk.  The materials run in sun mode: they evaluate the BRDF for
the sun exactly and emit the reflected radiance, shadowed by other yarns, so the rig needs no
light bounces (the paper's model has no inter-reflection between yarns, §7).  The general-lighting
materials are lit by the rig's sun lamp, direct light only by default, so that they see the same
single sun as the sun mode; the one measured "in a scene" (``yarn_scene``) is rendered with full
path tracing instead (:meth:`Rig.use_path_tracing`, :data:`SCENE_BOUNCES`), so yarns light each other.

Turns.  A sweep may measure the sample at several azimuths about its normal
(:attr:`RigSettings.sample_azimuths_deg`): :meth:`Rig.set_azimuth` turns the sun and the camera
together by α about the sample's normal through the patch centre, which is the sample turned by −α,
as the fit's forward model turns them (``response_render``); it works alike for a built sample and a
user's object.  The framing keeps the sample's edges out of view at every turn (:mod:`.framing`).
"""

from __future__ import annotations

import itertools
import math
import pathlib
from dataclasses import dataclass, field

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ..materials import shader_node, sync_sun
from ..measurement_render import configure_measurement_render, remove_data_blocks, render_to_array
from ...mesh_attributes import CLOTH_NORMAL, YARN_TANGENT
from ...render_bounds import (
    DEFAULT_VALIDATION_RESOLUTION,
    DEFAULT_VALIDATION_SAMPLES,
    VALIDATION_PATCH_MM,
    VALIDATION_RESOLUTION,
    VALIDATION_SAMPLES,
    VALIDATION_SEED,
    check_render_memory,
)
from ..sample_object import build_sample_object
from ...weave import WeaveParameters
from ...validation.framing import (
    DEFAULT_INCIDENCES_DEG,
    DEFAULT_RIG_AZIMUTHS_DEG,
    DEFAULT_VIEWS_DEG,
    ParameterError,
    SampleBounds,
    check_angles,
    check_patch,
    check_sample_azimuths,
    largest_patch_mm,
    pixel_aspect,
    toward_camera,
    toward_sun,
)
from ...validation.measure import ViewMeasurement, measure_view

#: The sample a validation builds when given none: the default plain weave, large enough that a
#: 2 mm patch (two repeats) keeps its edges out of every default view (see ``framing``).
VALIDATION_WEAVE = WeaveParameters(warp_count=12, weft_count=12)
#: Pixels along the patch side, and samples per pixel (benchmarks/bench_validation.py).
DEFAULT_RESOLUTION = DEFAULT_VALIDATION_RESOLUTION
DEFAULT_SAMPLES = DEFAULT_VALIDATION_SAMPLES
#: Sun irradiance on a plane facing it, W/m² (any value calibrates out; tests use others).
DEFAULT_SUN_IRRADIANCE = 1.0

#: Cycles' bounce limits for a sweep "in a scene" (full path tracing, light between yarns).  Each
#: bounce off the cloth keeps at most its albedo, well under 1 (the rig has no world and no other
#: object), so the light left after 16 bounces is far below the render noise (on the shipped red
#: cotton 4, 16 and 64 bounces agree to four digits: docs/validation.md); Blender's defaults
#: (12, diffuse 4, glossy 4) could cut the chains between yarns of a more scattering yarn short.
#: Transparent: a shadow ray passes each yarn it crosses through that yarn's
#: back face (the shader's transparent far side), so 16 lets it cross more yarns than a ray through
#: a single cloth layer meets.  No volumes in the rig.
SCENE_BOUNCES = {"max_bounces": 16, "diffuse_bounces": 16, "glossy_bounces": 16, "transmission_bounces": 16,
                 "transparent_max_bounces": 16, "volume_bounces": 0}
#: The same limits for direct light only (every other material): no bounce at all.  The
#: transparent limit stays as in the scene sweep so that shadow rays cross yarns alike in both.
DIRECT_BOUNCES = {**{name: 0 for name in SCENE_BOUNCES}, "transparent_max_bounces": 16}

RIG_SCENE = "ClothLight Gonioreflectometer"
RIG_SAMPLE = "ClothLight Gonioreflectometer Sample"


@dataclass(frozen=True)
class RigSettings:
    """Angles, framing and render settings of a sweep.

    Attributes
    ----------
    incidences_deg, views_deg
        Sun zeniths θi in [0, 85] and signed view zeniths θv in [−85, 85], degrees.
    resolution
        Pixels along the patch side (the image is resolution × resolution).
    samples
        Cycles samples per pixel.
    seed
        Cycles' random seed.
    patch_mm
        Side of the square patch every view frames, mm; None: the largest whole number of weave
        repeats (or, for a surface without a weave, the largest patch) that keeps edges out of view.
    sun_irradiance
        E, W/m² on a plane facing the sun.
    sample_azimuths_deg
        The sample's azimuths α about its normal (the warp's angle from the plane of incidence,
        degrees), checked as a preset's ``[sample] azimuths_deg`` (ascending, distinct, in [0, 180)):
        every view is measured at each and averaged.  Default: one turn, α = 0.
    """

    incidences_deg: tuple[float, ...] = DEFAULT_INCIDENCES_DEG
    views_deg: tuple[float, ...] = DEFAULT_VIEWS_DEG
    resolution: int = DEFAULT_RESOLUTION
    samples: int = DEFAULT_SAMPLES
    seed: int = 0
    patch_mm: float | None = None
    sun_irradiance: float = DEFAULT_SUN_IRRADIANCE
    sample_azimuths_deg: tuple[float, ...] = DEFAULT_RIG_AZIMUTHS_DEG

    def __post_init__(self):
        incidences, views = check_angles(self.incidences_deg, self.views_deg)
        object.__setattr__(self, "incidences_deg", incidences)
        object.__setattr__(self, "views_deg", views)
        for name, bound in (("resolution", VALIDATION_RESOLUTION), ("samples", VALIDATION_SAMPLES),
                            ("seed", VALIDATION_SEED)):
            object.__setattr__(self, name, bound.check(getattr(self, name), name))
        check_render_memory(self.resolution**2, "resolution", self.resolution)
        if self.patch_mm is not None:
            object.__setattr__(self, "patch_mm", VALIDATION_PATCH_MM.check(self.patch_mm))
        if not (isinstance(self.sun_irradiance, (int, float)) and math.isfinite(self.sun_irradiance)
                and self.sun_irradiance > 0):
            raise ParameterError("sun_irradiance", self.sun_irradiance, "> 0 W/m²")
        object.__setattr__(self, "sample_azimuths_deg",
                           check_sample_azimuths(self.sample_azimuths_deg, "sample_azimuths_deg"))

    @property
    def max_view_deg(self) -> float:
        return max(abs(v) for v in self.views_deg)

    @property
    def max_incidence_deg(self) -> float:
        return max(self.incidences_deg)


def sample_bounds(obj) -> SampleBounds:
    """The extent of a sample object's mesh in its own frame (modifiers ignored), with the weave's
    spacing as edge band and its repeat as period when it is a ClothLight woven sample."""
    mesh = obj.data
    if not isinstance(mesh, bpy.types.Mesh) or not len(mesh.vertices):
        raise ParameterError("sample", obj.name, "a mesh object with vertices")
    co = np.empty(3 * len(mesh.vertices))
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    low, high = co.min(axis=0), co.max(axis=0)
    center = tuple(float(c) for c in (low + high) / 2.0)
    half = (high - low) / 2.0
    weave = obj.get("clothlight_weave") or {}
    spacing, interlacing = weave.get("spacing_mm"), weave.get("interlacing")
    if spacing is None or interlacing is None:
        return SampleBounds(center, (float(half[0]), float(half[1])), float(half[2]))
    rows, cols = len(interlacing), len(interlacing[0])
    return SampleBounds(center, (float(half[0]), float(half[1])), float(half[2]), edge_band=float(spacing),
                        period=(rows * float(spacing), cols * float(spacing)))


def calibration_plane(size_mm: float, name: str = "ClothLight Calibration Plane"):
    """A flat square of side ``size_mm`` in the x-y plane carrying the attributes ClothLight's
    shaders read (cloth normal +z, yarn tangent +x): a calibration target whose BRDF is known
    exactly when it wears the baseline material.  Not linked to any scene."""
    if not (isinstance(size_mm, (int, float)) and math.isfinite(size_mm) and size_mm > 0):
        raise ParameterError("size_mm", size_mm, "a length > 0 (mm)")
    h = size_mm / 2.0
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)], [], [(0, 1, 2, 3)])
    for attribute_name, vector in ((CLOTH_NORMAL, (0.0, 0.0, 1.0)), (YARN_TANGENT, (1.0, 0.0, 0.0))):
        attribute = mesh.attributes.new(attribute_name, "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", np.tile(vector, 4).astype(np.float32))
    mesh.update()
    return bpy.data.objects.new(name, mesh)


def _aim(obj, direction, target: Vector, distance: float) -> None:
    """Put ``obj`` at ``distance`` from ``target`` along ``direction`` with its local +Z along it.

    For directions in the x-z plane the rotation is about y, so the object's local x stays in the
    plane of incidence and its local y is the world's y (the frame's vertical axis)."""
    direction = Vector(direction)
    rotation = Vector((0.0, 0.0, 1.0)).rotation_difference(direction).to_matrix().to_4x4()
    obj.matrix_world = Matrix.Translation(target + distance * direction) @ rotation


@dataclass
class Rig:
    """A built rig: its scene and objects, the framed patch, and the state of the sweep."""

    scene: object
    sample: object
    sun: object
    camera: object
    settings: RigSettings
    bounds: SampleBounds
    patch_mm: float
    material: object = None
    theta_i_deg: float | None = None
    theta_v_deg: float | None = None
    azimuth_deg: float = 0.0
    _owned: list = field(default_factory=list)

    @property
    def patch_center(self) -> Vector:
        return Vector(self.bounds.center)

    def use_material(self, material) -> None:
        """Put ``material`` (a sun-mode ClothLight material) on every slot of the sample."""
        mesh = self.sample.data
        if not len(mesh.materials):
            mesh.materials.append(material)
        for index in range(len(mesh.materials)):
            mesh.materials[index] = material
        self.material = material
        self._sync_sun()

    def replace_sample(self, obj) -> None:
        """Measure the mesh object ``obj`` (taken over by the rig, removed with it) instead of the
        sample, e.g. a flat patch wearing a cloth-scale material; it must fit the same framing."""
        self.scene.collection.objects.link(obj)
        self._owned += [obj.data, obj]
        self.sample.hide_render = True
        self.sample = obj
        if self.material is not None:
            self.use_material(self.material)

    def use_path_tracing(self, on: bool) -> None:
        """Full path tracing (:data:`SCENE_BOUNCES`: light bounces between yarns) or direct light
        only (:data:`DIRECT_BOUNCES`, the default); a sweep sets it for every material it renders."""
        for name, value in (SCENE_BOUNCES if on else DIRECT_BOUNCES).items():
            setattr(self.scene.cycles, name, value)

    def set_azimuth(self, azimuth_deg: float) -> None:
        """Turn the sun and the camera together by α (degrees) about the sample's normal through the
        patch centre (module docstring): the sample measured turned by −α.  0: the plane of
        incidence x-z, as a rig is built."""
        self.azimuth_deg = float(azimuth_deg)
        if self.theta_i_deg is not None:
            self.set_incidence(self.theta_i_deg)
        if self.theta_v_deg is not None:
            self.set_view(self.theta_v_deg)

    def _turn(self, obj) -> None:
        """Turn ``obj`` (aimed in the plane x-z) by the rig's azimuth about the normal through the patch centre."""
        if self.azimuth_deg != 0.0:
            center = self.patch_center
            obj.matrix_world = (Matrix.Translation(center) @ Matrix.Rotation(math.radians(self.azimuth_deg), 4, "Z")
                                @ Matrix.Translation(-center) @ obj.matrix_world)

    def set_incidence(self, theta_i_deg: float) -> None:
        """Sun at zenith θi on the −x side (θi = 180°: straight from behind), turned by the rig's
        azimuth, and the material told."""
        _aim(self.sun, toward_sun(theta_i_deg), self.patch_center, 0.0)
        self._turn(self.sun)
        self.theta_i_deg = float(theta_i_deg)
        self._sync_sun()

    def _sync_sun(self) -> None:
        """Tell a material with a ClothLight script node where the sun is (node-only materials
        are lit by the sun lamp itself)."""
        if self.material is not None and self.theta_i_deg is not None and shader_node(self.material) is not None:
            sync_sun(self.material, self.sun)

    def set_view(self, theta_v_deg: float) -> None:
        """Camera at signed zenith θv framing the patch exactly (``framing``: non-square pixels),
        turned by the rig's azimuth (its image x stays in the plane of incidence)."""
        _aim(self.camera, toward_camera(theta_v_deg), self.patch_center, self._camera_distance)
        self._turn(self.camera)
        render = self.scene.render
        render.pixel_aspect_x, render.pixel_aspect_y = pixel_aspect(theta_v_deg)
        self.theta_v_deg = float(theta_v_deg)

    @property
    def _camera_distance(self) -> float:
        hx, hy = self.bounds.half_size
        return 10.0 + 2.0 * math.hypot(hx, hy, self.bounds.half_thickness)

    def render(self, path) -> np.ndarray:
        """Render the current view to the EXR ``path``; its pixels (N, N, 4), top row first."""
        return render_to_array(self.scene, pathlib.Path(path))

    def measure(self, path) -> ViewMeasurement:
        """Render the current view to ``path`` and measure it (``measure``)."""
        if self.material is None or self.theta_i_deg is None or self.theta_v_deg is None:
            raise RuntimeError("set a material, an incidence and a view before measuring")
        return measure_view(self.render(path), theta_i_deg=self.theta_i_deg, theta_v_deg=self.theta_v_deg,
                            patch_mm=self.patch_mm, sun_irradiance=self.settings.sun_irradiance)

    def remove(self) -> None:
        """Delete the rig's scene and everything it created (not the materials it was given)."""
        remove_data_blocks(self._owned)
        self._owned.clear()


def build_rig(sample, settings: RigSettings = RigSettings()) -> Rig:
    """Build the rig in a new scene around ``sample``.

    ``sample``: a mesh object whose mesh carries the ``cloth_normal`` attribute (a ClothLight woven
    sample or :func:`calibration_plane`; it is copied, never changed), a WeaveParameters (a sample is
    built), or None (:data:`VALIDATION_WEAVE`).  Raises ParameterError when the patch would bring
    the sample's edges into view at any of the settings' sample azimuths.
    """
    scene = bpy.data.scenes.new(RIG_SCENE)
    owned = [scene]
    try:
        if sample is None or isinstance(sample, WeaveParameters):
            # A name no other rig's sample has: build_sample_object rebuilds a sample of its name in
            # place, and a cluster worker keeps a rig for each kind of sweep (yarn, garment) in one file,
            # where the garment rig hid the yarn rig's sample and its swatches rendered black.
            names = (f"{RIG_SAMPLE}.{k:03d}" if k else RIG_SAMPLE for k in itertools.count())
            name = next(name for name in names if name not in bpy.data.objects)
            copy = build_sample_object(sample or VALIDATION_WEAVE, name=name, collection=scene.collection)
            if copy.name not in scene.collection.objects:
                scene.collection.objects.link(copy)
            owned += [copy.data, copy]
        else:
            if not isinstance(sample, bpy.types.Object) or sample.type != "MESH":
                raise ParameterError("sample", sample, "a mesh object, WeaveParameters or None")
            if CLOTH_NORMAL not in sample.data.attributes:
                raise ParameterError("sample", sample.name,
                                     f"a mesh with the '{CLOTH_NORMAL}' point attribute (a ClothLight sample)")
            copy = sample.copy()
            copy.data = sample.data.copy()
            copy.name = copy.data.name = RIG_SAMPLE
            copy.animation_data_clear()
            copy.parent = None
            copy.matrix_world = Matrix.Identity(4)
            copy.hide_render = False
            copy.visible_camera = True
            for slot in copy.material_slots:
                slot.link = "DATA"
            scene.collection.objects.link(copy)
            owned += [copy.data, copy]
        bounds = sample_bounds(copy)
        if settings.patch_mm is None:
            patch_mm = largest_patch_mm(bounds, settings.resolution, settings.max_view_deg, settings.max_incidence_deg,
                                        settings.sample_azimuths_deg)
        else:
            check_patch(settings.patch_mm, bounds, settings.resolution, settings.max_view_deg,
                        settings.max_incidence_deg, settings.sample_azimuths_deg)
            patch_mm = float(settings.patch_mm)

        configure_measurement_render(scene, resolution=(settings.resolution, settings.resolution),
                                     samples=settings.samples, seed=settings.seed)
        scene.world = None
        # Unbiased indirect light when it bounces: no clamping, no glossy blur (Blender's defaults
        # clamp indirect samples at 10 and blur glossy lobes after a diffuse bounce).
        scene.cycles.sample_clamp_direct = 0.0
        scene.cycles.sample_clamp_indirect = 0.0
        scene.cycles.blur_glossy = 0.0
        scene.cycles.caustics_reflective = scene.cycles.caustics_refractive = True
        # Only the camera and the sun move between renders: keep the BVH and shaders.
        scene.render.use_persistent_data = True
        scene.unit_settings.system = "METRIC"
        scene.unit_settings.scale_length = 0.001
        scene.unit_settings.length_unit = "MILLIMETERS"

        sun_data = bpy.data.lights.new(f"{RIG_SCENE} Sun", "SUN")
        owned.append(sun_data)
        sun_data.energy = settings.sun_irradiance
        sun_data.color = (1.0, 1.0, 1.0)
        sun_data.angle = 0.0
        sun = bpy.data.objects.new(f"{RIG_SCENE} Sun", sun_data)
        owned.append(sun)
        scene.collection.objects.link(sun)

        camera_data = bpy.data.cameras.new(f"{RIG_SCENE} Camera")
        owned.append(camera_data)
        camera_data.type = "ORTHO"
        camera_data.sensor_fit = "VERTICAL"
        camera_data.ortho_scale = patch_mm
        camera = bpy.data.objects.new(f"{RIG_SCENE} Camera", camera_data)
        owned.append(camera)
        scene.collection.objects.link(camera)
        scene.camera = camera
        rig = Rig(scene, copy, sun, camera, settings, bounds, patch_mm, _owned=owned)
        rig.use_path_tracing(False)
        camera_data.clip_start = 0.01
        camera_data.clip_end = 2.0 * rig._camera_distance
        return rig
    except BaseException:
        Rig(scene, None, None, None, settings, None, 0.0, _owned=owned).remove()
        raise
