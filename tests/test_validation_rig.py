"""The virtual gonioreflectometer: calibration on surfaces of known BRDF, framing without edges,
the object mask, the whole sweep with its outputs, cancel, the operator and the command line.

Calibration is proved on a flat plane: with the baseline shader's Lambert term alone (albedo a) the
rig must measure a/π at every incidence and view, and with its Cook–Torrance term alone the value
of that BRDF written out here from its definition; with a yarn table of constant ρ = L/E⊥ it must
measure ρ / cos θi.  Renders are tiny (16 px, 1 sample): a flat plane under a sun-mode material is
exact at any sampling.
"""

import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from clothlight.validation.framing import SampleBounds, frame_size_mm, largest_patch_mm
from clothlight.validation.measure import measure_view
from clothlight.weave import WeaveParameters
from precompute.errors import ParameterError
from clothlight.yarn_tables import yarn_tables_from_bake
from precompute.optics.ballistic import ATTENUATION_SAMPLES
from precompute.tables.closure_fit import LOBES
from tests.helpers import cook_torrance_between, write_yarn_table_folder

bpy = pytest.importorskip("bpy")

from clothlight.blender.materials import (  # noqa: E402
    GENERAL_MODE,
    SUN_MODE,
    build_baseline_material,
    build_yarn_material,
    shader_node,
)
from clothlight.blender.validation.rig import RIG_SCENE, RigSettings, build_rig, calibration_plane  # noqa: E402
from clothlight.blender.validation.run import ValidationCancelled, ValidationRun, run_validation  # noqa: E402

pytestmark = pytest.mark.render

REPO = pathlib.Path(__file__).resolve().parents[1]
SYNTHETIC_CSV = REPO / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"
ALBEDO = np.array([0.5, 0.25, 0.1])
SUN_IRRADIANCE = 3.0  # W/m²: not 1, so that a missing division by E shows


def fresh_file():
    bpy.ops.wm.read_homefile(use_empty=True)


def flat_rig(incidences, views, **overrides):
    fresh_file()
    plane = calibration_plane(10.0)
    settings = RigSettings(incidences_deg=incidences, views_deg=views, resolution=16, samples=1, patch_mm=4.0,
                           sun_irradiance=SUN_IRRADIANCE, **overrides)
    return build_rig(plane, settings)


def wear(rig, builder, **inputs):
    """Build a sun-mode material (script nodes compile through the rig scene's engine), set inputs, wear it."""
    with bpy.context.temp_override(scene=rig.scene):
        material = builder()
    node = shader_node(material)
    for name, value in inputs.items():
        node.inputs[name].default_value = value
    rig.use_material(material)
    return material


def sweep(rig, tmp_path):
    measured = []
    for theta_i in rig.settings.incidences_deg:
        rig.set_incidence(theta_i)
        for theta_v in rig.settings.views_deg:
            rig.set_view(theta_v)
            measured.append(rig.measure(tmp_path / f"i{theta_i:g}_v{theta_v:g}.exr"))
    return measured


def baseline():
    return build_baseline_material(name="test baseline", mode=SUN_MODE)


@pytest.mark.blender
def test_a_lambertian_plane_measures_albedo_over_pi_at_every_view_and_incidence(tmp_path):
    rig = flat_rig((0.0, 30.0, 45.0, 60.0), (-60.0, -30.0, 0.0, 20.0, 50.0, 70.0))
    wear(rig, baseline, DiffuseAlbedo=(*ALBEDO, 1.0), SpecularWeight=0.0)
    for view in sweep(rig, tmp_path):
        np.testing.assert_allclose(view.brdf_rgb, ALBEDO / math.pi, rtol=1e-3)
        assert view.cloth_pixels == 16 * 16 and view.coverage == pytest.approx(1.0, abs=1e-6)
    rig.remove()


def cook_torrance(theta_i, theta_v, m=0.8, n=1.557):
    """Cook–Torrance (1/sr) for light at −θi, view at θv in the x-z plane: :func:`cook_torrance_between`."""
    return cook_torrance_between([-math.sin(theta_i), 0.0, math.cos(theta_i)],
                                 [math.sin(theta_v), 0.0, math.cos(theta_v)], m, n)


