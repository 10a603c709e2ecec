"""How exactly the default tables hold the yarn: the unscattered light and the incidence grid.

Bakes the paper's red cotton with the default settings (cached in the user cache), then prints

* per wavelength (450, 550, 620, 650, 700 nm): the share of the incident flux that the transport saw
  leave the yarn without a collision, against the closed form of precompute/optics/ballistic.py averaged
  over each incidence cell as the transport's source samples it (mean ratio, worst cell), and what
  the unscattered light is worth beside the scattered light;
* the incidence-grid checks the bake made (``incidence_grid_checks`` of its summary): the lookup's
  bias against eq. (5) evaluated exactly, and ∫ρ dω_i under uniform light against the transport's
  own tallies, worst over the wavelengths, for every grid tried.

    python benchmarks/bench_table_accuracy.py
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from precompute.optics import ballistic
from precompute.bake import SPECTRAL_FILE, bake, load_spectral
from precompute.tables.grids import AngularGrid

result = bake("paper_2008")
arrays, spectral = load_spectral(result.folder / SPECTRAL_FILE)
wavelengths = arrays["wavelengths_nm"]
resolution = spectral["transport"]["angular_resolution"]
directions = AngularGrid("hemisphere", resolution).cell_samples(24)
mu_t = arrays["mu_s"] + arrays["mu_a"]
factor = ballistic.unscattered_radiance_factor(
    directions, spectral["host_index"], lambda length: ballistic.attenuation(mu_t, spectral["radius_mm"], length))
cos = directions[..., 2][..., None]
closed_form = (factor * cos).sum(axis=1) / cos.sum(axis=1)
measured = arrays["unscattered_fraction"]
print(f"red cotton, {result.folder}")
print("unscattered share of the incident flux per incidence cell: closed form / transport tally")
for target in (450, 550, 620, 650, 700):
    k = int(np.argmin(np.abs(wavelengths - target)))
    ratio = closed_form[:, k] / measured[:, k]
    print(f"  {wavelengths[k]:.0f} nm: mean {ratio.mean():.4f}, worst cell {np.abs(ratio - 1).max():.2%}; "
          f"unscattered {measured[:, k].mean():.3f} vs scattered exits {arrays['exit_fraction'][:, k].mean():.3f}")
print("incidence grid (lookup bias vs eq. (5) exact; uniform-light energy vs the tallies), worst wavelength:")
for check in result.summary["incidence_grid_checks"]:
    print(f"  N_i = {check['incidence_resolution']}: lookup {check['lookup_bias_worst']:.2%}, "
          f"energy {check['energy_error_worst']:.2%}")
print(f"chosen N_i = {result.summary['incidence_resolution']}; bake seconds {result.summary['seconds']}")
