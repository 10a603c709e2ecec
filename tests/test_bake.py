"""Bake: colour convention, self-describing tables, atomic content-addressed cache, command line."""

import json
import subprocess
import sys

import numpy as np
import OpenEXR
import pytest

from precompute import bake as bake_module
from precompute import cache
from precompute.bake import bake
from precompute.color import channel_ratios, spectral_to_rgb, spectral_weights
from precompute.tables import SCHEMA, TableError, read_table, write_table

WAVELENGTHS = np.arange(390.0, 731.0, 10.0)
SMALL = ["transport.angular_resolution=4", "transport.incidence_resolution=4", "transport.n_around=8", "transport.n_along=4"]


def test_flat_spectrum_is_white():
    for level in (1.0, 0.37):
        np.testing.assert_allclose(spectral_to_rgb(np.full(35, level), WAVELENGTHS), level, rtol=1e-12)


def test_white_balance_is_a_small_correction():
    # the per-channel factors only absorb the tabulated-D65 vs nominal-white difference
    import colour

    from precompute.color import ILLUMINANT, OBSERVER, RGB_SPACE

    cmfs = colour.MSDS_CMFS[OBSERVER]
    ill = colour.SDS_ILLUMINANTS[ILLUMINANT]
    xyz_bar = np.stack([np.interp(WAVELENGTHS, cmfs.wavelengths, cmfs.values[:, k]) for k in range(3)], 1)
    power = np.interp(WAVELENGTHS, ill.wavelengths, ill.values)
    white = (xyz_bar * power[:, None]).sum(0) / (power * xyz_bar[:, 1]).sum()
    rgb_white = np.asarray(colour.RGB_COLOURSPACES[RGB_SPACE].matrix_XYZ_to_RGB) @ white
    np.testing.assert_allclose(rgb_white, 1.0, atol=0.01)
    assert spectral_weights(WAVELENGTHS).shape == (35, 3)


def test_long_wavelengths_are_red_and_ratios_follow():
    red_spectrum = (WAVELENGTHS > 600).astype(float)
    rgb = spectral_to_rgb(red_spectrum, WAVELENGTHS)
    assert rgb[0] > 5 * max(rgb[1], rgb[2], 0)
    assert channel_ratios([2.0, 0.5, 0.25]) == {"B/R": 0.125, "G/R": 0.25}


def test_table_round_trip_and_header(tmp_path):
    pixels = np.random.default_rng(1).random((8, 8, 3)).astype(np.float32)
    write_table(tmp_path / "t.exr", pixels, {"seed": 3, "medium": {"radius_mm": 0.1}})
    back, metadata = read_table(tmp_path / "t.exr")
    np.testing.assert_array_equal(back, pixels)
    assert metadata == {"seed": 3, "medium": {"radius_mm": 0.1}}


