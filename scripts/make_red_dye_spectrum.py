"""Write precompute/data/red_dye_band_model.csv: the default red dye's mass absorption spectrum.

This is a documented BAND MODEL, not a measured spectrum (provenance and
assumptions: precompute/data/red_dye_band_model.md).  Two Gaussian bands in
wavelength:

* the main visible band of a red reactive dye, peak 530 nm, σ = 42 nm
  (red reactive dyes such as C.I. Reactive Red 120 and 195 have λmax in
  about 520–545 nm);
* a weaker violet/near-UV band at 395 nm, σ = 30 nm, 0.2× the main peak,
  which gives the blue reflectance of a "purplish" red.

Peak napierian mass absorption 5.5e4 cm²/g: a decadic molar absorptivity of
about 3.5e4 L/(mol·cm) at a molar mass of about 1.47 kg/mol, times ln 10.
"""

import math
import pathlib

PEAK_NM, PEAK_SIGMA_NM = 530.0, 42.0
VIOLET_NM, VIOLET_SIGMA_NM, VIOLET_RATIO = 395.0, 30.0, 0.2
PEAK_CM2_PER_G = 5.5e4

OUT = pathlib.Path(__file__).resolve().parents[1] / "precompute" / "data" / "red_dye_band_model.csv"


def mass_absorption(wavelength_nm: float) -> float:
    main = math.exp(-0.5 * ((wavelength_nm - PEAK_NM) / PEAK_SIGMA_NM) ** 2)
    violet = VIOLET_RATIO * math.exp(-0.5 * ((wavelength_nm - VIOLET_NM) / VIOLET_SIGMA_NM) ** 2)
    return PEAK_CM2_PER_G * (main + violet)


def main() -> None:
    lines = [
        "# Red dye napierian mass absorption coefficient: a documented band model, NOT a measurement.",
        "# Made by scripts/make_red_dye_spectrum.py; provenance: red_dye_band_model.md",
        "wavelength_nm,mass_absorption_cm2_per_g",
    ]
    lines += [f"{wl},{mass_absorption(wl):.6g}" for wl in range(350, 805, 5)]
    OUT.write_text("\n".join(lines) + "\n")
    print(OUT)


if __name__ == "__main__":
    main()
