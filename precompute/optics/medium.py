"""Physical description of a yarn medium (paper §3.2, §6.2), validated, with units; TOML presets.

A yarn is a host (cellulose for cotton, n = 1.557, §3.2) filled with spherical
particles of other indices (crystallites, wax/pectin, air voids, delustrant
TiO2, §6.2) and dyed (1–5 % dye by weight, §6.2).  The paper's "size of the
scattering particles – 150 nm" is read as the particle **diameter** and its
"particles concentration – 0.14" as the particle **volume fraction**; the
presets say so next to the numbers.

Every dataclass validates itself on construction and raises
:class:`~precompute.errors.ParameterError` naming the parameter, the value and
what is allowed; nothing is clamped.

Presets are TOML files in ``precompute/presets``.  The top-level keys ``name``
and ``description`` and the tables ``[wavelengths]``, ``[host]``,
``[[particles]]``, ``[fibres]``, ``[dye]``, ``[yarn]`` and ``[medium]`` belong to this
module, which rejects unknown keys in them; ``[transport]`` and ``[bake]``
belong to the bake, ``[fit]`` (a fitted preset's specular term) to :mod:`precompute.fit`,
``[sample]`` (the weave it was fitted on) to :mod:`.measured_sample`, ``[closeup]`` to the add-on's
close-ups, and are ignored here.
Relative file paths in a preset resolve next to the TOML file, then in ``precompute/data``.

Issue 43's yarn of fibres: a ``[fibres]`` table (:class:`Fibres`) puts the dye in the fibres and the
fibres in the host, which for a spun yarn is air (``host.refractive_index = 1``: no refracting yarn
surface); their optics are :mod:`precompute.optics.fibre`'s.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import pathlib
import tomllib
from dataclasses import dataclass, field

import numpy as np

from precompute import bounds
from precompute.errors import ParameterError
from precompute.optics.fibre_orientation import FIBRE_ORIENTATIONS, RANDOM_ORIENTATION

PRESET_DIR = pathlib.Path(__file__).resolve().parents[1] / "presets"
DATA_DIR = pathlib.Path(__file__).resolve().parents[1] / "data"
DEFAULT_PRESET = "red_cotton"
#: Densest packing of equal spheres (Kepler, π/√18 ≈ 0.7405): no dispersion of spheres fills more.
MAX_VOLUME_FRACTION = 0.74
#: Densest packing of parallel equal cylinders (hexagonal, π/(2√3) ≈ 0.9069): no bundle of fibres fills more.
MAX_FIBRE_VOLUME_FRACTION = 0.90
DEPENDENT_SCATTERING_MODELS = ("none", "percus-yevick")
#: ``medium.phase_samples`` value that lets the optics choose the cos θ grid (the default).
AUTO_PHASE_SAMPLES = "auto"
_FOREIGN_TABLES = ("transport", "bake", "fit", "closeup", "sample")


def _finite(name: str, value, allowed: str = "a finite number") -> float:
    # Text and booleans are not numbers even where float() would take them.
    if isinstance(value, (bool, str, bytes)):
        raise ParameterError(name, value, allowed)
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, allowed) from None
    if not math.isfinite(number):
        raise ParameterError(name, value, allowed)
    return number


def _positive(name: str, value) -> float:
    number = _finite(name, value, "a finite number > 0")
    if number <= 0:
        raise ParameterError(name, value, "a finite number > 0")
    return number


def _finite_array(name: str, values, allowed: str = "finite numbers") -> np.ndarray:
    if isinstance(values, (str, bytes, bool)) or (
        isinstance(values, (list, tuple)) and any(isinstance(v, (str, bytes, bool)) for v in values)
    ):
        raise ParameterError(name, values, allowed)
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, values, allowed) from None
    if array.dtype == object or not np.all(np.isfinite(array)):
        raise ParameterError(name, values, allowed)
    return array


def _increasing(name: str, values) -> np.ndarray:
    array = _finite_array(name, values, "a non-empty list of finite, strictly increasing numbers")
    if array.ndim != 1 or array.size == 0 or np.any(np.diff(array) <= 0):
        raise ParameterError(name, values, "a non-empty list of finite, strictly increasing numbers")
    return array


def _interpolate(name: str, table_nm: np.ndarray, values: np.ndarray, wavelengths_nm: np.ndarray) -> np.ndarray:
    """Linear interpolation that refuses to extrapolate beyond the tabulated range."""
    if wavelengths_nm.min() < table_nm[0] or wavelengths_nm.max() > table_nm[-1]:
        raise ParameterError(
            name,
            f"tabulated over {table_nm[0]:g}–{table_nm[-1]:g} nm",
            f"a table covering the simulation's {wavelengths_nm.min():g}–{wavelengths_nm.max():g} nm",
        )
    return np.interp(wavelengths_nm, table_nm, values)


@dataclass(frozen=True)
class WavelengthGrid:
    """Vacuum wavelengths of the simulation, nm.

    Either ``start_nm`` to ``stop_nm`` in ``step_nm`` steps, or an explicit,
    strictly increasing list ``values_nm``.  The default, 390–730 nm in 10 nm
    steps (35 samples), is the paper's measurement grid (§4).
    """

    start_nm: float | None = None
    stop_nm: float | None = None
    step_nm: float | None = None
    values_nm: tuple[float, ...] | None = None

    def __post_init__(self):
        if self.values_nm is not None:
            if (self.start_nm, self.stop_nm, self.step_nm) != (None, None, None):
                raise ParameterError(
                    "wavelengths.values_nm", self.values_nm, "either values_nm or start_nm/stop_nm/step_nm, not both"
                )
            values = _increasing("wavelengths.values_nm", self.values_nm)
            bounds.WAVELENGTH_COUNT.check(len(values), "wavelengths.values_nm (count)")
            if values[0] <= 0:
                raise ParameterError("wavelengths.values_nm", self.values_nm, "wavelengths > 0 nm")
            return
        start = _positive("wavelengths.start_nm", 390.0 if self.start_nm is None else self.start_nm)
        stop = _positive("wavelengths.stop_nm", 730.0 if self.stop_nm is None else self.stop_nm)
        step = _positive("wavelengths.step_nm", 10.0 if self.step_nm is None else self.step_nm)
        if stop < start:
            raise ParameterError("wavelengths.stop_nm", self.stop_nm, f"≥ start_nm = {start:g}")
        count = (stop - start) / step + 1
        if count > bounds.WAVELENGTH_COUNT.high:  # before the grid is made
            raise ParameterError("wavelengths.step_nm", self.step_nm,
                                 f"a step giving at most {bounds.WAVELENGTH_COUNT.high} wavelengths from start_nm to "
                                 f"stop_nm (this one gives {count:.4g})")
        if abs(round((stop - start) / step) * step - (stop - start)) > 1e-6 * step:
            raise ParameterError(
                "wavelengths.step_nm", self.step_nm, f"a divisor of stop_nm − start_nm = {stop - start:g}"
            )

    @property
    def values(self) -> np.ndarray:
        """(L,) the wavelengths, nm, strictly increasing."""
        if self.values_nm is not None:
            return np.asarray(self.values_nm, float)
        start = 390.0 if self.start_nm is None else float(self.start_nm)
        stop = 730.0 if self.stop_nm is None else float(self.stop_nm)
        step = 10.0 if self.step_nm is None else float(self.step_nm)
        return start + step * np.arange(int(round((stop - start) / step)) + 1)


@dataclass(frozen=True)
class RefractiveIndex:
    """A complex refractive index ``n + ik`` (``k ≥ 0`` absorbs), constant or tabulated vs wavelength.

    ``n`` and ``k`` are numbers, or sequences on ``wavelengths_nm`` (vacuum, nm),
    interpolated linearly and never extrapolated.  ``name`` is the parameter's
    dotted name, used in error messages.
    """

    n: float | tuple[float, ...]
    k: float | tuple[float, ...] = 0.0
    wavelengths_nm: tuple[float, ...] | None = None
    name: str = "refractive_index"

    def __post_init__(self):
        if self.wavelengths_nm is None:
            _positive(f"{self.name}.n", self.n)
            if _finite(f"{self.name}.k", self.k, "a finite number ≥ 0") < 0:
                raise ParameterError(f"{self.name}.k", self.k, "a finite number ≥ 0")
            return
        table = _increasing(f"{self.name}.wavelengths_nm", self.wavelengths_nm)
        for part, allowed in (("n", "> 0"), ("k", "≥ 0")):
            values = _finite_array(f"{self.name}.{part}", getattr(self, part))
            if values.ndim > 1 or (values.ndim == 1 and values.shape != table.shape):
                raise ParameterError(
                    f"{self.name}.{part}", getattr(self, part), f"one number, or {table.size} (one per wavelength)"
                )
            if (part == "n" and np.any(values <= 0)) or (part == "k" and np.any(values < 0)):
                raise ParameterError(f"{self.name}.{part}", getattr(self, part), f"{allowed} at every wavelength")

    @property
    def is_absorbing(self) -> bool:
        """Whether ``k`` is non-zero anywhere."""
        return bool(np.any(np.asarray(self.k, float) != 0.0))

    def at(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """(L,) complex index ``n + ik`` at the given vacuum wavelengths (nm)."""
        wavelengths_nm = np.asarray(wavelengths_nm, float)
        if self.wavelengths_nm is None:
            return np.full(wavelengths_nm.shape, complex(float(self.n), float(self.k)))
        table = np.asarray(self.wavelengths_nm, float)
        n = _interpolate(
            f"{self.name}.wavelengths_nm",
            table,
            np.broadcast_to(np.asarray(self.n, float), table.shape),
            wavelengths_nm,
        )
        k = _interpolate(
            f"{self.name}.wavelengths_nm",
            table,
            np.broadcast_to(np.asarray(self.k, float), table.shape),
            wavelengths_nm,
        )
        return n + 1j * k


@dataclass(frozen=True)
class ParticleSpecies:
    """One kind of spherical particle dispersed in the host.

    Attributes
    ----------
    name
        Label used in reports and error messages (``particles[name]``).
    refractive_index
        Absolute (not relative) index of the particle material.
    volume_fraction
        Fraction of the yarn volume the particles occupy, in (0, 0.74).
    diameter_nm
        Diameter of monodisperse particles, nm.  Or ``None``, with a log-normal
        *number* distribution of diameters: ``median_diameter_nm`` (nm) and
        ``geometric_sigma`` (dimensionless geometric standard deviation, in
        (1, 2.5]).
    """

    name: str
    refractive_index: RefractiveIndex
    volume_fraction: float
    diameter_nm: float | None = None
    median_diameter_nm: float | None = None
    geometric_sigma: float | None = None

    def __post_init__(self):
        label = f"particles[{self.name}]"
        if not isinstance(self.refractive_index, RefractiveIndex):
            raise ParameterError(f"{label}.refractive_index", self.refractive_index, "a RefractiveIndex")
        fraction = _finite(f"{label}.volume_fraction", self.volume_fraction, f"(0, {MAX_VOLUME_FRACTION})")
        if not 0.0 < fraction < MAX_VOLUME_FRACTION:
            raise ParameterError(f"{label}.volume_fraction", self.volume_fraction, f"(0, {MAX_VOLUME_FRACTION})")
        if self.diameter_nm is not None:
            if self.median_diameter_nm is not None or self.geometric_sigma is not None:
                raise ParameterError(
                    f"{label}.diameter_nm",
                    self.diameter_nm,
                    "either diameter_nm or median_diameter_nm with geometric_sigma, not both",
                )
            bounds.PARTICLE_DIAMETER_NM.check(self.diameter_nm, f"{label}.diameter_nm")
            return
        if self.median_diameter_nm is None or self.geometric_sigma is None:
            raise ParameterError(f"{label}.diameter_nm", None, "a diameter, or median_diameter_nm with geometric_sigma")
        bounds.PARTICLE_DIAMETER_NM.check(self.median_diameter_nm, f"{label}.median_diameter_nm")
        sigma = _finite(f"{label}.geometric_sigma", self.geometric_sigma, "(1, 2.5]")
        if not 1.0 < sigma <= 2.5:
            raise ParameterError(
                f"{label}.geometric_sigma", self.geometric_sigma, "(1, 2.5] (1 is monodisperse: use diameter_nm)"
            )


@dataclass(frozen=True)
class Fibres:
    """The fibres a yarn is spun from, in the host (air for a spun yarn: ``host.refractive_index = 1``).

    Attributes
    ----------
    refractive_index
        Absolute index of the fibre material (cellulose ≈ 1.557, §3.2); the dye, when the medium has
        one, is absorbed inside the fibres (:mod:`precompute.optics.fibre`).
    diameter_um
        Fibre diameter, µm (cotton 12–20 µm).
    volume_fraction
        Fraction of the yarn volume the fibres fill, in (0, 0.90) (a spun yarn packs 0.4–0.6).
    cross_section
        ``"circle"``: the only one modelled so far.
    absorption_per_mm
        Grey absorption of the fibre material itself beside the dye, 1/mm.
    orientation
        ``"random"``: fibres in every direction, scattering as their Mie proxy (:mod:`precompute.optics.fibre`);
        ``"yarn_axis"``: along the yarn at its twist's helix angle (``yarn.twist_angle_deg``), every
        collision traced through a fibre (:mod:`precompute.optics.fibre_orientation`).
    orientation_spread_deg
        With ``"yarn_axis"``: σ of the fibres' spread about their helix (migration, hairiness), degrees.
    roughness_deg
        With ``"yarn_axis"``: σ of the blur of the direction a fibre sends light in (a fibre surface
        rougher than a smooth cylinder's), degrees.
    """

    refractive_index: RefractiveIndex
    diameter_um: float
    volume_fraction: float
    cross_section: str = "circle"
    absorption_per_mm: float = 0.0
    orientation: str = RANDOM_ORIENTATION
    orientation_spread_deg: float = 0.0
    roughness_deg: float = 0.0

    def __post_init__(self):
        if not isinstance(self.refractive_index, RefractiveIndex):
            raise ParameterError("fibres.refractive_index", self.refractive_index, "a RefractiveIndex")
        bounds.FIBRE_DIAMETER_UM.check(self.diameter_um)
        fraction = _finite("fibres.volume_fraction", self.volume_fraction, f"(0, {MAX_FIBRE_VOLUME_FRACTION})")
        if not 0.0 < fraction < MAX_FIBRE_VOLUME_FRACTION:
            raise ParameterError("fibres.volume_fraction", self.volume_fraction, f"(0, {MAX_FIBRE_VOLUME_FRACTION})")
        if self.cross_section != "circle":
            raise ParameterError("fibres.cross_section", self.cross_section, "'circle'")
        value = _finite("fibres.absorption_per_mm", self.absorption_per_mm, "a finite number ≥ 0")
        if value < 0:
            raise ParameterError("fibres.absorption_per_mm", self.absorption_per_mm, "a finite number ≥ 0")
        if self.orientation not in FIBRE_ORIENTATIONS:
            raise ParameterError("fibres.orientation", self.orientation, f"one of {FIBRE_ORIENTATIONS}")
        for name in ("orientation_spread_deg", "roughness_deg"):
            angle = _finite(f"fibres.{name}", getattr(self, name), "[0, 90] degrees")
            if not 0.0 <= angle <= 90.0:
                raise ParameterError(f"fibres.{name}", getattr(self, name), "[0, 90] degrees")


@dataclass(frozen=True)
class Dye:
    """Dye dissolved in the fiber (§6.2: 1–5 % by weight).

    ``mass_absorption_cm2_per_g`` is the napierian mass absorption coefficient
    ``ε(λ)`` in cm²/g on ``wavelengths_nm`` (vacuum, nm); a dye weight fraction
    ``w`` in a fiber of density ``ρ_f`` (g/cm³) absorbs with ``μ_a = ε · w · ρ_f``
    (1/cm).  ``source`` names where the spectrum came from.
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
        table = _increasing("dye.wavelengths_nm", self.wavelengths_nm)
        epsilon = _finite_array(
            "dye.mass_absorption_cm2_per_g", self.mass_absorption_cm2_per_g, f"{table.size} finite values ≥ 0"
        )
        if epsilon.shape != table.shape:
            raise ParameterError(
                "dye.mass_absorption_cm2_per_g",
                f"{epsilon.size} values",
                f"{table.size} finite values ≥ 0, one per wavelength",
            )
        if np.any(epsilon < 0):
            raise ParameterError("dye.mass_absorption_cm2_per_g", float(epsilon.min()), "≥ 0 at every wavelength")


@dataclass(frozen=True)
class Yarn:
    """Yarn cross-section.

    ``radius_mm`` is the radius of the circular cross-section the transport
    uses (paper §3.2).  ``cross_section = "ellipse"`` with ``semi_axes_mm``
    (two lengths, mm) records an elliptical cross-section for later use (§7).
    ``ply_count`` plies are twisted about the yarn's axis at ``twist_angle_deg``, the surface
    helix angle (degrees from the axis); the paper's yarn is one untwisted rod (1, 0°).  One
    angle per yarn: the close-up geometry's ply grooves and the fibres' orientation both use it.
    """

    radius_mm: float = 0.1
    cross_section: str = "circle"
    semi_axes_mm: tuple[float, float] | None = None
    ply_count: int = 1
    twist_angle_deg: float = 0.0

    def __post_init__(self):
        bounds.YARN_RADIUS_MM.check(self.radius_mm)
        bounds.YARN_PLY_COUNT.check(self.ply_count)
        bounds.YARN_TWIST_ANGLE_DEG.check(self.twist_angle_deg)
        if self.cross_section not in ("circle", "ellipse"):
            raise ParameterError("yarn.cross_section", self.cross_section, "'circle' or 'ellipse'")
        if self.cross_section == "circle":
            if self.semi_axes_mm is not None:
                raise ParameterError("yarn.semi_axes_mm", self.semi_axes_mm, "absent for a circular cross-section")
            return
        if not isinstance(self.semi_axes_mm, (tuple, list)) or len(self.semi_axes_mm) != 2:
            raise ParameterError(
                "yarn.semi_axes_mm", self.semi_axes_mm, "two semi-axes in mm for an elliptical cross-section"
            )
        for axis in self.semi_axes_mm:
            _positive("yarn.semi_axes_mm", axis)


@dataclass(frozen=True)
class Host:
    """The yarn's host material.

    ``refractive_index`` must be real (``k = 0``); the host's own absorption is
    ``absorption_per_mm``, the absorption coefficient (1/mm) it adds to the
    yarn volume, default 0 (undyed cellulose is transparent in the visible).
    """

    refractive_index: RefractiveIndex
    absorption_per_mm: float = 0.0

    def __post_init__(self):
        if not isinstance(self.refractive_index, RefractiveIndex):
            raise ParameterError("host.refractive_index", self.refractive_index, "a RefractiveIndex")
        if self.refractive_index.is_absorbing:
            raise ParameterError(
                "host.refractive_index.k", self.refractive_index.k, "0: give the host's absorption as absorption_per_mm"
            )
        for n in np.atleast_1d(np.asarray(self.refractive_index.n, float)):
            bounds.HOST_REFRACTIVE_INDEX.check(n)
        value = _finite("host.absorption_per_mm", self.absorption_per_mm, "a finite number ≥ 0")
        if value < 0:
            raise ParameterError("host.absorption_per_mm", self.absorption_per_mm, "a finite number ≥ 0")


@dataclass(frozen=True)
class MediumParameters:
    """Everything that defines a yarn medium; see the module docstring.

    ``fibres``: the yarn's fibres (:class:`Fibres`), or None for the paper's
    yarn of one host; with fibres the dye is in them, not in the host.
    ``dependent_scattering`` is ``"none"`` (independent scattering, as in the
    paper) or ``"percus-yevick"`` (hard-sphere structure-factor correction, see
    :mod:`precompute.optics.mie`); ``phase_samples`` is ``"auto"`` (the default: the
    optics choose a cos θ grid fine enough for every species at every
    wavelength, :func:`precompute.optics.mie.auto_phase_grid`) or the size of a grid
    uniform in cos θ, refused by the optics if too coarse for the particles.
    """

    name: str
    host: Host
    particles: tuple[ParticleSpecies, ...]
    dye: Dye | None = None
    fibres: Fibres | None = None
    yarn: Yarn = field(default_factory=Yarn)
    wavelengths: WavelengthGrid = field(default_factory=WavelengthGrid)
    dependent_scattering: str = "none"
    phase_samples: int | str = AUTO_PHASE_SAMPLES
    description: str = ""

    def __post_init__(self):
        if self.dependent_scattering not in DEPENDENT_SCATTERING_MODELS:
            raise ParameterError(
                "medium.dependent_scattering", self.dependent_scattering, f"one of {DEPENDENT_SCATTERING_MODELS}"
            )
        if self.phase_samples != AUTO_PHASE_SAMPLES and (
            isinstance(self.phase_samples, bool)
            or not isinstance(self.phase_samples, int)
            or not 201 <= self.phase_samples <= 200001
        ):
            raise ParameterError(
                "medium.phase_samples", self.phase_samples, f"{AUTO_PHASE_SAMPLES!r} or an integer in [201, 200001]"
            )
        if self.fibres is not None and not isinstance(self.fibres, Fibres):
            raise ParameterError("fibres", self.fibres, "a Fibres")
        if self.fibres is not None and self.fibres.orientation != RANDOM_ORIENTATION:
            # the transport traces oriented fibres alone, in a host that neither absorbs nor scatters
            if self.particles:
                raise ParameterError("particles", len(self.particles), "none beside fibres along the yarn axis")
            if self.host.absorption_per_mm != 0.0:
                raise ParameterError("host.absorption_per_mm", self.host.absorption_per_mm,
                                     "0 with fibres along the yarn axis (theirs is fibres.absorption_per_mm)")
        if not all(isinstance(p, ParticleSpecies) for p in self.particles):
            raise ParameterError("particles", self.particles, "a sequence of ParticleSpecies")
        total = self.total_volume_fraction
        if total >= MAX_VOLUME_FRACTION:
            raise ParameterError("particles[*].volume_fraction (sum)", total, f"< {MAX_VOLUME_FRACTION}")

    @property
    def total_volume_fraction(self) -> float:
        """Fraction of the yarn volume taken by particles of every species."""
        return float(sum(p.volume_fraction for p in self.particles))

    @property
    def dye_only_absorbs(self) -> bool:
        """Whether a change of the dye changes only what the medium absorbs, not how it scatters, so that
        one transport reweighted reads every dye amount (a dye series, :mod:`precompute.transport.absorption`):
        a dye in the host, or in fibres along the yarn axis, whose transport takes their index real and
        follows their absorption alone along each chord (:mod:`precompute.transport._fibres`); not in
        randomly oriented fibres, whose scattering their absorption index enters (:mod:`.fibre`)."""
        return self.fibres is None or self.fibres.orientation != RANDOM_ORIENTATION

    def with_dye(self, weight_percent: float) -> MediumParameters:
        """The same medium with another dye amount, % of fibre weight (a dyed medium)."""
        return dataclasses.replace(self, dye=dataclasses.replace(self.dye, weight_percent=float(weight_percent)))

    def to_dict(self) -> dict:
        """A plain, JSON-serialisable description (for headers, hashes and reports)."""

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
    """Read a two-column CSV: vacuum wavelength (nm), value ≥ 0.

    ``#`` lines are comments and a first row of text is a header.  Missing,
    non-numeric, non-finite or negative values, fewer than two rows and
    wavelengths that do not strictly increase raise :class:`ParameterError`
    naming ``parameter``, the file and the line.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise ParameterError(parameter, str(path), "an existing CSV file")
    wavelengths, values = [], []
    header_allowed = True
    for line_number, line in enumerate(_read_text(path, parameter, "a UTF-8 CSV file").splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        row = next(csv.reader([line]))
        if header_allowed:
            header_allowed = False
            if not _is_number(row[0]):
                continue  # the header row
        where = f"{parameter} ({path.name}, line {line_number})"
        if len(row) < 2 or not row[0].strip() or not row[1].strip():
            raise ParameterError(where, line, "two values: wavelength_nm, value")
        if not (_is_number(row[0]) and _is_number(row[1])):
            raise ParameterError(where, line, "numbers")
        wavelength, value = float(row[0]), float(row[1])
        if not (math.isfinite(wavelength) and math.isfinite(value)):
            raise ParameterError(where, line, "finite numbers")
        if value < 0:
            raise ParameterError(where, value, "a value ≥ 0")
        wavelengths.append(wavelength)
        values.append(value)
    if len(wavelengths) < 2:
        raise ParameterError(parameter, str(path), "a CSV with at least two data rows")
    _increasing(f"{parameter} ({path.name}) wavelengths", wavelengths)
    return tuple(wavelengths), tuple(values)


def _read_text(path: pathlib.Path, parameter: str, what: str) -> str:
    """A text file's content; ParameterError naming ``parameter`` and the file (and, for bytes that
    are not UTF-8, the line) when it cannot be read as text."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ParameterError(parameter, str(path), f"{what} this user can read ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise ParameterError(parameter, str(path), f"{what} (line {line} holds bytes that are not UTF-8 text: "
                                                   "is this a binary file?)") from None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _table(config: dict, key: str, where: str) -> dict:
    value = config.get(key, {})
    if not isinstance(value, dict):
        raise ParameterError(f"{where}{key}", value, "a TOML table")
    return value


