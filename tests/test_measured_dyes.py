"""Measured dye spectra (precompute/data/congo_red.csv, evans_blue.csv, curcumin.csv): load, cover, peak,
scale, colour.

The documented values below are the source's (PhotochemCAD J17 / J19 / D08, Taniguchi & Lindsey,
Photochem. Photobiol. 94, 290–327 (2018)); see precompute/data/congo_red.md, evans_blue.md and curcumin.md.
"""

import math

import numpy as np
import pytest

from precompute.optics.dye import dye_absorption_coefficient
from precompute.optics.medium import DATA_DIR, Dye, read_spectrum_csv

SIMULATION_NM = (390.0, 730.0)
RED_COTTON_WEIGHT_PERCENT, COTTON_DENSITY = 3.0, 1.52

# name: (peak λ nm, decadic molar ε at the peak L/(mol·cm), molar mass g/mol)
DOCUMENTED = {
    "congo_red": (483.0, 48000.0, 696.66),  # C.I. Direct Red 28, C32H22N6Na2O6S2, in PBS
    "evans_blue": (606.0, 86000.0, 960.79),  # C.I. Direct Blue 53, C34H24N6Na4O14S4, in PBS
    "curcumin": (425.0, 55000.0, 368.38),  # C.I. Natural Yellow 3, C21H20O6, in ethanol
}


def _load(name):
    wavelengths, values = read_spectrum_csv(DATA_DIR / f"{name}.csv", f"{name}.csv")
    return np.asarray(wavelengths), np.asarray(values)


def _mu_a(name, wavelengths_nm):
    wavelengths, values = _load(name)
    dye = Dye(RED_COTTON_WEIGHT_PERCENT, COTTON_DENSITY, tuple(wavelengths), tuple(values), source=name)
    return dye_absorption_coefficient(dye, np.asarray(wavelengths_nm, float))


@pytest.mark.parametrize("name", sorted(DOCUMENTED))
def test_loads_covers_simulation_grid_and_is_non_negative(name):
    wavelengths, values = _load(name)
    assert wavelengths[0] <= 380.0 and wavelengths[-1] >= 740.0
    assert wavelengths[0] <= SIMULATION_NM[0] and wavelengths[-1] >= SIMULATION_NM[1]
    assert np.all(np.diff(wavelengths) <= 10.0)
    assert np.all(np.isfinite(values)) and np.all(values >= 0.0)
    grid = np.arange(SIMULATION_NM[0], SIMULATION_NM[1] + 1.0, 10.0)
    assert np.all(np.isfinite(_mu_a(name, grid)))  # the dye model accepts the table on the simulation grid


@pytest.mark.parametrize("name", sorted(DOCUMENTED))
def test_peak_where_and_as_large_as_the_source_says(name):
    peak_nm, molar_epsilon, molar_mass = DOCUMENTED[name]
    wavelengths, values = _load(name)
    assert abs(wavelengths[np.argmax(values)] - peak_nm) <= 5.0
    expected = math.log(10.0) * molar_epsilon * 1000.0 / molar_mass  # napierian cm²/g
    assert values.max() == pytest.approx(expected, rel=2e-3)


@pytest.mark.parametrize("name", sorted(DOCUMENTED))
def test_header_states_the_documented_molar_mass_and_peak(name):
    peak_nm, molar_epsilon, molar_mass = DOCUMENTED[name]
    header = (DATA_DIR / f"{name}.csv").read_text(encoding="utf-8")
    assert f"M = {molar_mass:.2f} g/mol" in header
    assert f"Peak: {peak_nm:g} nm, {molar_epsilon:g} L/(mol cm)" in header
    assert (DATA_DIR / f"{name}.md").is_file()


def test_red_absorbs_blue_far_more_than_deep_red():
    mu_450, mu_550, mu_650 = _mu_a("congo_red", [450.0, 550.0, 650.0])
    # measured: μa(450)/μa(650) ≈ 265, μa(550)/μa(650) ≈ 133 (the 530 nm band model gives ≈ 12 and ≈ 53)
    assert mu_450 / mu_650 >= 100.0
    assert mu_550 / mu_650 >= 50.0
    assert mu_450 == pytest.approx(580.0, rel=0.01)  # 1/mm at 3 % in 1.52 g/cm³: the blue is gone within microns


def test_congo_red_extension_beyond_700_nm_is_flat_and_small():
    wavelengths, values = _load("congo_red")
    tail = values[wavelengths > 700.0]
    assert tail.size and np.all(tail == tail[0])
    assert tail[0] <= 0.005 * values.max()
    measured = values[(wavelengths >= 690.0) & (wavelengths <= 700.0)]
    assert tail[0] == pytest.approx(measured.mean(), rel=1e-4)


def test_blue_absorbs_orange_red_far_more_than_blue():
    mu_450, mu_606 = _mu_a("evans_blue", [450.0, 606.0])
    assert mu_606 / mu_450 >= 5.0  # measured ≈ 11


def test_yellow_absorbs_blue_and_lets_green_and_red_through():
    mu_425, mu_550, mu_650 = _mu_a("curcumin", [425.0, 550.0, 650.0])
    assert mu_425 >= 300.0 * mu_550  # measured ≈ 580: a yellow, not an orange
    assert mu_650 <= 0.005 * mu_425


def test_curcumin_extension_beyond_600_nm_is_the_mean_of_its_last_measured_samples():
    wavelengths, values = _load("curcumin")
    tail = values[wavelengths > 600.0]
    assert tail.size and np.all(tail == tail[0])
    measured = values[(wavelengths >= 590.0) & (wavelengths <= 600.0)]
    assert tail[0] == pytest.approx(measured.mean(), rel=1e-4)
    assert tail[0] <= 0.002 * values.max()