@pytest.mark.blender
@pytest.mark.parametrize("mode", [SUN_MODE, GENERAL_MODE])
@pytest.mark.parametrize("theta_i", [30.0, 45.0, 60.0])
def test_the_cook_torrance_term_measures_its_formula(tmp_path, theta_i, mode):
    # the mirror direction (h = n: D at its peak), two off-specular views and the retro-reflection;
    # in general mode through Cycles' own Beckmann closure, which must be the same term
    rig = flat_rig((theta_i,), (theta_i, theta_i - 25.0, -20.0, -theta_i))
    wear(rig, lambda: build_baseline_material(name="test baseline", mode=mode),
         DiffuseAlbedo=(0.0, 0.0, 0.0, 1.0), SpecularWeight=1.0)
    for view in sweep(rig, tmp_path):
        expected = cook_torrance(math.radians(theta_i), math.radians(view.theta_v_deg))
        # Cycles evaluates Smith's Λ by Walter's rational approximation (within 1 % of erf's form)
        np.testing.assert_allclose(view.brdf_rgb, [expected] * 3, rtol=1e-3 if mode == SUN_MODE else 1e-2)
    rig.remove()


CONSTANT_RHO = np.array([0.2, 0.1, 0.05])


@pytest.fixture(scope="module")
def constant_bake(tmp_path_factory):
    """A bake folder whose yarn BRDF is the constant ρ = L/E⊥ = CONSTANT_RHO for every pair of directions."""
    n_i, n_o, lobes = 5, 4, len(LOBES)
    return write_yarn_table_folder(
        tmp_path_factory.mktemp("bake"), np.broadcast_to(CONSTANT_RHO, (n_i * n_o, n_i * n_o, 3)),
        np.zeros((n_o, lobes * n_o, 3)), np.zeros((1, ATTENUATION_SAMPLES, 3)),  # an opaque yarn
        incidence_resolution=n_i, exit_resolution=n_o, optional=False)


@pytest.mark.blender
def test_a_constant_yarn_table_measures_rho_over_cos_incidence(tmp_path, constant_bake):
    # ρ is radiance per irradiance on a plane facing the beam, so a flat yarn of constant ρ has the
    # cloth BRDF ρ / cos θi, the same at every view
    rig = flat_rig((0.0, 45.0, 60.0), (-50.0, 0.0, 40.0))
    tables = yarn_tables_from_bake(constant_bake)
    wear(rig, lambda: build_yarn_material(tables, name="test yarn", mode=SUN_MODE), SpecularWeight=0.0)
    for view in sweep(rig, tmp_path):
        np.testing.assert_allclose(view.brdf_rgb, CONSTANT_RHO / math.cos(math.radians(view.theta_i_deg)), rtol=1e-3)
    rig.remove()


def test_two_rigs_in_one_file_keep_their_own_samples():
    """A cluster worker keeps a rig for the yarn sweep and one for the garment sweep in one file: the
    garment rig's flat patch hid the yarn rig's sample when both were the same object (black swatches)."""
    from clothlight.blender.validation.run import garment_patch

    yarn_rig = build_rig(None)  # the validation weave, as a worker builds it
    garment_rig = build_rig(None)
    try:
        assert yarn_rig.sample != garment_rig.sample
        garment_rig.replace_sample(garment_patch(garment_rig))
        assert not yarn_rig.sample.hide_render and yarn_rig.sample.name in yarn_rig.scene.collection.objects
    finally:
        garment_rig.remove()
        yarn_rig.remove()
    assert not [obj for obj in bpy.data.objects if obj.name.startswith("ClothLight Gonioreflectometer")]


