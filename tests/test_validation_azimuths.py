"""The validation rig averages the sample over its azimuths, as the fit's forward model does.

MERL's measurements are isotropic: at a view they report the weave's mean over its azimuth about the
normal.  ``python -m clothlight.validate --sample-azimuths 0 90`` (by default the ``--tables`` bake's
recorded ``[sample] azimuths_deg``, else one turn) renders every view with the sun and the cameras
turned together about the sample's normal to each azimuth and reports the mean.

Without Blender: the framing of a turned sample and the command line's checks, which refuse bad
azimuths with exit code 2 before the sweep (and Blender) starts.  With Blender, tiny renders (16–32
pixels, one sample): a run at 0° and 90° reports at every view the mean of the runs at 0° alone and
at 90° alone; a bake recording its azimuths is averaged at them by default; at 45° the framed patch
stays on the sample.
"""

import json
import math
import shutil

import numpy as np
import pytest

import clothlight.validate as validate_cli
from clothlight.validation.framing import (
    DEFAULT_RIG_AZIMUTHS_DEG,
    SampleBounds,
    check_patch,
    largest_patch_mm,
    required_half_extent_mm,
)
from clothlight.validation.measure import ViewMeasurement, mean_over_turns
from precompute.errors import ParameterError
from precompute.optics.ballistic import ATTENUATION_SAMPLES
from precompute.tables.closure_fit import LOBES
from precompute.tables.folder import SAMPLE_AZIMUTHS_RECORD_KEY, SUMMARY_FILE
from tests.helpers import write_yarn_table_folder

RHO = np.array([0.2, 0.1, 0.05])


@pytest.fixture(scope="module")
def small_bake(tmp_path_factory):
    """A tiny yarn bake folder (a constant, opaque yarn BRDF) whose summary records no azimuths."""
    n_i, n_o = 5, 4
    return write_yarn_table_folder(
        tmp_path_factory.mktemp("bake"), np.broadcast_to(RHO, (n_i * n_o, n_i * n_o, 3)),
        np.zeros((n_o, len(LOBES) * n_o, 3)), np.zeros((1, ATTENUATION_SAMPLES, 3)),
        incidence_resolution=n_i, exit_resolution=n_o, optional=False)


def recording(bake, folder, azimuths):
    """A copy of ``bake`` in ``folder`` whose summary records ``azimuths``, as a preset naming
    ``[sample] azimuths_deg`` bakes (the file hashes cover the tables, not the summary)."""
    shutil.copytree(bake, folder)
    summary = json.loads((folder / SUMMARY_FILE).read_text())
    summary[SAMPLE_AZIMUTHS_RECORD_KEY] = azimuths
    (folder / SUMMARY_FILE).write_text(json.dumps(summary))
    return folder


# -- framing a turned sample (no Blender) ---------------------------------------------------------


def test_a_turned_patch_must_reach_further_and_a_single_turn_frames_as_before():
    bounds = SampleBounds((0.0, 0.0, 0.0), (5.0, 4.0), 0.2, edge_band=0.5)
    h, tilt = 0.2, 0.2 * math.tan(math.radians(70.0)) + 0.4 * math.tan(math.radians(60.0))
    along = 2.0 / 2.0 + 2.0 / 16
    # one turn at 0°: the rectangle of the module docstring, as sweeps have always framed it
    assert required_half_extent_mm(2.0, bounds, 16, 70.0, 60.0) == pytest.approx((along + tilt + 0.5, along + 0.5))
    assert required_half_extent_mm(2.0, bounds, 16, 70.0, 60.0, (0.0, 90.0)) == pytest.approx(
        (along + tilt + 0.5, along + tilt + 0.5))  # at 90° the tilt lies along the sample's y
    diagonal = (along + tilt + along) / math.sqrt(2.0) + 0.5
    assert required_half_extent_mm(2.0, bounds, 16, 70.0, 60.0, (45.0,)) == pytest.approx((diagonal, diagonal))
    # without a weave period the largest patch meets the tighter side exactly, at every turn
    plain = SampleBounds((0.0, 0.0, 0.0), (5.0, 4.0), h, edge_band=0.5)
    for azimuths in ((0.0,), (0.0, 90.0), (45.0,), (0.0, 45.0, 90.0, 135.0), (30.0,)):
        largest = largest_patch_mm(plain, 16, 70.0, 60.0, azimuths)
        need = required_half_extent_mm(largest, plain, 16, 70.0, 60.0, azimuths)
        assert max(need[0] - 5.0, need[1] - 4.0) == pytest.approx(0.0, abs=1e-12), azimuths
    assert largest_patch_mm(plain, 16, 70.0, 60.0, (45.0,)) < largest_patch_mm(plain, 16, 70.0, 60.0, (0.0, 90.0))
    # a patch that fits the sample square to the light is refused turned to 45°, naming the turn
    square = SampleBounds((0.0, 0.0, 0.0), (3.0, 3.0), h, edge_band=0.5)
    check_patch(2.4, square, 128, 70.0, 60.0)  # ≤ 2.48 mm square to the light, ≤ 2.26 mm turned
    with pytest.raises(ParameterError, match=r"patch_mm = 2.4 .*≤ 2.258 mm .*turned to 0, 45°"):
        check_patch(2.4, square, 128, 70.0, 60.0, (0.0, 45.0))


