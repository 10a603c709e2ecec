"""The garment's thread count (clothlight/blender/garment/density.py): the validation weave at another
spacing, from the command line, the Bake Cloth worker and the Garment panel — at the settings and cache
key level (a cloth response renders for 45 min: none is rendered here)."""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from types import SimpleNamespace

import pytest

bpy = pytest.importorskip("bpy")

from clothlight import cloth_bake_worker, jobs  # noqa: E402
from clothlight.blender import operators, properties  # noqa: E402
from clothlight.blender.garment import bake, operator as garment_operator  # noqa: E402
from clothlight.blender.garment.density import (  # noqa: E402
    DEFAULT_THREADS_PER_CM,
    MM_PER_CM,
    THREADS_PER_CM,
    weave_at_thread_count,
)
from clothlight.blender.garment.measure import GoniometerSettings  # noqa: E402
from clothlight.blender.validation.rig import VALIDATION_WEAVE  # noqa: E402
from clothlight.weave import WeaveParameterError  # noqa: E402
from precompute.cache import entries as cache  # noqa: E402
from precompute.errors import ParameterError  # noqa: E402

SMALL = {"incidence_resolution": 3, "exit_resolution": 2, "pixels_per_patch": 6, "samples": 1}


def response_key(settings: GoniometerSettings) -> str:
    return cache.cache_key(bake.response_inputs(settings))


def test_the_default_thread_count_is_the_validation_weave_and_keeps_todays_settings_and_keys():
    assert DEFAULT_THREADS_PER_CM == MM_PER_CM / VALIDATION_WEAVE.spacing_mm
    for count in (None, DEFAULT_THREADS_PER_CM):
        assert weave_at_thread_count(count) is None
        settings = GoniometerSettings(**SMALL, weave=weave_at_thread_count(count))
        assert settings == GoniometerSettings(**SMALL)
        assert response_key(settings) == response_key(GoniometerSettings(**SMALL))


def test_another_thread_count_spaces_the_validation_yarns_and_keys_a_response_of_its_own():
    weave = weave_at_thread_count(16)
    settings = GoniometerSettings(**SMALL, weave=weave)
    # what summary.json's goniometer records: the validation weave's record at a spacing of 10/16 mm
    assert settings.to_dict()["weave"] == GoniometerSettings(
        **SMALL, weave=dataclasses.replace(VALIDATION_WEAVE, spacing_mm=0.625)).to_dict()["weave"]
    assert settings.to_dict()["weave"]["spacing_mm"] == 0.625
    keys = {response_key(GoniometerSettings(**SMALL, weave=weave_at_thread_count(n))) for n in (12, 16, 20, 24)}
    assert len(keys) == 4


@pytest.mark.parametrize("value", [0, -3, 9, 25, float("nan"), "ten", 12.5])
def test_a_thread_count_out_of_range_is_refused_naming_it(value):
    with pytest.raises(ParameterError, match=r"threads_per_cm .*\[10, 24\] threads/cm"):
        weave_at_thread_count(value)


def test_the_thread_counts_ends_are_the_weaves_clearance_and_the_responses_sampling():
    densest = weave_at_thread_count(THREADS_PER_CM.high)  # builds: the clearance check passes
    assert densest.spacing_mm == MM_PER_CM / THREADS_PER_CM.high
    with pytest.raises(WeaveParameterError):
        dataclasses.replace(VALIDATION_WEAVE, spacing_mm=MM_PER_CM / (THREADS_PER_CM.high + 1))
    # Camera samples of the response across a yarn's width: a patch is one plain repeat, two spacings.
    width = 2.0 * VALIDATION_WEAVE.cross_section_mm[0]

    def across(count):
        return width / (2.0 * MM_PER_CM / count / bake.RESPONSE_SAMPLES_PER_SIDE)

    assert across(THREADS_PER_CM.low) >= 2.0 > across(THREADS_PER_CM.low - 1)


def test_the_worker_measures_the_thread_count_it_is_given(tmp_path, monkeypatch, capsys):
    assert jobs.ClothBakeJob(tmp_path, cache_dir=tmp_path, settings={"threads_per_cm": 16}).arguments()[-2:] == [
        "--threads-per-cm", "16"]
    given = []

    def bake_cloth(tables, settings, **kwargs):
        given.append(settings)
        return tmp_path, False

    monkeypatch.setattr(bake, "bake_cloth", bake_cloth)
    # The worker watches its stdin for a cancel, and takes its end for one: a pipe never closed (its
    # watching threads are daemons, left blocked on it).
    read_end, _write_end = os.pipe()
    monkeypatch.setattr(sys, "stdin", os.fdopen(read_end))
    base = ["--tables", str(tmp_path), "--cache-dir", str(tmp_path)]
    assert cloth_bake_worker.main([*base, "--threads-per-cm", "16"]) == 0
    assert cloth_bake_worker.main(base) == 0
    assert [settings.to_dict() for settings in given] == [
        GoniometerSettings(weave=weave_at_thread_count(16)).to_dict(), GoniometerSettings().to_dict()]
    capsys.readouterr()
    assert cloth_bake_worker.main([*base, "--threads-per-cm", "30"]) == 2
    events = [json.loads(line) for line in capsys.readouterr().out.splitlines() if line.startswith("{")]
    assert events[-1]["bad_input"] and "threads_per_cm" in events[-1]["message"]
    assert len(given) == 2  # refused before any work


@pytest.fixture
def settings_registered():
    bpy.ops.wm.read_homefile(use_empty=True)
    for cls in properties.CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.clothlight = bpy.props.PointerProperty(type=properties.ClothLightSceneSettings)
    yield bpy.context.scene
    del bpy.types.Scene.clothlight
    for cls in reversed(properties.CLASSES):
        bpy.utils.unregister_class(cls)


def test_the_panels_thread_count_goes_to_bake_cloth_and_keeps_the_shipped_tables_to_its_default(
        settings_registered, tmp_path, monkeypatch):
    scene = settings_registered
    settings = scene.clothlight
    assert settings.garment_threads_per_cm == DEFAULT_THREADS_PER_CM
    assert (settings.bl_rna.properties["garment_threads_per_cm"].hard_min,
            settings.bl_rna.properties["garment_threads_per_cm"].hard_max) == (THREADS_PER_CM.low, THREADS_PER_CM.high)
    settings.cloth_tables_dir = str(tmp_path)
    settings.garment_threads_per_cm = 16
    assert settings.garment_threads_per_cm == 16
    assert settings.cloth_tables_dir == ""  # the folder held the other density's cloth

    monkeypatch.setattr(operators, "tables_for", lambda medium: (tmp_path, None))
    monkeypatch.setattr(operators.preferences, "cache_directory", lambda context=None: tmp_path)
    fake = SimpleNamespace(report=lambda kind, text: None)
    job = operators.CLOTHLIGHT_OT_bake_cloth._start(fake, SimpleNamespace(scene=scene))
    assert job.arguments()[-2:] == ["--threads-per-cm", "16"]

    shipped = []
    monkeypatch.setattr("clothlight.prebaked.prebaked_cloth_tables", lambda request: shipped.append(request))
    assert garment_operator.shipped_cloth_tables(scene) is None and not shipped  # another density: baked
    settings.garment_threads_per_cm = DEFAULT_THREADS_PER_CM
    assert garment_operator.shipped_cloth_tables(scene) is None and len(shipped) == 1  # the default: looked up