@pytest.mark.blender
@pytest.mark.parametrize("theta_v", [-70.0, -45.0, 0.0, 30.0, 70.0])
def test_every_view_frames_exactly_the_patch(theta_v):
    rig = flat_rig((0.0,), (theta_v,))
    rig.set_view(theta_v)
    frame = rig.camera.data.view_frame(scene=rig.scene)  # camera space, pixel aspect included
    width = max(c.x for c in frame) - min(c.x for c in frame)
    height = max(c.y for c in frame) - min(c.y for c in frame)
    np.testing.assert_allclose((width, height), frame_size_mm(rig.patch_mm, theta_v), rtol=1e-5)
    direction = rig.camera.matrix_world.to_3x3().col[2].normalized()  # toward the camera
    corners = []
    for corner in frame:
        point = rig.camera.matrix_world @ corner
        point = point - direction * (point.z / direction.z)  # along the view onto the cloth plane z = 0
        corners.append(tuple(point))
    h = rig.patch_mm / 2.0
    np.testing.assert_allclose(sorted(corners), sorted((sx * h, sy * h, 0.0) for sx in (-1, 1) for sy in (-1, 1)),
                               atol=1e-5)  # Blender's float32
    rig.remove()


def measure_woven(count, patch_mm, tmp_path):
    """The baseline on a count × count plain weave at the most oblique views and incidence, checking the mask."""
    fresh_file()
    settings = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(-60.0, 70.0), resolution=32, samples=1,
                           patch_mm=patch_mm)
    rig = build_rig(WeaveParameters(warp_count=count, weft_count=count), settings)
    wear(rig, baseline)
    measured = []
    for theta_i in settings.incidences_deg:
        rig.set_incidence(theta_i)
        for theta_v in settings.views_deg:
            rig.set_view(theta_v)
            pixels = rig.render(tmp_path / f"{count}_{theta_i:g}_{theta_v:g}.exr")
            background = pixels[..., 3] == 0.0
            assert np.all(pixels[background][:, :3] == 0.0)  # the background adds no light
            measured.append(measure_view(pixels, theta_i_deg=theta_i, theta_v_deg=theta_v, patch_mm=rig.patch_mm,
                                         sun_irradiance=settings.sun_irradiance))
    patch = rig.patch_mm
    rig.remove()
    return patch, measured


@pytest.mark.blender
def test_woven_views_see_no_sample_edge_and_the_mask_is_the_cloth(tmp_path, monkeypatch):
    """The default validation sample and a much larger one give the same pixels at the most oblique
    views and incidence: nothing beyond the default sample is seen or casts shadow.  Control: with
    the rig's check switched off, a patch too large for the sample does show its edges."""
    patch, small = measure_woven(12, None, tmp_path)
    assert patch == pytest.approx(2.0)  # two plain-weave repeats fit inside the margins
    _, large = measure_woven(20, patch, tmp_path)
    for a, b in zip(small, large):
        np.testing.assert_allclose(a.brdf_rgb, b.brdf_rgb, rtol=1e-4)
        assert a.cloth_pixels == b.cloth_pixels
        assert 0.5 * 32**2 < a.cloth_pixels < 32**2  # mostly yarn, with gaps between yarns
    monkeypatch.setattr("clothlight.blender.validation.rig.check_patch", lambda *args: None)
    _, edged = measure_woven(12, 5.5, tmp_path)
    _, reference = measure_woven(20, 5.5, tmp_path)
    assert max(abs(a.brdf_rgb[0] / b.brdf_rgb[0] - 1.0) for a, b in zip(edged, reference)) > 1e-3


@pytest.mark.blender
def test_patches_that_would_show_edges_are_refused():
    fresh_file()
    with pytest.raises(ParameterError, match="patch_mm"):
        build_rig(None, RigSettings(patch_mm=3.0))
    with pytest.raises(ParameterError, match="use more yarns"):
        build_rig(WeaveParameters(warp_count=6, weft_count=6), RigSettings())
    assert RIG_SCENE not in bpy.data.scenes and len(bpy.data.objects) == 0  # nothing left behind
    # a flat plane of side S holds patches up to (S/2)/(1/2 + 1/N)
    bounds = SampleBounds((0.0, 0.0, 0.0), (5.0, 5.0), 0.0)
    assert largest_patch_mm(bounds, 16, 70.0, 60.0) == pytest.approx(5.0 / (0.5 + 1 / 16))


def png_size(path):
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


