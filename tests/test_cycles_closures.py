"""The NumPy twins of Cycles' closures return what Cycles renders.

A flat plane (normal +z) carries one closure with a fixed fibre tangent (+x); a
sun of irradiance E lights it and an orthographic camera looks at it from V.
Every pixel's radiance must be ``eval(V, L) · E`` as the twin computes it, for
lights on the specular cone, off it, behind the plane and round the fibre.
"""

import math

import numpy as np
import pytest

from precompute.tables import cycles_closures as cc
from tests.helpers import add_camera, add_sun, direction, empty_render_scene, script_material

SUN_IRRADIANCE = 2.0
NORMAL = np.array([0.0, 0.0, 1.0])
TANGENT = np.array([1.0, 0.0, 0.0])

CLOSURE_SHADER = """
shader closure_probe(int Kind = 0, float R1 = 0.2, float R2 = 0.5, float Alpha = 0.3,
                     output closure color BSDF = 0)
{
    vector T = vector(1, 0, 0);
    if (Kind == 0)
        BSDF = hair_reflection(N, R1, R2, T, 0.0);
    else if (Kind == 1)
        BSDF = hair_transmission(N, R1, R2, T, 0.0);
    else if (Kind == 2)
        BSDF = microfacet("ggx", normalize(I), Alpha, 1.5, 0);
    else if (Kind == 3)
        BSDF = microfacet("beckmann", N, Alpha, 1.5, 0);
    else if (Kind == 4)
        BSDF = diffuse_toon(N, 1.0, 0.0);
    else  // the Metallic BSDF node's physical conductor
        BSDF = conductor_bsdf(N, vector(1, 0, 0), Alpha, Alpha, color(1.5), color(0), "beckmann");
}
"""


def render_closure(tmp_path, kind, view, light, r1=0.2, r2=0.5, alpha=0.3):
    import bpy

    from clothlight.blender.measurement_render import render_to_array

    scene = empty_render_scene(resolution=4, samples=1, bounces=0)
    bpy.ops.mesh.primitive_plane_add(size=40.0)
    plane = bpy.context.active_object
    material, node = script_material("probe", "closure_probe", CLOSURE_SHADER)
    for name, value in (("Kind", kind), ("R1", r1), ("R2", r2), ("Alpha", alpha)):
        node.inputs[name].default_value = value
    plane.data.materials.append(material)
    add_sun(scene, light, SUN_IRRADIANCE)
    add_camera(scene, view)
    pixels = render_to_array(scene, tmp_path / "closure.exr")
    return float(np.median(pixels[..., 0])) / SUN_IRRADIANCE


CASES = [
    # closure, view (zenith, azimuth), light (zenith, azimuth), what the case probes
    ("hair_reflection", (40, 0), (40, 180), "on the cone, same azimuth round the fibre"),
    ("hair_reflection", (40, 0), (60, 150), "near the cone"),
    ("hair_reflection", (30, 60), (35, 200), "view off the fibre's plane"),
    ("hair_transmission", (20, 10), (150, 190), "from behind, forward"),
    ("hair_transmission", (50, 80), (120, 250), "from behind, round the fibre"),
    ("ggx_retro", (35, 20), (40, 25), "close to the view"),
    ("ggx_retro", (60, 200), (45, 190), "off the view"),
    ("beckmann", (30, 0), (35, 180), "near the mirror direction"),
    ("beckmann", (70, 20), (60, 150), "grazing, forward"),
    ("beckmann", (40, 90), (20, 80), "back toward the light"),
    ("uniform", (30, 0), (75, 180), "grazing light, the same as at normal"),
    ("uniform", (60, 90), (5, 10), "near-normal light"),
    ("conductor", (30, 0), (32, 180), "near the mirror direction, dielectric Fresnel"),
    ("conductor", (70, 0), (60, 180), "grazing, the Fresnel rising"),
]


@pytest.mark.render
@pytest.mark.blender
@pytest.mark.parametrize("kind, view_angles, light_angles, what", CASES, ids=[c[3] for c in CASES])
def test_twin_matches_cycles(bpy, tmp_path, kind, view_angles, light_angles, what):
    view, light = direction(*view_angles), direction(*light_angles)
    r1, r2, alpha = 0.2, 0.5, 0.3
    kinds = {"hair_reflection": 0, "hair_transmission": 1, "ggx_retro": 2, "beckmann": 3, "uniform": 4, "conductor": 5}
    if kind == "beckmann":  # the paper's rms slope
        alpha = 0.8
    elif kind == "conductor":  # the garment's specular lobe at voided_red_cotton's fitted slope
        alpha = 0.094
    rendered = render_closure(tmp_path, kinds[kind], view, light, r1, r2, alpha)
    if kind == "hair_reflection":
        expected = cc.hair_reflection_eval(NORMAL, TANGENT, view, light, r1, r2)
    elif kind == "hair_transmission":
        expected = cc.hair_transmission_eval(NORMAL, TANGENT, view, light, r1, r2)
    elif kind == "beckmann":
        expected = cc.beckmann_reflection_eval(NORMAL, view, light, alpha)
    elif kind == "uniform":
        expected = cc.uniform_eval(NORMAL, light)
    elif kind == "conductor":
        expected = cc.beckmann_conductor_eval(NORMAL, view, light, alpha, 1.5)
    else:
        expected = cc.ggx_reflection_eval(view, view, light, alpha)
    assert float(expected) > 1e-3, "each case must probe a lit part of the lobe"
    assert rendered == pytest.approx(float(expected), rel=5e-3)


def test_twins_vanish_where_cycles_does():
    view = direction(40, 0)
    behind = direction(120, 180)
    assert cc.hair_reflection_eval(NORMAL, TANGENT, view, behind, 0.2, 0.5) == 0.0
    assert cc.hair_transmission_eval(NORMAL, TANGENT, view, direction(40, 180), 0.2, 0.5) == 0.0
    assert cc.ggx_reflection_eval(NORMAL, view, behind, 0.3) == 0.0
    assert cc.beckmann_reflection_eval(NORMAL, view, behind, 0.8) == 0.0
    np.testing.assert_allclose(cc.diffuse_eval(NORMAL, direction(60, 0)), 0.5 / math.pi)
    np.testing.assert_allclose(cc.translucent_eval(NORMAL, direction(120, 0)), 0.5 / math.pi)
    assert cc.uniform_eval(NORMAL, behind) == 0.0


@pytest.mark.parametrize("kind", ["hair_reflection", "hair_transmission", "ggx", "beckmann", "uniform"])
def test_lobes_conserve_energy(kind):
    # Each lobe is normalised by its sampling pdf: the integral over the sphere is at most 1 (less
    # where the lobe is clipped), which makes a fitted weight the lobe's albedo.
    rng = np.random.default_rng(0)
    samples = rng.normal(size=(400_000, 3))
    samples /= np.linalg.norm(samples, axis=1, keepdims=True)
    view = direction(30, 20)
    if kind == "hair_reflection":
        values = cc.hair_reflection_eval(NORMAL, TANGENT, view, samples, 0.3, 0.6)
    elif kind == "hair_transmission":
        values = cc.hair_transmission_eval(NORMAL, TANGENT, view, samples, 0.3, 0.6)
    elif kind == "beckmann":
        values = cc.beckmann_reflection_eval(NORMAL, view, samples, 0.8)
    elif kind == "uniform":
        values = cc.uniform_eval(NORMAL, samples)
    else:
        values = cc.ggx_reflection_eval(view, view, samples, 0.4)
    integral = values.mean() * 4 * math.pi
    assert 0.3 < integral < 1.0 + 0.02
