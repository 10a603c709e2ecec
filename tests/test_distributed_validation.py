"""The validation sweep on a dask cluster: every worker renders in a rig of its own, and the
results, swatches and renders are the ones of the sweep rendered in this process."""

from __future__ import annotations

import json
import pathlib

import numpy as np
import OpenEXR
import pytest

pytest.importorskip("distributed")
bpy = pytest.importorskip("bpy")

from clothlight.blender.validation.rig import RigSettings  # noqa: E402
from clothlight.blender.validation.run import ValidationCancelled, run_validation  # noqa: E402
from clothlight.validation.framing import ParameterError  # noqa: E402

pytestmark = pytest.mark.slow

YARN_BAKE = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
SETTINGS = RigSettings(incidences_deg=(0.0, 45.0), views_deg=(-30.0, 0.0, 30.0), resolution=16, samples=2)


def _without_seconds(results: dict) -> dict:
    return {key: value for key, value in results.items() if key not in ("seconds", "files")}


def _pixels(path) -> np.ndarray:
    with OpenEXR.File(str(path)) as exr:
        return np.concatenate([np.asarray(channel.pixels) for part in exr.parts
                               for channel in part.channels.values()], axis=None)


def test_a_sweep_on_two_local_workers_is_the_one_rendered_here(tmp_path):
    options = {"materials": ("yarn", "baseline"), "tables_dir": YARN_BAKE, "settings": SETTINGS}
    here = run_validation(None, tmp_path / "here", **options)
    reports = []
    spread = run_validation(None, tmp_path / "spread", scheduler="local",
                            progress=lambda done, total, what: reports.append((done, total)), **options)
    assert json.dumps(_without_seconds(spread), sort_keys=True) == json.dumps(_without_seconds(here), sort_keys=True)
    assert here["materials"]["yarn"]["views"][0]["brdf_rgb"][0] > 0
    renders = sorted(p.relative_to(tmp_path / "here") for p in (tmp_path / "here" / "renders").rglob("*.exr"))
    assert len(renders) == 2 * (2 * 3 + 2)
    spread_renders = (tmp_path / "spread" / "renders").rglob("*.exr")
    assert renders == sorted(p.relative_to(tmp_path / "spread") for p in spread_renders)
    for render in renders:
        assert np.array_equal(_pixels(tmp_path / "here" / render), _pixels(tmp_path / "spread" / render)), render
    for png in ("swatches/yarn_front.png", "swatches/baseline_back.png"):
        assert (tmp_path / "here" / png).read_bytes() == (tmp_path / "spread" / png).read_bytes()
    assert reports[-1] == (16, 16) and [done for done, _ in reports] == sorted(done for done, _ in reports)


def test_cancel_stops_a_sweep_on_a_cluster_and_a_sample_object_is_not_sent(tmp_path):
    with pytest.raises(ValidationCancelled):
        run_validation(None, tmp_path / "cancelled", scheduler="local", cancel=lambda: True,
                       materials=("baseline",), settings=SETTINGS)
    assert not (tmp_path / "cancelled" / "results.json").exists()
    plane = bpy.data.objects.new("not a weave", bpy.data.meshes.new("not a weave"))
    try:
        with pytest.raises(ParameterError, match="scheduler"):
            run_validation(plane, tmp_path / "object", scheduler="local", materials=("baseline",), settings=SETTINGS)
    finally:
        bpy.data.objects.remove(plane)
