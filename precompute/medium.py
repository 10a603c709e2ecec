"""Physical description of a yarn medium (paper §3.2, §6.2), validated, with units; TOML presets.

A yarn is a host (cellulose for cotton, n = 1.557) filled with spherical
particles of other indices (crystallites, wax/pectin, air voids, delustrant
TiO2, §6.2) and dyed (1–5 % dye by weight, §6.2).  The paper's "size 150 nm" is
read as the particle *diameter* and "concentration 0.14" as the particle
*volume fraction*; the presets say so explicitly.

Presets are TOML files in ``precompute/presets``; the tables ``name``,
``description``, ``[wavelengths]``, ``[host]``, ``[[particles]]``, ``[dye]``,
``[yarn]`` and ``[medium]`` belong to this module, ``[transport]`` and
``[bake]`` to the bake.
"""

from __future__ import annotations

import csv
import math
import pathlib
import tomllib
from dataclasses import dataclass, field

import numpy as np

from .errors import ParameterError

PRESET_DIR = pathlib.Path(__file__).resolve().parent / "presets"
DATA_DIR = pathlib.Path(__file__).resolve().parent / "data"
DEFAULT_PRESET = "red_cotton"
#: Random close packing of equal spheres: no denser dispersion of particles exists.
MAX_VOLUME_FRACTION = 0.74
DEPENDENT_SCATTERING_MODELS = ("none", "percus-yevick")
_FOREIGN_TABLES = ("transport", "bake")


def _finite(name: str, value, allowed: str = "a finite number") -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, allowed) from None
    if not math.isfinite(number):
        raise ParameterError(name, value, allowed)
    return number


def _positive(name: str, value) -> float:
    number = _finite(name, value, "> 0")
    if number <= 0:
        raise ParameterError(name, value, "> 0")
    return number


def _increasing(name: str, values) -> np.ndarray:
    array = np.asarray(values, float)
    if array.ndim != 1 or array.size == 0:
        raise ParameterError(name, values, "a non-empty list")
    if not np.all(np.isfinite(array)):
        raise ParameterError(name, values, "finite values")
    if np.any(np.diff(array) <= 0):
        raise ParameterError(name, values, "strictly increasing values")
    return array


@dataclass(frozen=True)
class WavelengthGrid:
    """Vacuum wavelengths of the simulation, nm: ``start_nm`` to ``stop_nm`` in ``step_nm`` steps.

    The default, 390–730 nm in 10 nm steps (35 samples), is the paper's measurement grid (§4).
    """

    start_nm: float = 390.0
    stop_nm: float = 730.0
    step_nm: float = 10.0

    def __post_init__(self):
        start = _positive("wavelengths.start_nm", self.start_nm)
        stop = _positive("wavelengths.stop_nm", self.stop_nm)
        step = _positive("wavelengths.step_nm", self.step_nm)
        if stop < start:
            raise ParameterError("wavelengths.stop_nm", self.stop_nm, f"≥ start_nm = {start}")
        if abs(round((stop - start) / step) * step - (stop - start)) > 1e-6 * step:
            raise ParameterError("wavelengths.step_nm", self.step_nm, f"a divisor of stop_nm − start_nm = {stop - start}")

    @property
    def values(self) -> np.ndarray:
        count = int(round((self.stop_nm - self.start_nm) / self.step_nm)) + 1
        return self.start_nm + self.step_nm * np.arange(count)


