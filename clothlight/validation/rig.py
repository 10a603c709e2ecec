"""The virtual gonioreflectometer's scene (paper §4): a woven sample, a parallel white light at
incidence θi and orthographic cameras in the plane of incidence at θv = −60 … 70°.

Angles are in the plane of incidence x-z (across the weft, along the warp); negative θv is on the
light's side.  Every view frames the same central patch, small enough that no sample edge enters
even at the most oblique view; gaps between yarns stay transparent (alpha 0) and count as
cloth area that returns no light, as in a real measurement of the cloth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import bpy
from mathutils import Vector

from ..measurement_render import configure_measurement_render
from ..sample_object import build_sample_object
from ..weave import WeaveParameters

DEFAULT_INCIDENCES_DEG = (0.0, 30.0, 45.0, 60.0)
DEFAULT_VIEWS_DEG = tuple(float(v) for v in range(-60, 71, 10))
SUN_IRRADIANCE = 1.0  # W/m² (the scene is in mm, but irradiance is per the lamp's own unit)
CAMERA_DISTANCE_MM = 50.0


@dataclass(frozen=True)
class RigSettings:
    """Sample, framing and render settings of a sweep.

    ``patch_mm``: side of the square patch every view frames; ``resolution``: pixels per side;
    ``samples``: Cycles samples per pixel.
    """

    weave: WeaveParameters = WeaveParameters(warp_count=12, weft_count=12)
    patch_mm: float = 1.0
    resolution: int = 48
    samples: int = 4
    seed: int = 0

    def __post_init__(self):
        half_sample = min(self.weave.sample_size_mm) / 2.0
        reach = self.patch_mm / 2.0 / math.cos(math.radians(max(abs(v) for v in DEFAULT_VIEWS_DEG)))
        if reach + self.weave.spacing_mm > half_sample:
            raise ValueError(
                f"patch_mm = {self.patch_mm} is too large for a {2 * half_sample} mm sample: oblique views would "
                f"see its edges (need patch_mm/2/cos 70° + spacing ≤ {half_sample} mm)")


def direction_in_plane(theta_deg: float) -> Vector:
    """Unit vector at zenith θ in the x-z plane; negative θ toward −x."""
    t = math.radians(theta_deg)
    return Vector((math.sin(t), 0.0, math.cos(t)))


def build_rig(settings: RigSettings, scene=None):
    """Sample, sun and camera in ``scene`` (new empty scene contents); returns (sample, sun, camera)."""
    scene = scene or bpy.context.scene
    configure_measurement_render(scene, resolution=(settings.resolution, settings.resolution),
                                 samples=settings.samples, seed=settings.seed)
    scene.world = None
    scene.cycles.max_bounces = 0  # sun-mode materials emit the exact single-bounce radiance
    scene.unit_settings.system = "METRIC"
    scene.unit_settings.scale_length = 0.001
    scene.unit_settings.length_unit = "MILLIMETERS"
    sample = build_sample_object(settings.weave)
    sun_data = bpy.data.lights.get("ClothLight Sun") or bpy.data.lights.new("ClothLight Sun", "SUN")
    sun_data.energy = SUN_IRRADIANCE
    sun_data.angle = 0.0
    sun = bpy.data.objects.get("ClothLight Sun") or bpy.data.objects.new("ClothLight Sun", sun_data)
    if sun.name not in scene.collection.objects:
        scene.collection.objects.link(sun)
    camera_data = bpy.data.cameras.get("ClothLight Camera") or bpy.data.cameras.new("ClothLight Camera")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = settings.patch_mm
    camera_data.clip_start = 1.0
    camera_data.clip_end = 4 * CAMERA_DISTANCE_MM
    camera = bpy.data.objects.get("ClothLight Camera") or bpy.data.objects.new("ClothLight Camera", camera_data)
    if camera.name not in scene.collection.objects:
        scene.collection.objects.link(camera)
    scene.camera = camera
    return sample, sun, camera


def aim(obj, direction: Vector, distance: float = 0.0) -> None:
    """Put ``obj`` at ``distance`` along ``direction`` with its local −Z pointing back along it."""
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(direction)
    obj.location = direction * distance


def set_incidence(sun, theta_i_deg: float) -> None:
    """Sun on the negative-x side at zenith θi (so negative θv is the light's side)."""
    aim(sun, direction_in_plane(-theta_i_deg))


def set_view(camera, settings: RigSettings, theta_v_deg: float) -> None:
    """Orthographic view from zenith θv, framing a patch of ``patch_mm`` on the cloth along x."""
    aim(camera, direction_in_plane(theta_v_deg), CAMERA_DISTANCE_MM)
    # The view's width across the plane of incidence is the patch side; along it the cloth is
    # foreshortened by cos θv, so the square image sees patch_mm × patch_mm/cos θv of cloth.
    camera.data.ortho_scale = settings.patch_mm