@pytest.mark.blender
def test_a_sweep_can_set_the_yarns_specular_weight_to_measure_the_cloth_without_its_sheen(tmp_path, constant_bake):
    # The sheen is linear in its weight: the cloth with weight 2 minus the cloth without it is twice
    # the cloth with weight 1 minus the cloth without it, at the mirror view where the sheen shines.
    fresh_file()
    settings = RigSettings(incidences_deg=(30.0,), views_deg=(30.0, -20.0), resolution=16, samples=1)
    brdf = {}
    for weight in (0.0, 1.0, 2.0):
        results = run_validation(None, tmp_path / str(weight), tables_dir=constant_bake, materials=("yarn",),
                                 settings=settings, swatches=False, specular_weight=weight)
        assert results["settings"]["yarn_specular"]["weight"] == weight
        brdf[weight] = np.array([v["brdf_rgb"] for v in results["materials"]["yarn"]["views"]])
    sheen = brdf[1.0] - brdf[0.0]
    assert sheen[0].min() > 1e-3  # the mirror view
    np.testing.assert_allclose(brdf[2.0] - brdf[0.0], 2.0 * sheen, rtol=1e-3, atol=1e-6)
    with pytest.raises(ParameterError, match="specular_weight"):
        ValidationRun(None, tmp_path / "bad", tables_dir=constant_bake, materials=("yarn",), specular_weight=-1.0)


@pytest.mark.blender
def test_the_whole_sweep_writes_calibrated_results_plots_and_report(tmp_path, constant_bake):
    fresh_file()
    settings = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(-60.0, 0.0, 60.0), resolution=16, samples=1)
    calls = []
    results = run_validation(None, tmp_path, tables_dir=constant_bake, measured_csv=SYNTHETIC_CSV, settings=settings,
                             progress=lambda done, total, what: calls.append((done, total, what)))
    # 2 materials × (6 views + 2 swatches), then the report, written before the folder is swapped in
    assert [call[:2] for call in calls] == [(k, 16) for k in range(1, 17)] + [(16, 16)]
    assert calls[-1][2] == "report written"
    on_disk = json.loads((tmp_path / "results.json").read_text())
    measured_sum = sum(next(p for p in on_disk["measurement"]["in_plane"]["0"] if p[0] == 0.0)[1:])  # θi = θv = 0
    patch = on_disk["settings"]["patch_mm"]
    for kind in ("yarn", "baseline"):
        entry = on_disk["materials"][kind]
        assert len(entry["views"]) == 6
        for v in entry["views"]:
            # the JSON's BRDF is its pixel sum through the documented formula
            f = np.array(v["rgb_sum"]) * (patch / 16) ** 2 / (1.0 * math.cos(math.radians(v["theta_i_deg"])) * patch**2)
            np.testing.assert_allclose(v["brdf_rgb"], f, rtol=1e-9)
        normal = next(v for v in entry["views"] if v["theta_i_deg"] == 0 and v["theta_v_deg"] == 0)
        r, g, b = normal["brdf_rgb"]
        assert entry["table1"] == pytest.approx({"B/R": b / r, "G/R": g / r})
        # the paper's normalisation: the model's normal-incidence, normal-view value becomes the measured one
        assert sum(normal["paper_normalised_rgb"]) == pytest.approx(measured_sum)
        assert entry["metrics"]["views_compared"] == 6
        for side in ("front", "back"):
            assert png_size(tmp_path / entry["swatches"][side]["png"]) == (16, 16)
    # lit from behind, the baseline's surface terms see no light; the yarn table transmits
    assert sum(on_disk["materials"]["baseline"]["swatches"]["back"]["mean_rgb_per_irradiance"]) < 1e-3
    assert sum(on_disk["materials"]["yarn"]["swatches"]["back"]["mean_rgb_per_irradiance"]) > 0.05
    assert on_disk["files"]["plots"] == ["sweeps.png", "sweeps_paper_normalised.png"]
    for name in ("report.md", "sweeps.png", "sweeps_paper_normalised.png"):
        assert (tmp_path / name).stat().st_size > 0
    report = (tmp_path / "report.md").read_text()
    assert "(sweeps.png)" in report and "SYNTHETIC" in report and "Table 1" in report
    assert results["materials"]["yarn"]["table1"] == pytest.approx(on_disk["materials"]["yarn"]["table1"])
    # the user's file is as it was: the rig's scene, objects and materials are gone
    assert [s.name for s in bpy.data.scenes] == ["Scene"]
    assert len(bpy.data.objects) == len(bpy.data.meshes) == len(bpy.data.materials) == 0