def _check_keys(table: dict, allowed: set[str], where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ParameterError(f"{where}.{unknown[0]}", table[unknown[0]], f"one of the keys {sorted(allowed)}")


def _resolve(path_text, parameter: str, base_dir: pathlib.Path) -> pathlib.Path:
    if not isinstance(path_text, str) or not path_text:
        raise ParameterError(parameter, path_text, "a file path")
    path = pathlib.Path(path_text)
    if path.is_absolute():
        return path
    candidates = [base_dir / path, DATA_DIR / path]
    return next((c for c in candidates if c.is_file()), candidates[0])


def _index(spec, name: str, base_dir: pathlib.Path) -> RefractiveIndex:
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return RefractiveIndex(n=spec, name=name)
    if isinstance(spec, list) and len(spec) == 2:
        return RefractiveIndex(n=spec[0], k=spec[1], name=name)
    if isinstance(spec, dict):
        _check_keys(spec, {"n", "k", "wavelengths_nm", "csv"}, name)
        if "csv" in spec:
            if set(spec) != {"csv"}:
                raise ParameterError(
                    f"{name}.csv", spec["csv"], "a CSV of wavelength_nm, n alone, without n, k or wavelengths_nm"
                )
            wavelengths, n = read_spectrum_csv(_resolve(spec["csv"], f"{name}.csv", base_dir), f"{name}.csv")
            return RefractiveIndex(n=n, wavelengths_nm=wavelengths, name=name)
        if "n" not in spec or "wavelengths_nm" not in spec:
            raise ParameterError(name, spec, "a table with wavelengths_nm and n (and optionally k)")

        def values(key):
            value = spec.get(key, 0.0)
            return tuple(value) if isinstance(value, list) else value

        return RefractiveIndex(n=values("n"), k=values("k"), wavelengths_nm=values("wavelengths_nm"), name=name)
    raise ParameterError(name, spec, "a number n, [n, k], or a table {wavelengths_nm, n, k} or {csv}")


def dye_mixture_spectrum(spectrum_csv, shares, base_dir: pathlib.Path = PRESET_DIR):
    """A ``[dye]`` table's spectrum: one CSV, or a shade recipe — several dyes in the same fibre.

    ``spectrum_csv`` a CSV file (``shares`` None), or a list of K of them with ``shares`` the K
    fractions of the dye weight each dye makes up (≥ 0, summing to 1).  Absorption adds (Beer–Lambert
    for dyes that do not interact), so K dyes at weight shares s_k of w % absorb as one dye of w % with
    ε(λ) = Σ s_k ε_k(λ).  Returns (wavelengths nm, ε cm²/g, a source naming the CSVs and their shares):
    the first table's wavelengths within the range every table covers."""
    if isinstance(spectrum_csv, str):
        if shares is not None:
            raise ParameterError("dye.shares", shares, "absent for one dye (a list of shares goes with a list of "
                                                       "spectrum_csv files)")
        path = _resolve(spectrum_csv, "dye.spectrum_csv", base_dir)
        wavelengths_nm, epsilon = read_spectrum_csv(path, "dye.spectrum_csv")
        return wavelengths_nm, epsilon, path.name
    if not isinstance(spectrum_csv, list) or not spectrum_csv:
        raise ParameterError("dye.spectrum_csv", spectrum_csv, "a CSV file, or a list of them with dye.shares")
    count = len(spectrum_csv)
    if (not isinstance(shares, list) or len(shares) != count
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0
                       for v in shares)):
        raise ParameterError("dye.shares", shares, f"{count} numbers ≥ 0, one per dye.spectrum_csv file")
    if not math.isclose(sum(shares), 1.0, abs_tol=1e-6):
        raise ParameterError("dye.shares", shares, "fractions of the dye weight that sum to 1")
    tables = []
    for number, text in enumerate(spectrum_csv):
        name = f"dye.spectrum_csv[{number}]"
        path = _resolve(text, name, base_dir)
        tables.append((path.name, *(np.asarray(v, float) for v in read_spectrum_csv(path, name))))
    low = max(table[1][0] for table in tables)
    high = min(table[1][-1] for table in tables)
    grid = tables[0][1][(tables[0][1] >= low) & (tables[0][1] <= high)]
    if grid.size < 2:
        raise ParameterError("dye.spectrum_csv", spectrum_csv, "spectra that share a wavelength range")
    epsilon = sum(share * np.interp(grid, wavelengths, values)
                  for share, (_, wavelengths, values) in zip(shares, tables))
    source = " + ".join(f"{share:.4g} {name}" for share, (name, _, _) in zip(shares, tables))
    return tuple(float(v) for v in grid), tuple(float(v) for v in epsilon), source


