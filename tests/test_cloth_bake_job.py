"""The Garment panel's Bake Cloth job (clothlight/jobs.py ClothBakeJob, clothlight/cloth_bake_worker.py):
the cloth tables of a yarn bake in a child process, with progress, cached, and a cancel that writes
nothing."""

from __future__ import annotations

import pathlib

import pytest

pytest.importorskip("bpy")

from clothlight.garment.tables import check_cloth_table_folder
from clothlight.jobs import ClothBakeCancelled, ClothBakeFailed, ClothBakeJob

pytestmark = [pytest.mark.blender, pytest.mark.render, pytest.mark.slow]

YARN_BAKE = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
#: The draft goniometer of tests/test_distributed_garment.py: 2 · 2² views.
TINY = {"incidence_resolution": 3, "exit_resolution": 2, "pixels_per_patch": 8, "samples": 2}


def test_bake_cloth_measures_once_with_progress_then_finds_the_cache(tmp_path):
    fractions = []
    job = ClothBakeJob(YARN_BAKE, cache_dir=tmp_path / "cache", settings=TINY)
    outcome = job.wait(on_progress=fractions.append)
    assert outcome.rendered and outcome.folder.is_relative_to(tmp_path / "cache")
    check_cloth_table_folder(outcome.folder)
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0) and len(fractions) >= 3
    assert job.stage == f"views {2 * 2**2}/{2 * 2**2}"
    again = ClothBakeJob(YARN_BAKE, cache_dir=tmp_path / "cache", settings=TINY).wait()
    assert again.folder == outcome.folder and not again.rendered


def test_a_cancelled_cloth_bake_writes_no_tables(tmp_path):
    # 2 · 8² views: a traced response takes seconds, so the cancel reaches the worker while it traces.
    job = ClothBakeJob(YARN_BAKE, cache_dir=tmp_path / "cache", settings={**TINY, "exit_resolution": 8})

    def cancel_once_rendering(fraction: float) -> None:
        if fraction > 0:
            job.cancel()

    with pytest.raises(ClothBakeCancelled, match="no cloth table was written"):
        job.wait(on_progress=cancel_once_rendering)
    assert not list((tmp_path / "cache").rglob("*.exr"))


def test_a_folder_that_is_no_yarn_bake_is_bad_input_naming_it(tmp_path):
    with pytest.raises(ClothBakeFailed) as error:
        ClothBakeJob(tmp_path / "nowhere", cache_dir=tmp_path / "cache", settings=TINY).wait()
    assert error.value.bad_input and "nowhere" in str(error.value)
