"""Write precompute/data/{congo_red,evans_blue,curcumin}.csv from PhotochemCAD spectra.

Measured absorption spectra of three dyes that dye cotton directly (no mordant), converted to the
napierian mass absorption coefficient the dye model uses (precompute/optics/dye.py), the red, blue
and yellow of a dye mixture (a shade recipe, precompute/optics/medium.py):

* C.I. Direct Red 28 (Congo red), PhotochemCAD compound J17;
* C.I. Direct Blue 53 (Evans blue), PhotochemCAD compound J19;
* C.I. Natural Yellow 3 (curcumin, turmeric's dye), PhotochemCAD compound D08.

Source: M. Taniguchi and J. S. Lindsey, "Database of absorption and
fluorescence spectra of >300 common compounds for use in PhotochemCAD",
Photochem. Photobiol. 94, 290–327 (2018), doi:10.1111/php.12860.  The spectra
were measured in PBS (curcumin: ethanol; Agilent 8453, January 2017) and are tabulated as the
decadic molar absorption coefficient ε (L mol⁻¹ cm⁻¹) at 1 nm steps, the
spectrum's maximum scaled by the database to a literature ε (see
precompute/data/congo_red.md, evans_blue.md and curcumin.md).

The raw tables are not redistributed here (the database states no licence).
Pass the PhotochemCAD absorption files, two columns ``wavelength (nm)``,
``ε (L/mol/cm)`` after one header line — in the PhotochemCAD distribution and
its web mirrors named ``J17.absorption.txt`` / ``J-17, 573-58-0, Congo Red,
PBS.abs.txt`` and ``J19.absorption.txt`` / ``J-19, 314-13-6, Evans Blue,
PBS.abs.txt``, and ``D08.absorption.txt`` / ``D-8, 458-37-7, Curcumin, ETOH.abs.txt``::

    python scripts/make_dye_spectra.py --congo-red J17.absorption.txt --evans-blue J19.absorption.txt \
        --curcumin D08.absorption.txt

Conversion: ε_mass (cm²/g) = ln(10) · ε_molar (L mol⁻¹ cm⁻¹) · 1000 (cm³/L) / M (g/mol).
Output grid: 380–740 nm in 1 nm steps, the source's own 1 nm samples (no
interpolation, no smoothing).  Congo red is tabulated only to 700 nm; 701–740 nm
hold the mean of its last eleven samples (690–700 nm), see congo_red.md; curcumin only to
600 nm, 601–740 nm the mean of 590–600 nm (0.15 % of its peak), see curcumin.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import pathlib

DATA = pathlib.Path(__file__).resolve().parents[1] / "precompute" / "data"
GRID_NM = tuple(range(380, 741))  # 380–740 nm, 1 nm

# IUPAC standard atomic weights (abridged, g/mol)
ATOMIC_WEIGHT = {"C": 12.011, "H": 1.008, "N": 14.007, "Na": 22.98977, "O": 15.999, "S": 32.06}

CITATION = (
    "M. Taniguchi, J. S. Lindsey, Database of absorption and fluorescence spectra of >300 common "
    "compounds for use in PhotochemCAD, Photochem. Photobiol. 94, 290-327 (2018), doi:10.1111/php.12860"
)


@dataclasses.dataclass(frozen=True)
class DyeSource:
    key: str
    name: str
    photochemcad_id: str
    formula: dict[str, int]
    formula_text: str
    peak_nm: float  # λ of the tabulated maximum (PhotochemCAD "wavelength_abs")
    peak_molar: float  # decadic molar ε at that maximum, L/(mol·cm) (PhotochemCAD "epsilon_abs")
    epsilon_basis: str
    solvent: str = "PBS"
    tail_mean_nm: tuple[int, int] = (690, 700)  # samples averaged to extend a table that stops short of 740 nm

    @property
    def molar_mass(self) -> float:
        return sum(ATOMIC_WEIGHT[element] * count for element, count in self.formula.items())


CONGO_RED = DyeSource(
    key="congo_red",
    name="C.I. Direct Red 28 (Congo red, C.I. 22120, CAS 573-58-0), disodium salt",
    photochemcad_id="J17",
    formula={"C": 32, "H": 22, "N": 6, "Na": 2, "O": 6, "S": 2},
    formula_text="C32H22N6Na2O6S2",
    peak_nm=483.0,
    peak_molar=48000.0,
    epsilon_basis=(
        "48000 L/(mol cm) at 500 nm in water (Tanizaki 1957), applied by PhotochemCAD to the PBS maximum at 483 nm"
    ),
)

EVANS_BLUE = DyeSource(
    key="evans_blue",
    name="C.I. Direct Blue 53 (Evans blue, C.I. 23860, CAS 314-13-6), tetrasodium salt",
    photochemcad_id="J19",
    formula={"C": 34, "H": 24, "N": 6, "Na": 4, "O": 14, "S": 4},
    formula_text="C34H24N6Na4O14S4",
    peak_nm=606.0,
    peak_molar=86000.0,
    epsilon_basis=(
        "86000 L/(mol cm) at 606 nm in water (Luo 2005), applied by PhotochemCAD to the PBS maximum at 606 nm"
    ),
)


CURCUMIN = DyeSource(
    key="curcumin",
    name="C.I. Natural Yellow 3 (curcumin, C.I. 75300, CAS 458-37-7)",
    photochemcad_id="D08",
    formula={"C": 21, "H": 20, "O": 6},
    formula_text="C21H20O6",
    peak_nm=425.0,
    peak_molar=55000.0,
    epsilon_basis=(
        "55000 L/(mol cm) at 422 nm in ethanol (Jasim 1989), applied by PhotochemCAD to the ethanol maximum at 425 nm"
    ),
    solvent="ethanol",
    tail_mean_nm=(590, 600),
)


def molar_to_mass(epsilon_molar: float, molar_mass: float) -> float:
    """Decadic molar absorption coefficient L/(mol·cm) → napierian mass absorption coefficient cm²/g."""
    return math.log(10.0) * epsilon_molar * 1000.0 / molar_mass


def read_photochemcad(path: pathlib.Path) -> dict[int, float]:
    """A PhotochemCAD absorption table: one header line, then ``wavelength<TAB>ε`` rows at integer nm."""
    table: dict[int, float] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines()[1:]:
        if not line.strip():
            continue
        wavelength, value = (float(field) for field in line.split()[:2])
        if wavelength != round(wavelength):
            raise ValueError(f"{path}: wavelength {wavelength} is not on the 1 nm grid")
        table[int(round(wavelength))] = value
    return table


def convert(source: DyeSource, path: pathlib.Path) -> tuple[list[tuple[int, float]], str]:
    raw = read_photochemcad(path)
    peak_nm = max(raw, key=raw.get)
    if abs(peak_nm - source.peak_nm) > 0.5 or abs(raw[peak_nm] / source.peak_molar - 1.0) > 1e-3:
        raise ValueError(
            f"{path}: maximum {raw[peak_nm]} at {peak_nm} nm, expected {source.peak_molar} at {source.peak_nm} nm"
        )
    if any(value < 0 for value in raw.values()):
        raise ValueError(f"{path}: negative ε")
    last = max(raw)
    low, high = source.tail_mean_nm
    tail = [raw[wl] for wl in range(low, high + 1)] if last < GRID_NM[-1] else []
    fill = sum(tail) / len(tail) if tail else None
    rows = []
    for wavelength in GRID_NM:
        molar = raw[wavelength] if wavelength in raw else fill
        if molar is None:
            raise ValueError(f"{path}: no value at {wavelength} nm")
        rows.append((wavelength, molar_to_mass(molar, source.molar_mass)))
    extension = (
        f"# {last + 1}-{GRID_NM[-1]} nm: not measured; held at the mean of the {low}-{high} nm "
        f"samples ({fill:.4g} L/(mol cm), {100 * fill / source.peak_molar:.2f} % of the peak)"
        if fill is not None
        else f"# {GRID_NM[0]}-{GRID_NM[-1]} nm: all measured (source table {min(raw)}-{last} nm)"
    )
    return rows, extension


def write(source: DyeSource, path: pathlib.Path) -> pathlib.Path:
    rows, extension = convert(source, path)
    mass = source.molar_mass
    peak = molar_to_mass(source.peak_molar, mass)
    lines = [
        f"# {source.name}: napierian mass absorption coefficient, measured in solution ({source.solvent}).",
        f"# Source: PhotochemCAD compound {source.photochemcad_id}; {CITATION}.",
        f"# Source scale: {source.epsilon_basis}.",
        f"# Conversion: eps_mass (cm2/g) = ln(10) * eps_molar (L/(mol cm)) * 1000 (cm3/L) / M; "
        f"M = {mass:.2f} g/mol ({source.formula_text}).",
        f"# Peak: {source.peak_nm:g} nm, {source.peak_molar:g} L/(mol cm) = {peak:.6g} cm2/g.",
        "# Grid: the source's own 1 nm samples, no interpolation or smoothing.",
        extension,
        f"# Made by scripts/make_dye_spectra.py; provenance: {source.key}.md",
        "wavelength_nm,mass_absorption_cm2_per_g",
    ]
    lines += [f"{wavelength},{value:.6g}" for wavelength, value in rows]
    out = DATA / f"{source.key}.csv"
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--congo-red", type=pathlib.Path, required=True, help="PhotochemCAD J17 absorption file")
    parser.add_argument("--evans-blue", type=pathlib.Path, required=True, help="PhotochemCAD J19 absorption file")
    parser.add_argument("--curcumin", type=pathlib.Path, required=True, help="PhotochemCAD D08 absorption file")
    args = parser.parse_args(argv)
    for source, path in ((CONGO_RED, args.congo_red), (EVANS_BLUE, args.evans_blue), (CURCUMIN, args.curcumin)):
        print(write(source, path))


if __name__ == "__main__":
    main()