def test_the_mean_over_turns_averages_every_quantity_and_keeps_a_single_turn():
    def view(theta_v, scale, pixels):
        return ViewMeasurement(30.0, theta_v, [scale, 2 * scale, 3 * scale], pixels, pixels / 256,
                               [10 * scale] * 3, [scale / 10] * 3)

    one = [view(0.0, 1.0, 200), view(40.0, 2.0, 210)]
    assert mean_over_turns([one]) == one
    other = [view(0.0, 3.0, 100), view(40.0, 4.0, 211)]
    mean = mean_over_turns([one, other])
    assert [v.theta_v_deg for v in mean] == [0.0, 40.0]
    assert mean[0].rgb_sum == pytest.approx([2.0, 4.0, 6.0]) and mean[1].brdf_rgb == pytest.approx([0.3] * 3)
    assert mean[0].sum_over_cos_rgb == pytest.approx([20.0] * 3) and mean[0].coverage == pytest.approx(150 / 256)
    assert (mean[0].cloth_pixels, mean[1].cloth_pixels) == (150, 210)  # 210.5, rounded to even
    with pytest.raises(ParameterError, match="turns"):
        mean_over_turns([one, other[::-1]])


# -- the command line (no Blender: the sweep is replaced by a sentinel) -------------------------


class SweepStarted(BaseException):
    """Raised where the command would start its sweep and import Blender: the arguments got through."""


@pytest.fixture
def no_sweep(monkeypatch):
    started = []

    def sweep(args, interrupt):
        started.append(args)
        raise SweepStarted

    monkeypatch.setattr(validate_cli, "_sweep", sweep)
    return started


@pytest.mark.parametrize("azimuths, expected", [
    (["90", "0"], "ascending"), (["0", "0"], "distinct"), (["180"], "[0, 180)"), (["-45"], "[0, 180)"),
    (["nan"], "[0, 180)"), (["ten"], "invalid float value"), ([], "expected at least one argument"),
])
def test_bad_sample_azimuths_exit_2_naming_the_option_before_the_sweep(tmp_path, capsys, no_sweep, azimuths, expected):
    code = validate_cli.main(["--out", str(tmp_path / "v"), "--sample-azimuths", *azimuths])
    err = capsys.readouterr().err
    assert code == 2 and "--sample-azimuths" in err and expected in err, err
    assert no_sweep == [] and not (tmp_path / "v").exists()


def test_the_azimuths_come_from_the_option_else_the_bake_else_one_turn(tmp_path, no_sweep, small_bake):
    recorded = recording(small_bake, tmp_path / "recorded", [0, 45, 90, 135])
    for argv, expected in (([], DEFAULT_RIG_AZIMUTHS_DEG), (["--sample-azimuths", "0", "90"], (0.0, 90.0)),
                           (["--tables", str(small_bake)], (0.0,)),
                           (["--tables", str(recorded)], (0.0, 45.0, 90.0, 135.0)),
                           (["--tables", str(recorded), "--sample-azimuths", "30"], (30.0,))):
        with pytest.raises(SweepStarted):
            validate_cli.main(["--out", str(tmp_path / "v"), *argv])
        assert no_sweep.pop().sample_azimuths == expected, argv
    assert DEFAULT_RIG_AZIMUTHS_DEG == (0.0,)