@pytest.mark.blender
def test_a_user_sample_is_measured_from_a_copy_and_left_untouched(tmp_path):
    fresh_file()
    plane = calibration_plane(10.0, name="user plane")
    bpy.context.scene.collection.objects.link(plane)
    own = bpy.data.materials.new("user material")
    plane.data.materials.append(own)
    plane.location = (3.0, -2.0, 1.0)  # the rig measures the sample in its own frame
    settings = RigSettings(incidences_deg=(30.0,), views_deg=(0.0,), resolution=8, samples=1, patch_mm=4.0)
    results = run_validation(plane, tmp_path, settings=settings, swatches=False)
    # default baseline: Lambert 0.6/π red plus Cook–Torrance m = 0.8 at (θi, θv) = (30°, 0°), white
    expected = np.array([0.6 / math.pi, 0.0, 0.0]) + cook_torrance(math.radians(30.0), 0.0)
    np.testing.assert_allclose(results["materials"]["baseline"]["views"][0]["brdf_rgb"], expected, rtol=1e-3)
    assert list(plane.data.materials) == [own] and tuple(plane.location) == (3.0, -2.0, 1.0)
    assert [o.name for o in bpy.data.objects] == ["user plane"]


@pytest.mark.blender
def test_cancel_stops_before_the_next_render_and_removes_the_rig(tmp_path):
    fresh_file()
    settings = RigSettings(incidences_deg=(0.0, 30.0), views_deg=(0.0, 30.0), resolution=8, samples=1)
    done = []
    with pytest.raises(ValidationCancelled, match="nothing was written"):
        run_validation(None, tmp_path / "validation", settings=settings, progress=lambda d, t, w: done.append(d),
                       cancel=lambda: len(done) >= 2)
    assert done == [1, 2]
    assert list(tmp_path.iterdir()) == []  # the folder is written as a whole: no renders, no staging left
    assert [s.name for s in bpy.data.scenes] == ["Scene"] and len(bpy.data.objects) == 0


@pytest.mark.blender
def test_a_sweep_replaces_an_earlier_one_as_a_whole_and_never_a_folder_of_other_files(tmp_path):
    fresh_file()
    settings = RigSettings(incidences_deg=(0.0,), views_deg=(0.0,), resolution=8, samples=1)
    out = tmp_path / "validation"
    run_validation(None, out, settings=settings, swatches=False)
    earlier = sorted(p.relative_to(out) for p in out.rglob("*"))
    assert pathlib.Path("results.json") in earlier and pathlib.Path("renders/baseline/i+00.0_v+00.0.exr") in earlier
    done = []
    with pytest.raises(ValidationCancelled):
        run_validation(None, out, settings=settings, progress=lambda d, t, w: done.append(d),
                       cancel=lambda: len(done) >= 1)
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == earlier and sorted(tmp_path.iterdir()) == [out]
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ParameterError, match=r"out_dir = .*notes\.txt"):
        ValidationRun(None, out, settings=settings)


@pytest.mark.blender
def test_a_run_stepped_like_the_modal_operator_can_be_closed_midway(tmp_path):
    fresh_file()
    run = ValidationRun(None, tmp_path, settings=RigSettings(incidences_deg=(0.0,), views_deg=(0.0, 40.0),
                                                             resolution=8, samples=1), swatches=False)
    steps = run.steps()
    assert next(steps).done == 1 and RIG_SCENE in bpy.data.scenes
    steps.close()  # what Esc does
    assert RIG_SCENE not in bpy.data.scenes and len(bpy.data.objects) == 0 and run.results is None