def test_reader_refuses_foreign_truncated_tampered_and_wrong_schema_files(tmp_path):
    pixels = np.ones((4, 4, 3), np.float32)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, {"RGB": pixels}) as exr:
        exr.write(str(tmp_path / "foreign.exr"))
    with pytest.raises(TableError, match="not a ClothLight table"):
        read_table(tmp_path / "foreign.exr")
    write_table(tmp_path / "good.exr", pixels, {})
    data = (tmp_path / "good.exr").read_bytes()
    (tmp_path / "truncated.exr").write_bytes(data[: len(data) // 2])
    with pytest.raises(TableError, match="not a readable OpenEXR"):
        read_table(tmp_path / "truncated.exr")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "clothlight_schema": "clothlight-table/0"}
    with OpenEXR.File(header, {"RGB": pixels}) as exr:
        exr.write(str(tmp_path / "old.exr"))
    with pytest.raises(TableError, match="schema"):
        read_table(tmp_path / "old.exr")
    from precompute.tables import HASH_KEY, METADATA_KEY, SCHEMA_KEY

    header = {"compression": OpenEXR.ZIP_COMPRESSION, SCHEMA_KEY: SCHEMA, METADATA_KEY: "{}", HASH_KEY: "0" * 64}
    with OpenEXR.File(header, {"RGB": pixels}) as exr:
        exr.write(str(tmp_path / "tampered.exr"))
    with pytest.raises(TableError, match="hash"):
        read_table(tmp_path / "tampered.exr")


@pytest.fixture(scope="module")
def small_bake(tmp_path_factory):
    return bake("red_cotton", SMALL, paths_per_cell=400, cache_dir=tmp_path_factory.mktemp("cache"))


def test_bake_writes_self_describing_tables(small_bake):
    atlas, metadata = read_table(small_bake.brdf_table)
    assert atlas.shape == (16, 16, 3) and atlas.min() >= 0.0
    assert metadata["schema"] == SCHEMA and metadata["transport"]["seed"] == 0
    assert metadata["medium"]["particles"][0]["diameter_nm"] == 150.0
    assert metadata["units"]["rho"].startswith("1/sr")
    lobes, lobe_meta = read_table(small_bake.lobe_table)
    assert lobes.shape == (4, 14 * 4, 3) and len(lobe_meta["lobe_directions"]) == 14
    summary = small_bake.summary
    assert set(summary["table1_ratios_normal"]) == {"B/R", "G/R"}
    spectral = np.load(small_bake.folder / "spectral.npz")
    assert spectral["rho"].shape == (16, 16, 35)


def test_second_bake_is_a_cache_hit_without_transport(small_bake, monkeypatch):
    def no_transport(*args, **kwargs):
        raise AssertionError("a cache hit must not simulate")

    monkeypatch.setattr(bake_module, "simulate_yarn", no_transport)
    again = bake("red_cotton", SMALL, paths_per_cell=400, cache_dir=small_bake.folder.parent)
    assert again.cache_hit and again.folder == small_bake.folder
    with pytest.raises(AssertionError, match="must not simulate"):
        bake("red_cotton", SMALL, paths_per_cell=400, seed=1, cache_dir=small_bake.folder.parent)


def test_interrupted_bake_leaves_nothing_behind(tmp_path, monkeypatch):
    def interrupted(folder, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(bake_module, "write_table", interrupted)
    with pytest.raises(KeyboardInterrupt):
        bake("red_cotton", SMALL, paths_per_cell=40, cache_dir=tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_concurrent_bakes_of_one_key_end_with_one_valid_table(tmp_path):
    command = [sys.executable, "-m", "precompute", "bake", *sum((["--set", s] for s in SMALL), []),
               "--paths", "200", "--cache-dir", str(tmp_path), "--json"]
    runs = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True) for _ in range(2)]
    outputs = [json.loads(run.communicate()[0]) for run in runs]
    assert all(run.returncode == 0 for run in runs)
    entries = [p for p in tmp_path.iterdir()]
    assert len(entries) == 1 and outputs[0]["folder"] == outputs[1]["folder"] == str(entries[0])
    read_table(entries[0] / "brdf.exr")
    assert (entries[0] / cache.COMPLETE_MARKER).is_file()


def test_command_line_exit_codes(tmp_path):
    base = [sys.executable, "-m", "precompute", "bake", "--cache-dir", str(tmp_path)]
    bad = subprocess.run(base + ["--set", "dye.weight_percent=-3", "--paths", "10"], capture_output=True, text=True)
    assert bad.returncode == 2 and "dye.weight_percent" in bad.stderr
    blocked = tmp_path / "a-file"
    blocked.write_text("")
    broken = subprocess.run([sys.executable, "-m", "precompute", "bake", "--cache-dir", str(blocked),
                             *sum((["--set", s] for s in SMALL), []), "--paths", "10"], capture_output=True, text=True)
    assert broken.returncode == 1 and "error" in broken.stderr
