"""The allowed range of every numeric input of the yarn bake, as data: one definition per parameter.

The Python API (:mod:`precompute.optics.medium`, :mod:`precompute.bake`), the command line (``python -m
precompute``: each option parses with :meth:`Bound.argument`, which also takes the ``2e4`` notation
its help prints) and the add-on's panel (``clothlight/blender/properties.py``: ``min``/``max`` from
:meth:`Bound.limits`) all read these, so they refuse the same values with the same message: the
parameter, the value and the range (:class:`~precompute.errors.ParameterError`).  The add-on's own
bounds (validation renders, the cloth gonioreflectometer) are in ``clothlight/render_bounds.py``,
the weave's in ``clothlight/weave/params.py``.

Upper limits keep a run within what a machine can do: the grids' tallies are estimated before they
are allocated (:func:`transport_memory_bytes`) and refused above :func:`memory_limit_bytes` (half
of this machine's memory) with the estimate and the parameters that make it.

Standard library only: the panel imports this at Blender's start.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import os
from decimal import Decimal, InvalidOperation
from types import MappingProxyType

from precompute.errors import ParameterError

#: Share of the machine's physical memory a bake or a render may plan to use.
MEMORY_FRACTION = 0.5
#: Assumed where the physical memory cannot be read (not Linux or macOS).
FALLBACK_MEMORY_BYTES = 16 * 2**30


@dataclasses.dataclass(frozen=True)
class Bound:
    """The allowed range of one numeric parameter: [low, high], either end open where said.

    Attributes
    ----------
    name
        The parameter as the API, a preset or an override spells it (``transport.n_around``).
    low, high
        Smallest and largest allowed value.
    integer
        Only integers (``True`` and ``False`` are not numbers here).
    odd
        Only odd integers.
    unit
        Unit shown after the range ("nm", "mm").
    low_open, high_open
        ``low`` (``high``) itself is not allowed: the range is (low, high] ([low, high), (low, high)).
    """

    name: str
    low: float
    high: float
    integer: bool = False
    odd: bool = False
    unit: str = ""
    low_open: bool = False
    high_open: bool = False

    def allowed(self) -> str:
        """The range in words, as error messages and the docs give it."""
        kind = "an odd integer" if self.odd else ("an integer" if self.integer else "a number")
        unit = f" {self.unit}" if self.unit else ""
        return (f"{kind} in {'(' if self.low_open else '['}{_show(self.low)}, {_show(self.high)}"
                f"{')' if self.high_open else ']'}{unit}")

    def _outside(self, number) -> bool:
        return (not self.low <= number <= self.high or (self.low_open and number == self.low)
                or (self.high_open and number == self.high))

    def refuse(self, value, name: str | None = None) -> ParameterError:
        return ParameterError(name or self.name, value, self.allowed())

    def check(self, value, name: str | None = None) -> int | float:
        """``value`` as an int (integer bounds) or a float, if allowed; ParameterError otherwise.

        ``name`` replaces :attr:`name` in the message (``particles[scatterers].diameter_nm``)."""
        if isinstance(value, (bool, str, bytes)) or value is None:
            raise self.refuse(value, name)
        if self.integer:
            try:
                number = operator.index(value)  # int and numpy integers, never floats
            except TypeError:
                raise self.refuse(value, name) from None
        else:
            try:
                number = float(value)
            except (TypeError, ValueError, OverflowError):
                raise self.refuse(value, name) from None
            if not math.isfinite(number):
                raise self.refuse(value, name)
        if self._outside(number) or (self.odd and number % 2 == 0):
            raise self.refuse(value, name)
        return number

    def parse(self, text: str, name: str | None = None) -> int | float:
        """A value typed as text (an option, a field), checked: integers may be written ``20000``,
        ``20_000`` or ``2e4``; numbers as Python reads floats.  ParameterError otherwise."""
        if not isinstance(text, str):
            return self.check(text, name)
        if not self.integer:
            try:
                return self.check(float(text), name)
            except (ValueError, ParameterError):  # not a number, or refused: the text as typed in the message
                raise self.refuse(text.strip(), name) from None
        try:
            exact = Decimal(text.strip())
        except InvalidOperation:
            raise self.refuse(text.strip(), name) from None
        if not exact.is_finite() or exact != exact.to_integral_value():
            raise self.refuse(text.strip(), name)
        if self._outside(exact):  # compared as decimals: 1e999999 never becomes an int
            raise self.refuse(int(exact) if exact.adjusted() < 30 else text.strip(), name)
        return self.check(int(exact), name)

    def argument(self, option: str):
        """An argparse ``type`` for the option ``option``: :meth:`parse`, its refusal in argparse's
        words (``argument --paths: transport.paths_per_cell = 0 is invalid: allowed …``, exit code 2)."""
        import argparse

        def convert(text: str) -> int | float:
            try:
                return self.parse(text)
            except ParameterError as error:
                raise argparse.ArgumentTypeError(str(error)) from None

        convert.__name__ = option
        return convert

    def limits(self) -> dict:
        """``min`` and ``max`` for a Blender ``IntProperty`` / ``FloatProperty`` of this parameter."""
        if self.integer:
            return {"min": int(self.low), "max": int(self.high)}
        return {"min": float(self.low), "max": float(self.high)}


def _show(number: float) -> str:
    if isinstance(number, int) or float(number).is_integer():
        return str(int(number))
    return f"{number:g}"


# ---- the yarn bake ([transport] of a preset, python -m precompute bake, the Bake Tables panel) ----

#: Paths per incidence cell: 10^8 × 144 cells is days of transport on a workstation.
PATHS_PER_CELL = Bound("transport.paths_per_cell", 2, 100_000_000, integer=True)
#: Relative standard error of every cell's albedo: below 10^-4 no cell gets there within the
#: transport's path cap (4·10^6 per cell), above 0.5 the estimate means nothing.
TARGET_REL_STDERR = Bound("transport.target_rel_stderr", 1e-4, 0.5)
N_AROUND = Bound("transport.n_around", 3, 256, integer=True)
N_ALONG = Bound("transport.n_along", 1, 256, integer=True)
ANGULAR_RESOLUTION = Bound("transport.angular_resolution", 2, 64, integer=True)
#: N_i of the tables' incidence grid (or "auto"): odd, up to 63 (a table's atlas side N_i · N_o).
INCIDENCE_RESOLUTION = Bound("transport.incidence_resolution", 3, 63, integer=True, odd=True)
#: The grid settings of ``[transport]``, by their key: what a bake request carries besides its path
#: budget and seed (:class:`clothlight.medium_settings.BakeRequest`), and what sizes the transport's tallies.
GRID_SETTINGS = ("n_around", "n_along", "angular_resolution", "incidence_resolution")
SEED = Bound("transport.seed", 0, 2**63 - 1, integer=True)
#: The ``[transport]`` defaults, the one place for them: the bake merges a preset's table over them,
#: the transport's grids (:class:`precompute.transport.TransportGrids`) and the add-on's bake request
#: (:class:`clothlight.medium_settings.BakeRequest`) take theirs from here.  32 × 3 cells around and along: a
#: uniformly lit yarn reads only the sum along the axis (docs/transport.md), and an odd count lets the
#: transport use the yarn's mirror symmetry across its cross-section too, tracing a quarter of the
#: incidence cells rather than a half (:mod:`precompute.transport.symmetry`); 12 × 12 angular cells as
#: the paper's 144; the incidence grid chosen by the bake's accuracy checks.
TRANSPORT_DEFAULTS = MappingProxyType({
    "n_around": 32,
    "n_along": 3,
    "angular_resolution": 12,
    "incidence_resolution": "auto",
    "paths_per_cell": None,
    "target_rel_stderr": 0.01,
    "seed": 0,
})

# ---- the medium (preset TOML, --set, the Yarn Medium panel) ----

#: A particle's diameter (or number median diameter): Mie series grow with the size parameter,
#: and at 100 µm it is already ~1200 terms in the blue.
PARTICLE_DIAMETER_NM = Bound("particles[*].diameter_nm", 1.0, 100_000.0, unit="nm")
YARN_RADIUS_MM = Bound("yarn.radius_mm", 0.001, 10.0, unit="mm")
#: Fibre diameters, µm: from fine microfibres to coarse wool and bast fibres.
FIBRE_DIAMETER_UM = Bound("fibres.diameter_um", 1.0, 100.0, unit="µm")
#: Plies twisted into one yarn: sewing threads and shirting go up to 6; one is a single yarn.
YARN_PLY_COUNT = Bound("yarn.ply_count", 1, 6, integer=True)
#: Surface twist angle of the yarn (the helix angle of its plies and fibres to its axis): 0 is
#: untwisted; ring-spun cotton is 20–35°, and past 60° a yarn snarls.
YARN_TWIST_ANGLE_DEG = Bound("yarn.twist_angle_deg", 0.0, 60.0, unit="°", high_open=True)
#: The host's refractive index at every wavelength: the yarn sits in air (n = 1) and the transport's
#: boundary refracts from air into a denser host; no fibre comes near the upper end.
HOST_REFRACTIVE_INDEX = Bound("host.refractive_index.n", 1.0, 10.0)
#: Wavelengths of the simulation: every table grows with their number.
WAVELENGTH_COUNT = Bound("wavelengths (count)", 1, 1001, integer=True)

def parse_pair(value, name: str, allowed: str) -> tuple[float, float]:
    """Two finite numbers, given as a pair or typed ``"A,B"``.  ParameterError naming ``name`` with
    ``allowed`` (what the caller takes) otherwise; the caller checks their order and range."""
    try:
        values = [float(part) for part in (value.split(",") if isinstance(value, str) else value)]
    except (TypeError, ValueError):
        raise ParameterError(name, value, allowed) from None
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise ParameterError(name, value, allowed)
    return values[0], values[1]


def check_dye_range(value, name: str = "dye_series") -> tuple[float, float]:
    """A dye range (low, high), % of fibre weight, as a pair of numbers or typed ``"LOW,HIGH"``:
    0 ≤ low < high < 100.  ParameterError naming ``name`` otherwise."""
    low, high = parse_pair(value, name, "two dye amounts LOW,HIGH in % of fibre weight, e.g. 0.5,5")
    if not (0.0 <= low < high < 100.0):
        raise ParameterError(name, value, "0 ≤ LOW < HIGH < 100 (% of fibre weight)")
    return low, high


# ---- the medium fit (python -m clothlight.fit, the Yarn Medium panel's Fit) ----

#: Forward-model evaluations of a fit, the final one included: each takes about a second or more.
FIT_EVALUATIONS = Bound("--budget-evaluations", 2, 100_000, integer=True)


# ---- the slab check (python -m precompute slab) ----

SLAB_PATHS = Bound("paths", 2, 1_000_000_000, integer=True)
SLAB_ALBEDO = Bound("albedo", 0.0, 1.0)
SLAB_G = Bound("g", -1.0, 1.0, low_open=True, high_open=True)
SLAB_TAU = Bound("tau", 0.0, 10_000.0, low_open=True)
SLAB_INDEX = Bound("n", 1.0, 10.0)
SLAB_SEED = Bound("seed", 0, 2**63 - 1, integer=True)


# ---- memory ----

def physical_memory_bytes() -> int:
    """This machine's physical memory (a fallback where it cannot be read)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return FALLBACK_MEMORY_BYTES