@pytest.fixture
def operator_registered():
    from clothlight.blender.validation.operator import CLOTHLIGHT_OT_validate

    registered = hasattr(bpy.types, CLOTHLIGHT_OT_validate.__name__)
    if not registered:
        bpy.utils.register_class(CLOTHLIGHT_OT_validate)
    yield
    if not registered:
        bpy.utils.unregister_class(CLOTHLIGHT_OT_validate)


@pytest.mark.blender
def test_the_operator_runs_the_sweep_in_background_mode(tmp_path, operator_registered):
    fresh_file()
    options = dict(out_dir=str(tmp_path), materials={"BASELINE"}, incidences="0", views="0, 30", resolution=8,
                   samples=1, swatches=False)
    assert bpy.ops.clothlight.validate("INVOKE_DEFAULT", **options) == {"FINISHED"}
    results = json.loads((tmp_path / "results.json").read_text())
    assert [v["theta_v_deg"] for v in results["materials"]["baseline"]["views"]] == [0.0, 30.0]
    assert bpy.context.window_manager["clothlight_validation_dir"] == str(tmp_path)
    assert bpy.data.images["ClothLight Validation"].filepath == str(tmp_path / "sweeps.png")
    with pytest.raises(RuntimeError, match="incidences"):
        bpy.ops.clothlight.validate(**{**options, "incidences": "0 thirty"})
    with pytest.raises(RuntimeError, match="tables_dir"):
        bpy.ops.clothlight.validate(**{**options, "materials": {"YARN"}})


@pytest.mark.blender
def test_the_command_line_and_the_blender_script_share_arguments(tmp_path):
    from clothlight.validate import main

    tiny = ["--material", "baseline", "--resolution", "8", "--samples", "1", "--incidences", "0", "--views", "0",
            "--no-swatches"]
    assert main(["--out", str(tmp_path / "a"), *tiny]) == 0
    assert (tmp_path / "a" / "results.json").is_file()
    assert main(["--out", str(tmp_path / "b"), "--views", "0", "95"]) == 2
    assert main(["--out", str(tmp_path / "b"), "--measured", str(tmp_path / "missing.csv")]) == 2
    script = subprocess.run([sys.executable, str(REPO / "scripts" / "validate_blender.py"), "--",
                             "--out", str(tmp_path / "c"), *tiny, "--json"], cwd=REPO, capture_output=True, text=True)
    assert script.returncode == 0, script.stderr[-2000:]
    assert json.loads(script.stdout)["materials"]["baseline"]["views"][0]["theta_v_deg"] == 0.0


# -- light between yarns: the general-lighting yarn material path traced in a scene ---------------

SHIPPED_TABLES = REPO / "example_blends" / "tables" / "paper_2008"
BOUNCE_SETTINGS = ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces")


def bounces_per_material(run):
    """Run a ValidationRun step by step; the rig's bounce limits seen after each material's renders."""
    seen = {}
    for step in run.steps():
        cycles = bpy.data.scenes[RIG_SCENE].cycles
        seen.setdefault(step.what.split(":")[0], set()).add(tuple(getattr(cycles, n) for n in BOUNCE_SETTINGS))
    return seen