@dataclass(frozen=True)
class RefractiveIndex:
    """A complex refractive index ``n + i k`` (``k ≥ 0`` absorbs), constant or tabulated vs wavelength.

    Tabulated values are interpolated linearly and never extrapolated.
    """

    n: float | tuple[float, ...]
    k: float | tuple[float, ...] = 0.0
    wavelengths_nm: tuple[float, ...] | None = None
    name: str = "refractive_index"

    def __post_init__(self):
        if self.wavelengths_nm is None:
            if _finite(f"{self.name}.n", self.n) <= 0:
                raise ParameterError(f"{self.name}.n", self.n, "> 0")
            if _finite(f"{self.name}.k", self.k) < 0:
                raise ParameterError(f"{self.name}.k", self.k, "≥ 0")
            return
        wl = _increasing(f"{self.name}.wavelengths_nm", self.wavelengths_nm)
        for part, lower in (("n", 0.0), ("k", 0.0)):
            values = np.broadcast_to(np.asarray(getattr(self, part), float), wl.shape)
            if not np.all(np.isfinite(values)):
                raise ParameterError(f"{self.name}.{part}", getattr(self, part), "finite values")
            if part == "n" and np.any(values <= lower):
                raise ParameterError(f"{self.name}.n", getattr(self, part), "> 0 at every wavelength")
            if part == "k" and np.any(values < lower):
                raise ParameterError(f"{self.name}.k", getattr(self, part), "≥ 0 at every wavelength")

    def at(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Complex index ``n + ik`` at the given vacuum wavelengths."""
        wavelengths_nm = np.asarray(wavelengths_nm, float)
        if self.wavelengths_nm is None:
            return np.full(wavelengths_nm.shape, complex(self.n, self.k))
        table = np.asarray(self.wavelengths_nm, float)
        if wavelengths_nm.min() < table[0] or wavelengths_nm.max() > table[-1]:
            raise ParameterError(
                f"{self.name}.wavelengths_nm",
                (table[0], table[-1]),
                f"a range covering the simulation's {wavelengths_nm.min()}–{wavelengths_nm.max()} nm",
            )
        n = np.interp(wavelengths_nm, table, np.broadcast_to(np.asarray(self.n, float), table.shape))
        k = np.interp(wavelengths_nm, table, np.broadcast_to(np.asarray(self.k, float), table.shape))
        return n + 1j * k


@dataclass(frozen=True)
class ParticleSpecies:
    """One kind of spherical particle dispersed in the host.

    Attributes
    ----------
    refractive_index
        Absolute index of the particle material.
    volume_fraction
        Fraction of the yarn volume the particles occupy, in (0, 0.74).
    diameter_nm
        Diameter of monodisperse particles, nm; or ``None`` with a log-normal
        number distribution given by ``median_diameter_nm`` and ``geometric_sigma`` (> 1).
    """

    name: str
    refractive_index: RefractiveIndex
    volume_fraction: float
    diameter_nm: float | None = None
    median_diameter_nm: float | None = None
    geometric_sigma: float | None = None

    def __post_init__(self):
        label = f"particles[{self.name}]"
        fraction = _finite(f"{label}.volume_fraction", self.volume_fraction, f"(0, {MAX_VOLUME_FRACTION})")
        if not 0.0 < fraction < MAX_VOLUME_FRACTION:
            raise ParameterError(f"{label}.volume_fraction", self.volume_fraction, f"(0, {MAX_VOLUME_FRACTION})")
        if self.diameter_nm is not None:
            if self.median_diameter_nm is not None or self.geometric_sigma is not None:
                raise ParameterError(f"{label}.diameter_nm", self.diameter_nm, "either diameter_nm or a log-normal size distribution, not both")
            _positive(f"{label}.diameter_nm", self.diameter_nm)
        else:
            if self.median_diameter_nm is None or self.geometric_sigma is None:
                raise ParameterError(f"{label}.diameter_nm", None, "a diameter, or median_diameter_nm with geometric_sigma")
            _positive(f"{label}.median_diameter_nm", self.median_diameter_nm)
            sigma = _finite(f"{label}.geometric_sigma", self.geometric_sigma, "> 1")
            if sigma <= 1.0:
                raise ParameterError(f"{label}.geometric_sigma", self.geometric_sigma, "> 1 (1 would be monodisperse: use diameter_nm)")


@dataclass(frozen=True)
class Dye:
    """Dye dissolved in the fiber.

    ``mass_absorption_cm2_per_g`` is the napierian mass absorption coefficient
    ``ε(λ)`` in cm²/g on ``wavelengths_nm``; with dye weight fraction ``w`` of a
    fiber of density ``ρ_f`` (g/cm³) the absorption coefficient is
    ``μ_a = ε · w · ρ_f`` (1/cm).
    """

    weight_percent: float
    fiber_density_g_per_cm3: float
    wavelengths_nm: tuple[float, ...]
    mass_absorption_cm2_per_g: tuple[float, ...]
    source: str = ""

    def __post_init__(self):
        percent = _finite("dye.weight_percent", self.weight_percent, "[0, 100)")
        if not 0.0 <= percent < 100.0:
            raise ParameterError("dye.weight_percent", self.weight_percent, "[0, 100)")
        _positive("dye.fiber_density_g_per_cm3", self.fiber_density_g_per_cm3)
        wl = _increasing("dye.wavelengths_nm", self.wavelengths_nm)
        eps = np.asarray(self.mass_absorption_cm2_per_g, float)
        if eps.shape != wl.shape or not np.all(np.isfinite(eps)):
            raise ParameterError("dye.mass_absorption_cm2_per_g", "missing or non-finite values", f"{wl.size} finite values")
        if np.any(eps < 0):
            raise ParameterError("dye.mass_absorption_cm2_per_g", float(eps.min()), "≥ 0 at every wavelength")


@dataclass(frozen=True)
class Yarn:
    """Yarn cross-section: a circle of ``radius_mm``, or an ellipse of ``semi_axes_mm`` (§7)."""

    radius_mm: float = 0.1
    cross_section: str = "circle"
    semi_axes_mm: tuple[float, float] | None = None

    def __post_init__(self):
        _positive("yarn.radius_mm", self.radius_mm)
        if self.cross_section not in ("circle", "ellipse"):
            raise ParameterError("yarn.cross_section", self.cross_section, "'circle' or 'ellipse'")
        if self.cross_section == "ellipse":
            if self.semi_axes_mm is None or len(self.semi_axes_mm) != 2:
                raise ParameterError("yarn.semi_axes_mm", self.semi_axes_mm, "two semi-axes in mm for an elliptical cross-section")
            for axis in self.semi_axes_mm:
                _positive("yarn.semi_axes_mm", axis)


@dataclass(frozen=True)
class Host:
    """The yarn's host material: refractive index and its own absorption coefficient (1/mm)."""

    refractive_index: RefractiveIndex
    absorption_per_mm: float = 0.0

    def __post_init__(self):
        if self.refractive_index.k not in (0, 0.0) and self.refractive_index.wavelengths_nm is None:
            raise ParameterError("host.refractive_index.k", self.refractive_index.k, "0: give host absorption as absorption_per_mm")
        value = _finite("host.absorption_per_mm", self.absorption_per_mm, "≥ 0")
        if value < 0:
            raise ParameterError("host.absorption_per_mm", self.absorption_per_mm, "≥ 0")


@dataclass(frozen=True)
class MediumParameters:
    """Everything that defines a yarn medium; see the module docstring."""

    name: str
    host: Host
    particles: tuple[ParticleSpecies, ...]
    dye: Dye | None = None
    yarn: Yarn = field(default_factory=Yarn)
    wavelengths: WavelengthGrid = field(default_factory=WavelengthGrid)
    dependent_scattering: str = "none"
    description: str = ""

    def __post_init__(self):
        if self.dependent_scattering not in DEPENDENT_SCATTERING_MODELS:
            raise ParameterError("medium.dependent_scattering", self.dependent_scattering, f"one of {DEPENDENT_SCATTERING_MODELS}")
        total = sum(p.volume_fraction for p in self.particles)
        if total >= MAX_VOLUME_FRACTION:
            raise ParameterError("particles[*].volume_fraction (sum)", total, f"< {MAX_VOLUME_FRACTION}")

    def to_dict(self) -> dict:
        """A plain, JSON-serialisable description (for headers, hashes and reports)."""
        import dataclasses

        def plain(value):
            if dataclasses.is_dataclass(value):
                return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
            if isinstance(value, (tuple, list)):
                return [plain(v) for v in value]
            if isinstance(value, np.ndarray):
                return value.tolist()
            return value

        return plain(self)


# ---- loading ------------------------------------------------------------------------------------


def read_spectrum_csv(path: str | pathlib.Path, parameter: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Read a two-column CSV (wavelength nm, value); ``#`` lines are comments, a text header is allowed."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise ParameterError(parameter, str(path), "an existing CSV file")
    wavelengths, values = [], []
    with path.open(newline="") as handle:
        rows = [row for row in csv.reader(line for line in handle if not line.lstrip().startswith("#")) if row]
    for number, row in enumerate(rows, start=1):
        if number == 1 and not _is_number(row[0]):
            continue  # header
        if len(row) < 2 or not row[0].strip() or not row[1].strip():
            raise ParameterError(f"{parameter} ({path.name}, data row {number})", row, "two values: wavelength_nm, value")
        if not (_is_number(row[0]) and _is_number(row[1])):
            raise ParameterError(f"{parameter} ({path.name}, data row {number})", row, "numbers")
        wavelength, value = float(row[0]), float(row[1])
        if not (math.isfinite(wavelength) and math.isfinite(value)):
            raise ParameterError(f"{parameter} ({path.name}, data row {number})", row, "finite numbers")
        if value < 0:
            raise ParameterError(f"{parameter} ({path.name}, data row {number})", value, "≥ 0")
        wavelengths.append(wavelength)
        values.append(value)
    if len(wavelengths) < 2:
        raise ParameterError(parameter, str(path), "at least two data rows")
    _increasing(f"{parameter} ({path.name}) wavelengths", wavelengths)
    return tuple(wavelengths), tuple(values)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _check_keys(table: dict, allowed: set[str], where: str) -> None:
    unknown = set(table) - allowed
    if unknown:
        raise ParameterError(f"{where}.{sorted(unknown)[0]}", table[sorted(unknown)[0]], f"one of the keys {sorted(allowed)}")


def _index(spec, name: str, base_dir: pathlib.Path) -> RefractiveIndex:
    if isinstance(spec, (int, float)):
        return RefractiveIndex(n=float(spec), name=name)
    if isinstance(spec, list) and len(spec) == 2:
        return RefractiveIndex(n=float(spec[0]), k=float(spec[1]), name=name)
    if isinstance(spec, dict):
        _check_keys(spec, {"n", "k", "wavelengths_nm", "csv"}, name)
        if "csv" in spec:
            wl, n = read_spectrum_csv(base_dir / spec["csv"], f"{name}.csv")
            return RefractiveIndex(n=n, wavelengths_nm=wl, name=name)
        return RefractiveIndex(
            n=tuple(spec["n"]) if isinstance(spec.get("n"), list) else spec.get("n", 0.0),
            k=tuple(spec["k"]) if isinstance(spec.get("k"), list) else spec.get("k", 0.0),
            wavelengths_nm=tuple(spec["wavelengths_nm"]) if "wavelengths_nm" in spec else None,
            name=name,
        )
    raise ParameterError(name, spec, "a number n, [n, k], or a table {wavelengths_nm, n, k} or {csv}")


def medium_from_dict(config: dict, base_dir: pathlib.Path = PRESET_DIR) -> MediumParameters:
    """Build :class:`MediumParameters` from a preset's TOML content; relative file paths resolve in ``base_dir``."""
    _check_keys(config, {"name", "description", "wavelengths", "host", "particles", "dye", "yarn", "medium", *_FOREIGN_TABLES}, "preset")
    wavelengths = config.get("wavelengths", {})
    _check_keys(wavelengths, {"start_nm", "stop_nm", "step_nm"}, "wavelengths")
    host = config.get("host")
    if host is None:
        raise ParameterError("host", None, "a [host] table with refractive_index")
    _check_keys(host, {"refractive_index", "absorption_per_mm"}, "host")
    particles = []
    for number, spec in enumerate(config.get("particles", [])):
        _check_keys(spec, {"name", "refractive_index", "volume_fraction", "diameter_nm", "median_diameter_nm", "geometric_sigma"}, f"particles[{number}]")
        name = spec.get("name", str(number))
        particles.append(
            ParticleSpecies(
                name=name,
                refractive_index=_index(spec.get("refractive_index"), f"particles[{name}].refractive_index", base_dir),
                volume_fraction=spec.get("volume_fraction"),
                diameter_nm=spec.get("diameter_nm"),
                median_diameter_nm=spec.get("median_diameter_nm"),
                geometric_sigma=spec.get("geometric_sigma"),
            )
        )
    dye = None
    if "dye" in config:
        spec = config["dye"]
        _check_keys(spec, {"weight_percent", "fiber_density_g_per_cm3", "spectrum_csv"}, "dye")
        csv_path = spec.get("spectrum_csv")
        if csv_path is None:
            raise ParameterError("dye.spectrum_csv", None, "a CSV of wavelength_nm, mass absorption cm²/g")
        resolved = pathlib.Path(csv_path)
        if not resolved.is_absolute():
            candidates = [base_dir / resolved, DATA_DIR / resolved]
            resolved = next((c for c in candidates if c.is_file()), candidates[0])
        wl, eps = read_spectrum_csv(resolved, "dye.spectrum_csv")
        dye = Dye(
            weight_percent=spec.get("weight_percent"),
            fiber_density_g_per_cm3=spec.get("fiber_density_g_per_cm3"),
            wavelengths_nm=wl,
            mass_absorption_cm2_per_g=eps,
            source=str(resolved.name),
        )
    yarn = config.get("yarn", {})
    _check_keys(yarn, {"radius_mm", "cross_section", "semi_axes_mm"}, "yarn")
    medium = config.get("medium", {})
    _check_keys(medium, {"dependent_scattering"}, "medium")
    return MediumParameters(
        name=config.get("name", "custom"),
        description=config.get("description", ""),
        wavelengths=WavelengthGrid(**wavelengths),
        host=Host(
            refractive_index=_index(host.get("refractive_index"), "host.refractive_index", base_dir),
            absorption_per_mm=host.get("absorption_per_mm", 0.0),
        ),
        particles=tuple(particles),
        dye=dye,
        yarn=Yarn(
            radius_mm=yarn.get("radius_mm", 0.1),
            cross_section=yarn.get("cross_section", "circle"),
            semi_axes_mm=tuple(yarn["semi_axes_mm"]) if "semi_axes_mm" in yarn else None,
        ),
        dependent_scattering=medium.get("dependent_scattering", "none"),
    )


def preset_names() -> list[str]:
    """Names of the presets shipped in ``precompute/presets``."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def preset_path(name_or_path: str | pathlib.Path) -> pathlib.Path:
    """The TOML file of a shipped preset name, or the given path."""
    candidate = pathlib.Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        if not candidate.is_file():
            raise ParameterError("preset", str(name_or_path), "an existing TOML file")
        return candidate
    shipped = PRESET_DIR / f"{name_or_path}.toml"
    if not shipped.is_file():
        raise ParameterError("preset", str(name_or_path), f"one of {preset_names()} or a path to a TOML file")
    return shipped


def load_preset_config(name_or_path: str | pathlib.Path = DEFAULT_PRESET) -> tuple[dict, pathlib.Path]:
    """The raw TOML content of a preset and the folder its relative paths resolve in."""
    path = preset_path(name_or_path)
    try:
        config = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("preset", str(path), f"valid TOML ({exc})") from None
    return config, path.parent


def load_preset(name_or_path: str | pathlib.Path = DEFAULT_PRESET) -> MediumParameters:
    """Medium parameters of a shipped preset (by name) or of a TOML file (by path)."""
    config, base_dir = load_preset_config(name_or_path)
    return medium_from_dict(config, base_dir)
