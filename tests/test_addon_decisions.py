"""What the add-on decides without Blender: which tables a material reads, why a bake cannot run."""

from __future__ import annotations

import pathlib

import pytest

from clothlight import jobs, prebaked
from clothlight.medium_settings import BakeRequest


def test_a_baked_folder_wins_and_is_flagged_when_baked_from_other_settings(tmp_path):
    panel = BakeRequest(preset="voided_red_cotton")
    other = BakeRequest(preset="voided_red_cotton", overrides=(("dye.weight_percent", 1.0),))
    folder, warning = prebaked.tables_for_request(panel, tables_dir=tmp_path, tables_request=panel.to_json(),
                                                  cache_dir=tmp_path / "cache")
    assert folder == tmp_path and warning is None
    _, warning = prebaked.tables_for_request(panel, tables_dir=tmp_path, tables_request=other.to_json(),
                                             cache_dir=tmp_path / "cache")
    assert "bake again" in warning
    _, warning = prebaked.tables_for_request(panel, tables_dir=tmp_path, tables_request="",
                                             cache_dir=tmp_path / "cache")
    assert warning is None  # a folder chosen by hand: no request to compare


def test_an_unchanged_shipped_preset_reads_its_copy_of_the_prebaked_tables(tmp_path, monkeypatch):
    shipped = tmp_path / "prebaked"
    request = BakeRequest(preset="voided_red_cotton")
    (shipped / "voided_red_cotton").mkdir(parents=True)
    (shipped / "voided_red_cotton" / prebaked.REQUEST_FILE).write_text(request.to_json())
    copies = []
    monkeypatch.setattr(prebaked, "PREBAKED_DIR", shipped)

    def user_copy(folder, cache_dir):
        copies.append((folder, cache_dir))
        return pathlib.Path(cache_dir) / "copy"

    monkeypatch.setattr(prebaked, "user_copy", user_copy)
    folder, warning = prebaked.tables_for_request(request, tables_dir=None, tables_request="", cache_dir=tmp_path)
    assert (folder, warning) == (tmp_path / "copy", None)
    assert copies == [(shipped / "voided_red_cotton", tmp_path)]
    changed = BakeRequest(preset="voided_red_cotton", overrides=(("dye.weight_percent", 1.0),))
    with pytest.raises(LookupError, match="press Bake Tables"):
        prebaked.tables_for_request(changed, tables_dir=None, tables_request="", cache_dir=tmp_path)
    reason = jobs.bake_unavailable_reason(["numba"])
    with pytest.raises(LookupError, match="Bake unavailable: numba not installed"):
        prebaked.tables_for_request(changed, tables_dir=None, tables_request="", cache_dir=tmp_path,
                                    bake_unavailable=reason)


def test_a_bake_is_unavailable_only_when_a_dependency_is_missing(monkeypatch):
    assert jobs.bake_unavailable_reason([]) is None
    reason = jobs.bake_unavailable_reason(["numba", "llvmlite"])
    assert reason.startswith("Bake unavailable: numba, llvmlite not installed") and "Pre-baked" in reason
    monkeypatch.setattr(jobs, "missing_bake_dependencies", lambda: ["scipy"])
    assert "scipy" in jobs.bake_unavailable_reason()


def test_a_bake_job_sends_the_preferences_scheduler_to_its_child(tmp_path):
    request = BakeRequest(preset="voided_red_cotton")
    on_cluster = jobs.BakeJob(request, cache_dir=tmp_path, threads=4, scheduler="tcp://farm:8786").command()
    assert on_cluster[on_cluster.index("--scheduler") + 1] == "tcp://farm:8786"
    assert "--threads" not in on_cluster  # the cluster's workers have their own threads
    here = jobs.BakeJob(request, cache_dir=tmp_path, threads=4, scheduler="").command()
    assert "--scheduler" not in here and here[here.index("--threads") + 1] == "4"


def test_an_unchanged_shipped_preset_finds_its_shipped_cloth_tables_copied_whole_and_checked(tmp_path, monkeypatch):
    """Apply Garment Material's shipped cloth tables (``prebaked_cloth/<preset>/``): only for the
    request their yarn tables were baked from, read through a checked copy in the cache."""
    import shutil

    from precompute.tables.exr import TableError

    cloth_bake = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008_cloth"
    request = BakeRequest(preset="paper_2008")
    shipped = tmp_path / "prebaked_cloth"
    shutil.copytree(cloth_bake, shipped / "paper_2008")
    (shipped / "paper_2008" / prebaked.REQUEST_FILE).write_text(request.to_json())
    monkeypatch.setattr(prebaked, "PREBAKED_CLOTH_DIR", shipped)
    assert prebaked.prebaked_cloth_tables(request) == shipped / "paper_2008"
    assert prebaked.prebaked_cloth_tables(BakeRequest(preset="paper_2008", seed=1)) is None
    assert prebaked.prebaked_cloth_tables(BakeRequest(preset="voided_red_cotton")) is None

    cache = tmp_path / "cache"
    copy = prebaked.user_copy(shipped / "paper_2008", cache, cloth=True)
    assert copy.parent == cache / prebaked.CLOTH_COPIES_FOLDER
    assert {p.name: p.read_bytes() for p in copy.iterdir()} == {
        p.name: p.read_bytes() for p in (shipped / "paper_2008").iterdir()}
    assert prebaked.user_copy(shipped / "paper_2008", cache, cloth=True) == copy
    # Shipped tables that are not a whole cloth bake are refused, naming the file; nothing is copied.
    broken = shipped / "broken"
    shutil.copytree(shipped / "paper_2008", broken)
    (broken / "lobes.exr").write_bytes((broken / "lobes.exr").read_bytes()[:100])
    with pytest.raises(TableError, match="lobes.exr"):
        prebaked.user_copy(broken, cache, cloth=True)
    assert sorted(p.name for p in (cache / prebaked.CLOTH_COPIES_FOLDER).iterdir()) == [copy.name]