def memory_limit_bytes() -> int:
    """What one bake or render may plan to allocate: :data:`MEMORY_FRACTION` of the physical memory."""
    return int(MEMORY_FRACTION * physical_memory_bytes())


def gib(n_bytes: float) -> str:
    return f"{n_bytes / 2**30:.3g} GiB"


def check_memory(estimate_bytes: float, name: str, value: object) -> None:
    """ParameterError naming ``name`` (the parameters that make the estimate) when ``estimate_bytes``
    exceeds :func:`memory_limit_bytes`."""
    limit = memory_limit_bytes()
    if estimate_bytes > limit:
        raise ParameterError(name, value, f"settings that need at most {gib(limit)} (half this machine's memory); "
                                          f"these need about {gib(estimate_bytes)}")


def transport_memory_bytes(n_around: int, n_along: int, angular_resolution: int, incidence_resolution: int,
                           wavelengths: int) -> int:
    """Peak memory of a yarn bake's simulation, bytes: the BSSRDF tallies (n_in × n_around × (n_along + 2)
    × n_out × L float32, and their second moments n_in × n_around × n_out × L), then, while they are
    held, eq. (5)'s weights and ρ over the incidence grid (N_i² directions, float64)."""
    n_in = n_out = angular_resolution**2
    n_dirs = incidence_resolution**2
    tallies = 4 * n_in * n_around * (n_along + 2) * n_out * wavelengths + 4 * n_in * n_around * n_out * wavelengths
    brdf = (8 * n_dirs * n_in * n_around              # the source weights
            + 4 * n_in * n_around * n_out * wavelengths  # the axial sums
            + 4 * 8 * n_dirs * n_out * wavelengths)      # ρ, its variance and two temporaries
    return tallies + brdf


