"""A dye series: one simulation for a dye range, then the tables at any dye amount in it without
transport (``bake(dye_series=...)``, ``python -m precompute bake --dye-series``)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from precompute.bake import bake, load_spectral
from precompute.tables.color import spectral_to_rgb
from precompute.errors import ParameterError
from precompute.transport.symmetry import CellSymmetry

pytestmark = pytest.mark.slow

SMALL = ["transport.incidence_resolution=5", "transport.angular_resolution=4", "transport.n_around=8",
         "transport.n_along=4"]
PATHS = 6000
#: The incidence cells SMALL's transport traces (the others mirror them).
TRACED = CellSymmetry.of_grids(8, 4, 4).traced
RANGE = (0.5, 5.0)
FIBRES_RANGE = (0.5, 8.0)


def at_dye(percent: float) -> list[str]:
    return [*SMALL, f"dye.weight_percent={percent}"]


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("dye-series-cache")


@pytest.fixture(scope="module")
def series_bake(cache):
    return bake("voided_red_cotton", at_dye(1.0), paths_per_cell=PATHS, seed=3, cache_dir=cache, dye_series=RANGE)


def total_rgb(folder):
    arrays, _ = load_spectral(folder / "spectral.npz")
    rho = spectral_to_rgb(arrays["rho"].sum(axis=(0, 1)), arrays["wavelengths_nm"])
    stderr = spectral_to_rgb(arrays["rho_stderr"].sum(axis=(0, 1)), arrays["wavelengths_nm"])
    return rho, np.abs(stderr), arrays


def test_first_bake_of_a_range_simulates_then_any_amount_in_it_does_not(series_bake, cache):
    assert series_bake.simulated
    assert series_bake.summary["dye_series"]["dye_range_percent"] == list(RANGE)
    again = bake("voided_red_cotton", at_dye(3.2), paths_per_cell=PATHS, seed=3, cache_dir=cache, dye_series=RANGE)
    assert not again.simulated and not again.cache_hit
    assert "reweighting" in again.summary["seconds"]
    assert again.summary["dye_series"] == series_bake.summary["dye_series"]
    # more dye, a darker and redder yarn, read with a larger error from the same paths
    assert again.summary["rho_normal_rgb"][0] < series_bake.summary["rho_normal_rgb"][0]
    assert again.summary["paths"]["total"] == series_bake.summary["paths"]["total"]
    assert again.summary["paths"]["albedo_rel_stderr_max"] > series_bake.summary["paths"]["albedo_rel_stderr_max"]


@pytest.mark.parametrize("percent", [0.5, 2.5, 5.0])
def test_tables_read_from_the_series_agree_with_a_simulation_at_that_dye(cache, series_bake, percent):
    """ρ summed over the incidence and exit cells (RGB) and the albedo per incidence cell and
    wavelength, against transport run in the medium of that dye amount: within their errors."""
    read = bake("voided_red_cotton", at_dye(percent), paths_per_cell=PATHS, seed=3, cache_dir=cache, dye_series=RANGE)
    fresh = bake("voided_red_cotton", at_dye(percent), paths_per_cell=PATHS, seed=8, cache_dir=cache)
    assert_read_agrees_with_fresh(read, fresh)


@pytest.fixture(scope="module")
def fibres_series_bake(cache):
    return bake("blue_cotton", at_dye(2.0), paths_per_cell=PATHS, seed=3, cache_dir=cache, dye_series=FIBRES_RANGE)


@pytest.mark.parametrize("percent", [1.0, 8.0])
def test_a_series_of_fibres_along_the_yarn_axis_agrees_with_a_simulation_at_that_dye(cache, fibres_series_bake,
                                                                                     percent):
    """A dye in fibres along the yarn axis only absorbs inside them, along each chord their kernel traces
    (precompute.transport._fibres), so its exits reweighted by the length inside the fibres are a fresh
    transport's at that dye; from 0.5 % to 8 % the fibres' absorption grows up to elevenfold (at 610 nm)."""
    read = bake("blue_cotton", at_dye(percent), paths_per_cell=PATHS, seed=3, cache_dir=cache,
                dye_series=FIBRES_RANGE)
    fresh = bake("blue_cotton", at_dye(percent), paths_per_cell=PATHS, seed=8, cache_dir=cache)
    assert fibres_series_bake.simulated
    assert_read_agrees_with_fresh(read, fresh)


def assert_read_agrees_with_fresh(read, fresh):
    assert fresh.simulated and not read.simulated
    (rho_a, err_a, arrays_a), (rho_b, err_b, arrays_b) = total_rgb(read.folder), total_rgb(fresh.folder)
    assert np.all(np.abs(rho_a - rho_b) < 3 * (err_a + err_b)), (rho_a, rho_b, err_a + err_b)
    np.testing.assert_allclose(arrays_a["mu_a"], arrays_b["mu_a"])
    sigma = np.hypot(arrays_a["albedo_rel_stderr"] * arrays_a["exit_fraction"],
                     arrays_b["albedo_rel_stderr"] * arrays_b["exit_fraction"])
    counted = arrays_b["exit_fraction"] > 1e-3 * arrays_b["exit_fraction"].max()
    counted &= TRACED[:, None]  # an image cell's albedo is its source's: one sample, counted once
    deviation = np.abs(arrays_a["exit_fraction"] - arrays_b["exit_fraction"])[counted] / sigma[counted]
    # a cell's wavelengths share its paths, so whole cells deviate together: χ² over the few cells
    assert np.mean(deviation**2) < 2.5 and deviation.max() < 5


def test_a_dye_outside_the_range_or_an_undyed_medium_is_refused(cache):
    with pytest.raises(ParameterError, match="dye.weight_percent"):
        bake("voided_red_cotton", at_dye(6.0), paths_per_cell=PATHS, cache_dir=cache, dye_series=RANGE)
    with pytest.raises(ParameterError, match="dye_series"):
        bake("voided_red_cotton", at_dye(1.0), paths_per_cell=PATHS, cache_dir=cache, dye_series=(3.0, 1.0))
    with pytest.raises(ParameterError, match="dye_series"):
        bake("undyed_cotton", SMALL, paths_per_cell=PATHS, cache_dir=cache, dye_series=RANGE)


def test_cli_reads_from_the_series(cache, series_bake):
    run = subprocess.run([sys.executable, "-m", "precompute", "bake", *[a for s in at_dye(4.0) for a in ("--set", s)],
                          "--paths", str(PATHS), "--seed", "3", "--cache-dir", str(cache), "--dye-series", "0.5,5"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "read from the dye series 0.5–5 %" in run.stdout
    bad = subprocess.run([sys.executable, "-m", "precompute", "bake", "--dye-series", "five", "--json"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "LOW,HIGH" in bad.stderr
    summary = json.loads(subprocess.run(
        [sys.executable, "-m", "precompute", "bake", *[a for s in at_dye(4.0) for a in ("--set", s)], "--paths",
         str(PATHS), "--seed", "3", "--cache-dir", str(cache), "--dye-series", "0.5,5", "--json"],
        capture_output=True, text=True).stdout)
    assert summary["cache_hit"] and summary["dye_series"]["dye_range_percent"] == [0.5, 5.0]