@pytest.mark.blender
def test_light_between_yarns_only_adds_and_the_bounces_end_with_the_scene_material(tmp_path):
    from clothlight.blender.validation.rig import SCENE_BOUNCES

    fresh_file()
    settings = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(0.0, 60.0), resolution=32, samples=4)
    # named out of order: a sweep runs them in MATERIALS' order, the baseline after yarn_scene
    run = ValidationRun(None, tmp_path, materials=("baseline", "yarn_scene", "yarn_general"),
                        tables_dir=SHIPPED_TABLES, settings=settings, swatches=False)
    assert run.materials == ("yarn_general", "yarn_scene", "baseline")
    seen = bounces_per_material(run)
    assert seen["yarn_general"] == seen["baseline"] == {(0, 0, 0, 0)}  # direct light only, before and after
    assert seen["yarn_scene"] == {tuple(SCENE_BOUNCES[n] for n in BOUNCE_SETTINGS)}
    results = run.results
    direct = {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"])
              for v in results["materials"]["yarn_general"]["views"]}
    scene = {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"])
             for v in results["materials"]["yarn_scene"]["views"]}
    light = results["interreflection"]
    assert light["views_compared"] == 4
    assert [(v["theta_i_deg"], v["theta_v_deg"]) for v in light["views"]] == list(direct)
    for view in light["views"]:
        key = (view["theta_i_deg"], view["theta_v_deg"])
        # light between yarns only adds (same seed: the direct light is sampled alike, so noise is small)
        assert np.all(scene[key] >= direct[key] * (1.0 - 1e-3)), key
        assert scene[key][0] > direct[key][0] * 1.001  # red: the yarns light each other
        np.testing.assert_allclose(view["ratio_rgb"], scene[key] / direct[key], rtol=1e-9)
        np.testing.assert_allclose(view["added_brdf_rgb"], scene[key] - direct[key], atol=1e-12)
    red = [v["ratio_rgb"][0] for v in light["views"]]
    assert light["R"]["mean"] == pytest.approx(np.mean(red)) and light["R"]["max"] == pytest.approx(max(red))
    assert light["R"]["min"] == pytest.approx(min(red)) and min(red) >= 1.0
    at = light["R"]["max_at"]
    assert scene[(at["theta_i_deg"], at["theta_v_deg"])][0] / direct[(at["theta_i_deg"], at["theta_v_deg"])][0] \
        == pytest.approx(max(red))
    total = [scene[k].sum() / direct[k].sum() for k in direct]
    assert light["RGB"]["mean"] == pytest.approx(np.mean(total))
    assert light["comparison"]["views_compared"] == 4
    report = (tmp_path / "report.md").read_text()
    assert "## Light between yarns" in report and f"{light['R']['max']:.4g}" in report
    assert json.loads((tmp_path / "results.json").read_text())["interreflection"]["R"]["max_at"] == at
    assert "interreflection" not in run_validation(None, tmp_path / "alone", materials=("yarn_scene",),
                                                   tables_dir=SHIPPED_TABLES, settings=settings, swatches=False)


@pytest.mark.blender
def test_a_flat_plane_has_no_light_between_yarns(tmp_path):
    # nothing to inter-reflect: a plane's reflected light leaves it, its transmitted light finds nothing
    fresh_file()
    plane = calibration_plane(10.0, name="flat yarn")
    settings = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(-30.0, 40.0), resolution=16, samples=4,
                           patch_mm=4.0)
    results = run_validation(plane, tmp_path, materials=("yarn_general", "yarn_scene"), tables_dir=SHIPPED_TABLES,
                             settings=settings)
    light = results["interreflection"]
    assert light["views_compared"] == 4
    # within noise: at 4 samples a rare bounced path adds < 0.1 % in red at a view on the light's side
    # (5 × 10⁻⁴, and 16 times less at 64 samples); the woven sample's red gains 2–8 % (docs/validation.md)
    for view in light["views"]:
        np.testing.assert_allclose(view["ratio_rgb"], 1.0, atol=2e-3)
    for side in ("front", "back"):
        np.testing.assert_allclose(light["swatches"][side]["added_rgb_per_irradiance"], 0.0, atol=1e-4)


@pytest.mark.blender
def test_the_command_line_and_the_operator_offer_the_scene_material(tmp_path, operator_registered):
    from clothlight.validate import build_parser

    args = build_parser().parse_args(["--out", str(tmp_path), "--material", "yarn_general", "yarn_scene"])
    assert args.material == ["yarn_general", "yarn_scene"]
    fresh_file()
    options = dict(out_dir=str(tmp_path / "op"), materials={"YARN_GENERAL", "YARN_SCENE"},
                   tables_dir=str(SHIPPED_TABLES), incidences="0", views="0", resolution=8, samples=1,
                   swatches=False)
    assert bpy.ops.clothlight.validate(**options) == {"FINISHED"}
    results = json.loads((tmp_path / "op" / "results.json").read_text())
    assert list(results["materials"]) == ["yarn_general", "yarn_scene"] and results["interreflection"]["R"]