def decayed_tally_bytes(n_around: int, angular_resolution: int, wavelengths: int, steps: int) -> int:
    """Memory of the absorption-reweighting tallies (:class:`precompute.transport.cylinder.DecayedExits`),
    bytes: n_in × n_around × n_out × L × K float32."""
    n_in = n_out = angular_resolution**2
    return 4 * n_in * n_around * n_out * wavelengths * steps


__all__ = ["ANGULAR_RESOLUTION", "FIBRE_DIAMETER_UM", "HOST_REFRACTIVE_INDEX", "INCIDENCE_RESOLUTION",
           "MEMORY_FRACTION", "N_ALONG",
           "N_AROUND", "PARTICLE_DIAMETER_NM", "PATHS_PER_CELL", "SEED", "SLAB_ALBEDO", "SLAB_G", "SLAB_INDEX",
           "SLAB_PATHS", "SLAB_SEED", "SLAB_TAU", "TARGET_REL_STDERR", "TRANSPORT_DEFAULTS", "WAVELENGTH_COUNT",
           "YARN_RADIUS_MM", "YARN_PLY_COUNT", "YARN_TWIST_ANGLE_DEG",
           "Bound", "check_memory", "decayed_tally_bytes", "gib", "memory_limit_bytes",
           "physical_memory_bytes", "transport_memory_bytes"]