def test_a_bake_recording_bad_azimuths_is_refused_naming_its_summary(tmp_path, capsys, no_sweep, small_bake):
    bad = recording(small_bake, tmp_path / "bad", [90, 0])
    assert validate_cli.main(["--out", str(tmp_path / "v"), "--tables", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "summary.json" in err and SAMPLE_AZIMUTHS_RECORD_KEY in err and no_sweep == []


# -- sweeps (Blender, tiny renders) -------------------------------------------------------------

TWILL = {"interlacing": "twill_2_1", "warp_count": 12, "weft_count": 12}  # not alike turned by 90°


def brdf_by_view(entry):
    return {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"]) for v in entry["views"]}


@pytest.mark.render
def test_a_run_at_two_azimuths_reports_the_mean_of_the_runs_at_each(tmp_path, bpy):
    from clothlight.blender.validation.rig import RigSettings
    from clothlight.blender.validation.run import run_validation
    from clothlight.weave import WeaveParameters

    bpy.ops.wm.read_homefile(use_empty=True)
    weave = WeaveParameters(**TWILL)
    runs, calls = {}, []
    for azimuths in ((0.0,), (90.0,), (0.0, 90.0)):
        settings = RigSettings(incidences_deg=(30.0,), views_deg=(-30.0, 0.0, 40.0), resolution=16, samples=1,
                               sample_azimuths_deg=azimuths)
        runs[azimuths] = run_validation(weave, tmp_path / "-".join(f"{a:g}" for a in azimuths), scheduler=None,
                                        materials=("baseline",), settings=settings,
                                        progress=lambda done, total, what: calls.append((azimuths, done, total)))
    # every render counted: 3 views and 2 swatches at each turn, then the report
    assert [c[1:] for c in calls if c[0] == (0.0, 90.0)] == [(k, 10) for k in range(1, 11)] + [(10, 10)]
    at_0, at_90 = (brdf_by_view(runs[(a,)]["materials"]["baseline"]) for a in (0.0, 90.0))
    both = runs[(0.0, 90.0)]
    mean = brdf_by_view(both["materials"]["baseline"])
    assert list(mean) == list(at_0)
    for key in mean:
        np.testing.assert_allclose(mean[key], (at_0[key] + at_90[key]) / 2.0, rtol=1e-6, err_msg=str(key))
    # the turn matters on a twill: the mean is not either turn's value
    assert max(abs(at_0[k][0] / at_90[k][0] - 1.0) for k in mean) > 1e-2
    turns = both["materials"]["baseline"]["turns"]
    assert [t["azimuth_deg"] for t in turns] == [0.0, 90.0]
    for turn, single in zip(turns, (at_0, at_90)):
        for v in turn["views"]:
            np.testing.assert_allclose(v["brdf_rgb"], single[(v["theta_i_deg"], v["theta_v_deg"])], rtol=1e-6)
    for side in ("front", "back"):
        swatch = both["materials"]["baseline"]["swatches"][side]
        singles = [np.array(runs[(a,)]["materials"]["baseline"]["swatches"][side]["mean_rgb_per_irradiance"])
                   for a in (0.0, 90.0)]
        np.testing.assert_allclose(swatch["mean_rgb_per_irradiance"], (singles[0] + singles[1]) / 2.0,
                                   rtol=1e-6, atol=1e-12)
    # the azimuths are named in the results and the report; file names carry them only with several turns
    out = tmp_path / "0-90"
    assert json.loads((out / "results.json").read_text())["sample_azimuths_deg"] == [0.0, 90.0]
    assert [runs[(a,)]["sample_azimuths_deg"] for a in (0.0, 90.0)] == [[0.0], [90.0]]
    assert "mean of 2 renders with the warp at 0°, 90°" in (out / "report.md").read_text()
    assert sorted(p.name for p in (out / "renders" / "baseline").iterdir())[:2] == [
        "i+30.0_v+00.0_a000.0.exr", "i+30.0_v+00.0_a090.0.exr"]
    assert (out / "swatches" / "baseline_front_a090.0.png").is_file()
    assert sorted(p.name for p in (tmp_path / "90" / "renders" / "baseline").iterdir())[0] == "i+30.0_v+00.0.exr"
    assert (tmp_path / "90" / "swatches" / "baseline_front.png").is_file()


@pytest.mark.render
def test_a_bake_that_records_its_azimuths_is_averaged_at_them_by_default(tmp_path, bpy, small_bake):
    bake = recording(small_bake, tmp_path / "bake", [0, 90])
    tiny = ["--material", "yarn", "--resolution", "16", "--samples", "1", "--incidences", "30", "--views", "0", "40",
            "--no-swatches", "--scheduler", "none", "--tables", str(bake)]
    assert validate_cli.main(["--out", str(tmp_path / "default"), *tiny]) == 0
    results = json.loads((tmp_path / "default" / "results.json").read_text())
    assert results["sample_azimuths_deg"] == [0.0, 90.0]
    entry = results["materials"]["yarn"]
    assert [t["azimuth_deg"] for t in entry["turns"]] == [0.0, 90.0]
    for index, view in enumerate(entry["views"]):
        turned = [np.array(t["views"][index]["brdf_rgb"]) for t in entry["turns"]]
        np.testing.assert_allclose(view["brdf_rgb"], (turned[0] + turned[1]) / 2.0, rtol=1e-12)
    assert len(list((tmp_path / "default" / "renders" / "yarn").iterdir())) == 4
    # the option overrides the bake
    assert validate_cli.main(["--out", str(tmp_path / "one"), *tiny, "--sample-azimuths", "90"]) == 0
    one = json.loads((tmp_path / "one" / "results.json").read_text())
    assert one["sample_azimuths_deg"] == [90.0] and "turns" not in one["materials"]["yarn"]
    np.testing.assert_allclose([v["brdf_rgb"] for v in one["materials"]["yarn"]["views"]],
                               [t["brdf_rgb"] for t in entry["turns"][1]["views"]], rtol=1e-6)


@pytest.mark.render
def test_a_sample_turned_to_45_degrees_shows_no_edge(tmp_path, bpy, monkeypatch):
    """The default sample and a much larger one give the same pixels turned to 45° at the most
    oblique views and incidence.  Control: with the rig's check switched off, a patch too large for
    the turned sample does show its edges."""
    from clothlight.blender.materials import SUN_MODE, build_baseline_material
    from clothlight.blender.validation.rig import RigSettings, build_rig
    from clothlight.weave import WeaveParameters

    def measure(count, patch_mm):
        bpy.ops.wm.read_homefile(use_empty=True)
        settings = RigSettings(incidences_deg=(0.0, 60.0), views_deg=(-60.0, 70.0), resolution=32, samples=1,
                               patch_mm=patch_mm, sample_azimuths_deg=(45.0,))
        rig = build_rig(WeaveParameters(warp_count=count, weft_count=count), settings)
        with bpy.context.temp_override(scene=rig.scene):  # script nodes compile through the rig's engine
            material = build_baseline_material(name="test baseline", mode=SUN_MODE)
        rig.use_material(material)
        rig.set_azimuth(45.0)
        measured = []
        for theta_i in settings.incidences_deg:
            rig.set_incidence(theta_i)
            for theta_v in settings.views_deg:
                rig.set_view(theta_v)
                measured.append(rig.measure(tmp_path / f"{count}_{theta_i:g}_{theta_v:g}.exr").brdf_rgb[0])
        patch = rig.patch_mm
        rig.remove()
        bpy.data.materials.remove(material)
        return patch, np.array(measured)

    patch, small = measure(12, None)
    assert patch == pytest.approx(2.0)  # still two repeats: the default sample holds them turned
    _, large = measure(20, patch)
    np.testing.assert_allclose(small, large, rtol=1e-4)
    monkeypatch.setattr("clothlight.blender.validation.rig.check_patch", lambda *args: None)
    _, edged = measure(12, 4.0)  # its corners turned to 45° reach 2.8 mm from the centre of this 6 mm sample
    _, reference = measure(20, 4.0)
    assert np.max(np.abs(edged / reference - 1.0)) > 1e-3


@pytest.mark.slow
@pytest.mark.render
def test_turns_rendered_on_a_cluster_are_the_ones_rendered_here(tmp_path, bpy):
    """The command line's default scheduler where dask is installed: the same results and file names."""
    pytest.importorskip("distributed")
    from clothlight.blender.validation.rig import RigSettings
    from clothlight.blender.validation.run import run_validation

    bpy.ops.wm.read_homefile(use_empty=True)
    settings = RigSettings(incidences_deg=(30.0,), views_deg=(0.0, 40.0), resolution=16, samples=1,
                           sample_azimuths_deg=(0.0, 45.0))
    options = {"materials": ("baseline",), "settings": settings}
    here = run_validation(None, tmp_path / "here", **options)
    reports = []
    spread = run_validation(None, tmp_path / "spread", scheduler="local",
                            progress=lambda done, total, what: reports.append((done, total)), **options)

    def without_seconds(results):
        return json.dumps({k: v for k, v in results.items() if k not in ("seconds", "files")}, sort_keys=True)

    assert without_seconds(spread) == without_seconds(here)
    assert [t["azimuth_deg"] for t in here["materials"]["baseline"]["turns"]] == [0.0, 45.0]
    files = sorted(p.relative_to(tmp_path / "here") for p in (tmp_path / "here").rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(tmp_path / "spread") for p in (tmp_path / "spread").rglob("*") if p.is_file())
    assert len([p for p in files if p.suffix == ".exr"]) == 2 * (2 + 2)
    assert reports[-1] == (8, 8)


def test_the_band_figures_script_names_the_azimuths(tmp_path, capsys, monkeypatch):
    import importlib.util
    import pathlib
    import sys

    path = pathlib.Path(__file__).resolve().parents[1] / "scripts" / "rendered_fabric_figures.py"
    spec = importlib.util.spec_from_file_location("rendered_fabric_figures", path)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    monkeypatch.setattr(script, "rendered_figures", lambda results: {})
    results = tmp_path / "results.json"
    for recorded, line in (([0.0, 45.0, 90.0, 135.0], "sample averaged over the warp at 0°, 45°, 90°, 135°"),
                           ([0.0], "sample at one turn, the warp at 0°"), (None, "")):
        results.write_text(json.dumps({"materials": {}} | ({"sample_azimuths_deg": recorded} if recorded else {})))
        monkeypatch.setattr(sys, "argv", ["rendered_fabric_figures.py", str(results)])
        assert script.main() == 0
        out = capsys.readouterr().out
        assert out.startswith(line) and (line or out == ""), out


def operator_results(bpy, bake, out, **settings) -> dict:
    """results.json of the add-on's Validate operator run on ``bake`` with no sample active (the class
    registered for the run where the add-on is not)."""
    from clothlight.blender.validation.operator import CLOTHLIGHT_OT_validate

    registered = hasattr(bpy.types, CLOTHLIGHT_OT_validate.__name__)
    if not registered:
        bpy.utils.register_class(CLOTHLIGHT_OT_validate)
    try:
        bpy.ops.wm.read_homefile(use_empty=True)
        assert bpy.ops.clothlight.validate(out_dir=str(out), materials={"YARN"}, tables_dir=str(bake),
                                           incidences="30", samples=1, swatches=False, **settings) == {"FINISHED"}
    finally:
        if not registered:
            bpy.utils.unregister_class(CLOTHLIGHT_OT_validate)
    return json.loads((out / "results.json").read_text())


@pytest.mark.render
def test_the_operator_takes_the_azimuths_from_its_tables(tmp_path, bpy, small_bake):
    bake = recording(small_bake, tmp_path / "bake", [0, 90])
    results = operator_results(bpy, bake, tmp_path / "v", views="0 40", resolution=16)
    assert results["sample_azimuths_deg"] == [0.0, 90.0] and len(results["materials"]["yarn"]["turns"]) == 2


@pytest.mark.render
def test_the_operator_builds_the_weave_its_tables_were_fitted_on(tmp_path, bpy, small_bake):
    from clothlight.weave.sample_weaves import sample_weave
    from precompute.tables.folder import SAMPLE_WEAVE_KEY

    bake = recording(small_bake, tmp_path / "bake", [0])
    summary = json.loads((bake / SUMMARY_FILE).read_text())
    summary["medium"] = {"yarn": {"radius_mm": 0.1}}
    (bake / SUMMARY_FILE).write_text(json.dumps({**summary, SAMPLE_WEAVE_KEY: "pressed"}))
    results = operator_results(bpy, bake, tmp_path / "v", views="0", resolution=64)
    pressed, built = sample_weave("pressed", 0.1), results["settings"]["sample"]["weave"]
    assert built["spacing_mm"] == pytest.approx(pressed.spacing_mm)
    assert built["semi_axes_mm"] == pytest.approx(list(pressed.semi_axes_mm))
    assert built["warp_count"] == pressed.warp_count
