"""The virtual gonioreflectometer: calibration on surfaces with known BRDFs, measured-data import."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clothlight.validation.measured_data import (
    MeasurementFormatError,
    parse_measurement,
    relative_rms_error,
    rms_error,
    shape_correlation,
)

bpy = pytest.importorskip("bpy")

from clothlight.materials import build_baseline_material, shader_node  # noqa: E402
from clothlight.mesh_attributes import CLOTH_NORMAL  # noqa: E402
from clothlight.validation.measure import run_sweep  # noqa: E402
from clothlight.validation.rig import RigSettings, build_rig  # noqa: E402
from clothlight.weave import WeaveParameters  # noqa: E402


def flat_patch_rig(tmp_path, albedo, specular):
    bpy.ops.wm.read_homefile(use_empty=True)
    settings = RigSettings(resolution=12, samples=1)
    scene = bpy.context.scene
    sample, sun, camera = build_rig(settings, scene)
    bpy.data.objects.remove(sample)
    bpy.ops.mesh.primitive_plane_add(size=40.0)
    plane = bpy.context.active_object
    attribute = plane.data.attributes.new(CLOTH_NORMAL, "FLOAT_VECTOR", "POINT")
    attribute.data.foreach_set("vector", np.tile([0.0, 0.0, 1.0], len(plane.data.vertices)).astype(np.float32))
    material = build_baseline_material()
    node = shader_node(material)
    node.inputs["DiffuseAlbedo"].default_value = (*albedo, 1.0)
    node.inputs["SpecularWeight"].default_value = specular
    return scene, plane, sun, camera, material, settings


@pytest.mark.blender
def test_a_lambertian_patch_measures_albedo_over_pi_everywhere(tmp_path):
    scene, plane, sun, camera, material, settings = flat_patch_rig(tmp_path, (0.5, 0.25, 0.1), 0.0)
    results = run_sweep(scene, plane, sun, camera, material, settings, (0.0, 45.0, 60.0), (-60.0, -20.0, 0.0, 30.0, 70.0), tmp_path)
    for view in results:
        np.testing.assert_allclose(view.brdf_rgb, np.array([0.5, 0.25, 0.1]) / math.pi, rtol=2e-3)
        assert view.cloth_pixels == settings.resolution**2


def cook_torrance(theta_i, theta_v, m=0.8, n=1.557):
    """Blinn's Cook–Torrance for in-plane mirror-side directions, written out from its definition."""
    l = np.array([-math.sin(theta_i), 0, math.cos(theta_i)])
    v = np.array([math.sin(theta_v), 0, math.cos(theta_v)])
    h = (l + v) / np.linalg.norm(l + v)
    nh, nl, nv, vh = h[2], l[2], v[2], v @ h
    alpha = math.acos(nh)
    d = math.exp(-(math.tan(alpha) / m) ** 2) / (math.pi * m**2 * nh**4)
    g = min(1.0, 2 * nh * nv / vh, 2 * nh * nl / vh)
    c = vh
    gg = math.sqrt(n * n - 1 + c * c)
    f = 0.5 * ((gg - c) / (gg + c)) ** 2 * (1 + ((c * (gg + c) - 1) / (c * (gg - c) + 1)) ** 2)
    return f * d * g / (4 * nl * nv)


@pytest.mark.blender
def test_cook_torrance_term_matches_its_formula(tmp_path):
    scene, plane, sun, camera, material, settings = flat_patch_rig(tmp_path, (0.0, 0.0, 0.0), 1.0)
    views = (45.0, 20.0, 70.0)
    results = run_sweep(scene, plane, sun, camera, material, settings, (45.0,), views, tmp_path)
    for view in results:
        expected = cook_torrance(math.radians(45.0), math.radians(view.theta_v_deg))
        np.testing.assert_allclose(view.brdf_rgb, expected, rtol=3e-3)


@pytest.mark.blender
def test_woven_sample_views_frame_cloth_only(tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True)
    settings = RigSettings(resolution=24, samples=1)
    scene = bpy.context.scene
    sample, sun, camera = build_rig(settings, scene)
    material = build_baseline_material()
    results = run_sweep(scene, sample, sun, camera, material, settings, (30.0,), (-60.0, 0.0, 70.0), tmp_path)
    for view in results:
        # yarns fill most of the patch and the gaps let some background through
        assert 0.5 * 24**2 < view.cloth_pixels < 24**2
    with pytest.raises(ValueError, match="patch_mm"):
        RigSettings(weave=WeaveParameters(warp_count=4, weft_count=4), patch_mm=1.0)


GOOD = "# synthetic\ntheta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,0,0,0.2,0.02,0.01\n30,180,20,0,0.3,0.03,0.02\n30,180,20,180,0.1,0.01,0.01\n"


def test_measurement_import_and_in_plane_curves():
    measurement = parse_measurement(GOOD)
    assert measurement.values.shape == (3, 3) and not measurement.spectral
    x, y = measurement.in_plane(30.0)
    np.testing.assert_array_equal(x, [-20.0, 20.0])  # φo = φi: the light's side, negative
    np.testing.assert_allclose(y[:, 0], [0.1, 0.3])


@pytest.mark.parametrize(
    "text, row",
    [
        ("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,95,0,1,1,1\n", "row 2"),
        ("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,0,0,1,1,1\n0,0,10,360,1,1,1\n", "row 3"),
        ("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,0,0,1,-1,1\n", "row 2"),
        ("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,0,0,1,1\n", "row 2"),
        ("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,x,0,0,1,1,1\n", "row 2"),
        ("theta,phi\n0,0\n", "row 1"),
    ],
)
def test_malformed_rows_are_named(text, row):
    with pytest.raises(MeasurementFormatError, match=row):
        parse_measurement(text)


cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.text(max_size=5),
                  st.integers(-400, 400).map(str))


@settings(max_examples=150, deadline=None)
@given(st.lists(st.lists(cells, min_size=0, max_size=8), min_size=0, max_size=6))
def test_importer_never_crashes_and_names_the_bad_row(rows):
    text = "theta_i,phi_i,theta_o,phi_o,R,G,B\n" + "\n".join(",".join(r) for r in rows)
    try:
        parse_measurement(text)
    except MeasurementFormatError as error:
        assert "row " in str(error) or "empty" in str(error)


def test_metrics_on_known_curves():
    measured = np.array([1.0, 2.0, 3.0])
    assert rms_error(measured, measured) == 0.0
    assert relative_rms_error(measured * 1.1, measured) == pytest.approx(0.1)
    assert shape_correlation(2 * measured + 5, measured) == pytest.approx(1.0)
    assert shape_correlation(-measured, measured) == pytest.approx(-1.0)
