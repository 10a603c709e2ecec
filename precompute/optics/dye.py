"""Absorption by the dye in the fiber (paper §6.2: 1–5 % dye by weight)."""

from __future__ import annotations

import numpy as np

from precompute.errors import ParameterError
from precompute.optics.medium import Dye


def dye_absorption_coefficient(dye: Dye, wavelengths_nm: np.ndarray) -> np.ndarray:
    """Absorption coefficient of the dyed fiber, 1/mm.

    ``μ_a = ε(λ) · (w / 100) · ρ_f / 10``: ``ε`` the napierian mass absorption
    coefficient (cm²/g), ``w`` the dye weight percent, ``ρ_f`` the fiber density
    (g/cm³); the factor 1/10 turns 1/cm into 1/mm.  The spectrum is interpolated
    linearly and never extrapolated.
    """
    wavelengths_nm = np.asarray(wavelengths_nm, float)
    table = np.asarray(dye.wavelengths_nm, float)
    if wavelengths_nm.min() < table[0] or wavelengths_nm.max() > table[-1]:
        raise ParameterError(
            "dye.spectrum_csv wavelengths",
            f"tabulated over {table[0]:g}–{table[-1]:g} nm",
            f"a table covering the simulation's {wavelengths_nm.min():g}–{wavelengths_nm.max():g} nm",
        )
    epsilon = np.interp(wavelengths_nm, table, np.asarray(dye.mass_absorption_cm2_per_g, float))
    concentration_g_per_cm3 = dye.weight_percent / 100.0 * dye.fiber_density_g_per_cm3
    return epsilon * concentration_g_per_cm3 / 10.0