def medium_from_dict(config: dict, base_dir: pathlib.Path = PRESET_DIR) -> MediumParameters:
    """Build :class:`MediumParameters` from a preset's TOML content; relative file paths resolve in ``base_dir``."""
    _check_keys(
        config,
        {"name", "description", "wavelengths", "host", "particles", "fibres", "dye", "yarn", "medium",
         *_FOREIGN_TABLES},
        "preset",
    )
    wavelengths = _table(config, "wavelengths", "")
    _check_keys(wavelengths, {"start_nm", "stop_nm", "step_nm", "values_nm"}, "wavelengths")
    if "values_nm" in wavelengths and isinstance(wavelengths["values_nm"], list):
        wavelengths = {**wavelengths, "values_nm": tuple(wavelengths["values_nm"])}
    if "host" not in config:
        raise ParameterError("host", None, "a [host] table with refractive_index")
    host = _table(config, "host", "")
    _check_keys(host, {"refractive_index", "absorption_per_mm"}, "host")
    particle_specs = config.get("particles", [])
    if not isinstance(particle_specs, list) or not all(isinstance(s, dict) for s in particle_specs):
        raise ParameterError("particles", particle_specs, "[[particles]] tables")
    particles = []
    for number, spec in enumerate(particle_specs):
        _check_keys(
            spec,
            {"name", "refractive_index", "volume_fraction", "diameter_nm", "median_diameter_nm", "geometric_sigma"},
            f"particles[{number}]",
        )
        name = str(spec.get("name", number))
        if "refractive_index" not in spec:
            raise ParameterError(f"particles[{name}].refractive_index", None, "a number n, [n, k], or a table")
        if "volume_fraction" not in spec:
            raise ParameterError(f"particles[{name}].volume_fraction", None, f"(0, {MAX_VOLUME_FRACTION})")
        particles.append(
            ParticleSpecies(
                name=name,
                refractive_index=_index(spec["refractive_index"], f"particles[{name}].refractive_index", base_dir),
                volume_fraction=spec["volume_fraction"],
                diameter_nm=spec.get("diameter_nm"),
                median_diameter_nm=spec.get("median_diameter_nm"),
                geometric_sigma=spec.get("geometric_sigma"),
            )
        )
    dye = None
    if "dye" in config:
        spec = _table(config, "dye", "")
        _check_keys(spec, {"weight_percent", "fiber_density_g_per_cm3", "spectrum_csv", "shares"}, "dye")
        for key in ("weight_percent", "fiber_density_g_per_cm3"):
            if key not in spec:
                raise ParameterError(f"dye.{key}", None, "a number")
        if "spectrum_csv" not in spec:
            raise ParameterError("dye.spectrum_csv", None, "a CSV of wavelength_nm, napierian mass absorption cm²/g")
        wavelengths_nm, epsilon, source = dye_mixture_spectrum(spec["spectrum_csv"], spec.get("shares"), base_dir)
        dye = Dye(
            weight_percent=spec["weight_percent"],
            fiber_density_g_per_cm3=spec["fiber_density_g_per_cm3"],
            wavelengths_nm=wavelengths_nm,
            mass_absorption_cm2_per_g=epsilon,
            source=source,
        )
    fibres = None
    if "fibres" in config:
        spec = _table(config, "fibres", "")
        _check_keys(spec, {"refractive_index", "diameter_um", "volume_fraction", "cross_section", "absorption_per_mm",
                           "orientation", "orientation_spread_deg", "roughness_deg"}, "fibres")
        for key in ("refractive_index", "diameter_um", "volume_fraction"):
            if key not in spec:
                raise ParameterError(f"fibres.{key}", None, "a value")
        fibres = Fibres(
            refractive_index=_index(spec["refractive_index"], "fibres.refractive_index", base_dir),
            diameter_um=spec["diameter_um"],
            volume_fraction=spec["volume_fraction"],
            cross_section=spec.get("cross_section", "circle"),
            absorption_per_mm=spec.get("absorption_per_mm", 0.0),
            orientation=spec.get("orientation", RANDOM_ORIENTATION),
            orientation_spread_deg=spec.get("orientation_spread_deg", 0.0),
            roughness_deg=spec.get("roughness_deg", 0.0),
        )
    yarn = _table(config, "yarn", "")
    _check_keys(yarn, {"radius_mm", "cross_section", "semi_axes_mm", "ply_count", "twist_angle_deg"}, "yarn")
    medium = _table(config, "medium", "")
    _check_keys(medium, {"dependent_scattering", "phase_samples"}, "medium")
    return MediumParameters(
        name=str(config.get("name", "custom")),
        description=str(config.get("description", "")),
        wavelengths=WavelengthGrid(**wavelengths),
        host=Host(
            refractive_index=_index(host.get("refractive_index"), "host.refractive_index", base_dir),
            absorption_per_mm=host.get("absorption_per_mm", 0.0),
        ),
        particles=tuple(particles),
        dye=dye,
        fibres=fibres,
        yarn=Yarn(
            radius_mm=yarn.get("radius_mm", 0.1),
            cross_section=yarn.get("cross_section", "circle"),
            semi_axes_mm=(
                tuple(yarn["semi_axes_mm"]) if isinstance(yarn.get("semi_axes_mm"), list) else yarn.get("semi_axes_mm")
            ),
            ply_count=yarn.get("ply_count", 1),
            twist_angle_deg=yarn.get("twist_angle_deg", 0.0),
        ),
        dependent_scattering=medium.get("dependent_scattering", "none"),
        phase_samples=medium.get("phase_samples", AUTO_PHASE_SAMPLES),
    )


def preset_names() -> list[str]:
    """Names of the presets shipped in ``precompute/presets``."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def preset_path(name_or_path: str | pathlib.Path) -> pathlib.Path:
    """The TOML file of a shipped preset name, or the given path to a TOML file."""
    candidate = pathlib.Path(name_or_path)
    if str(name_or_path).strip() and candidate.is_dir():
        raise ParameterError("preset", str(name_or_path), "a preset name or a TOML file (this is a folder)")
    if not str(name_or_path).strip():
        raise ParameterError("preset", str(name_or_path), f"one of {preset_names()} or a path to a TOML file")
    if candidate.suffix == ".toml" or candidate.is_file():
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
        config = tomllib.loads(_read_text(path, "preset", "a UTF-8 TOML file"))
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("preset", str(path), f"valid TOML ({exc})") from None
    return config, path.parent


def load_preset(name_or_path: str | pathlib.Path = DEFAULT_PRESET) -> MediumParameters:
    """Medium parameters of a shipped preset (by name) or of a TOML file (by path)."""
    config, base_dir = load_preset_config(name_or_path)
    return medium_from_dict(config, base_dir)
