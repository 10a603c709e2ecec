"""The transport core against the exact adding-doubling solution (iadpython), and its spectral scheme."""

import json
import subprocess
import sys

import iadpython
import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.transport import TransportMedium, henyey_greenstein_medium, simulate_hg_slab, simulate_slab

CASES = [
    # albedo, g, tau, n
    (0.9, 0.75, 2.0, 1.0),  # van de Hulst
    (0.95, 0.5, 1.0, 1.4),
    (0.5, 0.0, 0.5, 1.5),
    (0.99, 0.9, 4.0, 1.33),
]


def adding_doubling(albedo, g, tau, n):
    sample = iadpython.Sample(a=albedo, b=tau, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=24)
    r_total, t_total, *_ = sample.rt()
    return r_total, t_total


@pytest.mark.parametrize("albedo, g, tau, n", CASES)
def test_slab_matches_adding_doubling(albedo, g, tau, n):
    result = simulate_hg_slab(albedo, g, tau, n, paths=200_000, seed=7)
    r_exact, t_exact = adding_doubling(albedo, g, tau, n)
    assert abs(result.R_total[0] - r_exact) < 3 * result.R_total_stderr[0] + 1e-3
    assert abs(result.T_total[0] - t_exact) < 3 * result.T_total_stderr[0] + 1e-3


def test_van_de_hulst_reference_values():
    # van de Hulst's tables: n = 1, albedo 0.9, g = 0.75, tau = 2 -> Rd 0.09739, Tt 0.66096.
    result = simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=200_000, seed=11)
    assert result.R_specular == 0.0 and result.R_unscattered[0] == 0.0
    assert abs(result.R_total[0] - 0.09739) < 3 * result.R_total_stderr[0] + 1e-3
    assert abs(result.T_total[0] - 0.66096) < 3 * result.T_total_stderr[0] + 1e-3
    # The unscattered transmission of a matched slab is exp(-tau).
    assert result.T_unscattered[0] == pytest.approx(np.exp(-2.0), abs=4e-3)


def test_energy_is_conserved_in_the_slab():
    result = simulate_hg_slab(0.8, 0.6, 1.5, 1.5, paths=100_000, seed=3)
    total = result.R_total[0] + result.T_total[0] + result.absorbed[0] + result.lost[0]
    assert total == pytest.approx(1.0, abs=5e-3)
    no_absorption = simulate_hg_slab(1.0, 0.6, 1.5, 1.5, paths=20_000, seed=3)
    assert no_absorption.absorbed[0] == 0.0


def test_spectral_paths_match_single_wavelength_runs():
    """Hero-wavelength MIS over 3 wavelengths whose μs differ 8-fold is unbiased per wavelength."""
    mu_s = np.array([0.5, 1.5, 4.0])
    mu_a = np.array([0.05, 0.3, 0.1])
    g = np.array([0.2, 0.6, 0.8])
    hg = henyey_greenstein_medium(mu_s / (mu_s + mu_a), g)
    spectral = TransportMedium(np.arange(3.0), mu_s, mu_a, hg.phase, hg.phase_icdf)
    thickness, n = 1.0, 1.4
    together = simulate_slab(spectral, thickness, n, paths=300_000, seed=5)
    for k in range(3):
        alone_medium = TransportMedium(np.arange(1.0), mu_s[k : k + 1], mu_a[k : k + 1], hg.phase[k : k + 1], hg.phase_icdf[k : k + 1])
        alone = simulate_slab(alone_medium, thickness, n, paths=300_000, seed=6)
        for name in ("R_total", "T_total"):
            err = np.hypot(getattr(together, f"{name}_stderr")[k], getattr(alone, f"{name}_stderr")[0])
            assert abs(getattr(together, name)[k] - getattr(alone, name)[0]) < 4 * err + 1e-3, (k, name)
        assert together.absorbed[k] == pytest.approx(alone.absorbed[0], abs=5e-3)


def test_bad_slab_input_names_the_parameter():
    with pytest.raises(ParameterError, match="albedo"):
        simulate_hg_slab(1.2, 0.5, 1.0, 1.0, paths=10)
    with pytest.raises(ParameterError, match="thickness"):
        simulate_hg_slab(0.5, 0.5, -1.0, 1.0, paths=10)
    with pytest.raises(ParameterError, match="n"):
        simulate_hg_slab(0.5, 0.5, 1.0, 0.5, paths=10)


def test_slab_command_prints_json_with_errors():
    output = subprocess.run(
        [sys.executable, "-m", "precompute", "slab", "--albedo", "0.9", "--g", "0.75", "--tau", "2",
         "--n", "1", "--paths", "100000", "--json"],
        capture_output=True, text=True, check=True,
    ).stdout
    summary = json.loads(output)
    for key in ("R_total", "T_total", "R_total_stderr", "T_total_stderr", "R_specular", "R_unscattered",
                "R_diffuse", "T_unscattered", "T_diffuse"):
        assert key in summary
    assert summary["R_total"] == pytest.approx(summary["R_specular"] + summary["R_unscattered"] + summary["R_diffuse"])
    assert abs(summary["T_total"] - 0.66096) < 3 * summary["T_total_stderr"] + 1e-3


def test_bad_command_line_input_exits_2_naming_the_parameter():
    result = subprocess.run(
        [sys.executable, "-m", "precompute", "slab", "--albedo", "0.9", "--g", "1.5", "--tau", "2", "--paths", "100"],
        capture_output=True, text=True,
    )
    assert result.returncode == 2 and "g" in result.stderr
