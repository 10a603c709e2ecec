"""The free parameters of a medium fit: what each sets, its unit, its fit range and its scale.

Each :class:`FitParameter` either sets one value of a preset's content (the dict a preset TOML
reads as, :func:`precompute.optics.medium.load_preset_config`) or is a keyword of the forward model (the
cloth's specular term, which is not part of the medium).  The optimiser works on every parameter
mapped to [0, 1] (:meth:`FitParameter.to_unit`): linearly, or linearly in log(value) where the
parameter spans decades (sizes and amounts).

The fit ranges lie inside what the medium accepts (``precompute.optics.medium``: volume fractions in
(0, 0.74) and < 0.74 in total, diameters within :data:`precompute.bounds.PARTICLE_DIAMETER_NM`,
dye in [0, 100) %, yarn radius within :data:`precompute.bounds.YARN_RADIUS_MM`), narrowed to what a
woven cloth's yarn can physically be, so the optimiser spends no evaluations on media no fabric is
made of.  docs/fitting.md lists them with their reasons.  A candidate whose volume fractions sum to
0.74 or more is refused by the medium; the optimiser scores it with a penalty instead of a forward
evaluation (:mod:`precompute.fit.optimise`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from precompute import bounds
from precompute.optics.cook_torrance import SPECULAR_DEFAULTS
from precompute.errors import ParameterError
from precompute.optics.medium import MAX_VOLUME_FRACTION

#: The particle species the void and scatterer parameters act on, by their preset ``name``.
VOIDS = "voids"
SCATTERERS = "scatterers"

#: What to add to a preset that has no species of a name a free parameter needs.
_SPECIES_TEMPLATES = {
    VOIDS: '[[particles]]\nname = "voids"\nrefractive_index = 1.0\ndiameter_nm = 1000.0\nvolume_fraction = 0.02',
    SCATTERERS: '[[particles]]\nname = "scatterers"\nrefractive_index = 1.61\ndiameter_nm = 150.0\n'
                'volume_fraction = 0.14',
}


#: The path of the second dye's share in a two-dye ``[dye]`` mixture (``shares = [1 − s, s]``,
#: precompute.optics.medium.dye_mixture_spectrum): one number sets the mixture's hue.
DYE_SHARE_PATH = "dye.shares"

#: Values the medium takes where a preset leaves them out (precompute.optics.medium.Yarn).
_MEDIUM_DEFAULTS = {"yarn.radius_mm": 0.1}


class UnknownFitParameterError(ParameterError):
    """A free parameter that is not in :data:`PARAMETERS` (bad input: exit code 2)."""


class MissingSpeciesError(ParameterError):
    """The preset lacks what a free parameter sets (a particle species, the dye)."""


@dataclass(frozen=True)
class FitParameter:
    """One free parameter of a fit.

    Attributes
    ----------
    name
        Its name on the command line (``--free``) and in the API.
    path
        What it sets: a preset path (``particles[voids].volume_fraction``) or, for the specular
        term, the forward model's keyword (``forward_model(..., specular_slope=)``).
    unit
        The unit of its values ("" for a fraction).
    low, high
        The fit range (both ends allowed).
    log
        Mapped to [0, 1] linearly in log(value) (sizes and amounts) rather than in value.
    scale
        The preset value is the parameter's value times ``scale`` (µm → nm: 1000).
    note
        Why the range is what it is (docs/fitting.md repeats it).
    """

    name: str
    path: str
    unit: str
    low: float
    high: float
    log: bool
    scale: float = 1.0
    note: str = ""

    @property
    def is_specular(self) -> bool:
        """Whether it is a forward-model keyword (a cloth-scale term: the sheen, the fuzz) rather than a
        medium value."""
        return self.path in SPECULAR_DEFAULTS

    def check(self, value: float) -> float:
        """``value`` as a float if it lies in the fit range; ParameterError naming it otherwise."""
        unit = f" {self.unit}" if self.unit else ""
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ParameterError(self.name, value, f"a number in [{self.low:g}, {self.high:g}]{unit}")
        if not self.low <= value <= self.high:
            raise ParameterError(self.name, value, f"a number in [{self.low:g}, {self.high:g}]{unit} (the fit range)")
        return float(value)

    def to_unit(self, value: float) -> float:
        """``value`` mapped to [0, 1] (clipped to the range first)."""
        value = min(max(float(value), self.low), self.high)
        if self.log:
            return (math.log(value) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, u: float) -> float:
        """The value at ``u`` in [0, 1] (clipped to [0, 1] first)."""
        u = min(max(float(u), 0.0), 1.0)
        if self.log:
            return math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)

    def at_bound(self, value: float, tolerance: float = 0.05) -> str | None:
        """``"lower"`` or ``"upper"`` when ``value`` lies within ``tolerance`` (of the [0, 1] range,
        where a noisy optimum settles short of a bound) of that end of the range, else None."""
        u = self.to_unit(value)
        if u <= tolerance:
            return "lower"
        if u >= 1.0 - tolerance:
            return "upper"
        return None

    # ---- the preset's content ----

    def get(self, config: Mapping, specular: Mapping | None = None) -> float:
        """The parameter's value in ``config`` (a preset's content) or, for the specular term, in
        ``specular`` (``{"specular_weight": …, "specular_slope": …}``); the medium's default where the
        preset leaves it out (the yarn radius)."""
        if self.is_specular:
            return float((specular or {}).get(self.path, SPECULAR_DEFAULTS[self.path]))
        if self.path == DYE_SHARE_PATH:  # no shares written: an even mixture
            return float((two_dye_table(config, self.name).get("shares") or (0.5, 0.5))[1])
        table, key = self._place(config)
        if key not in table:
            if self.path in _MEDIUM_DEFAULTS:
                return _MEDIUM_DEFAULTS[self.path] / self.scale
            raise MissingSpeciesError(self.path, None, f"a value in the preset for the free parameter {self.name}")
        return float(table[key]) / self.scale

    def set(self, config: dict, value: float) -> None:
        """Write ``value`` into ``config`` (in place).  Not for the specular parameters."""
        if self.is_specular:
            raise ValueError(f"{self.name} is a forward-model keyword, not a preset value")
        if self.path == DYE_SHARE_PATH:
            two_dye_table(config, self.name)["shares"] = [1.0 - float(value), float(value)]
            return
        table, key = self._place(config, create=True)
        table[key] = float(value) * self.scale

    def _place(self, config: Mapping, create: bool = False) -> tuple[dict, str]:
        section, _, key = self.path.rpartition(".")
        if section.startswith("particles["):
            return species_table(config, section[len("particles["):-1], self.name), key
        table = config.get(section)
        if isinstance(table, dict):
            return table, key
        if self.path in _MEDIUM_DEFAULTS:  # a table the medium fills with defaults
            if create:
                config[section] = table = {}
                return table, key
            return {}, key
        if section == "dye":
            raise MissingSpeciesError("dye", None, f"a [dye] table in the preset for the free parameter {self.name} "
                                                   "(weight_percent, fiber_density_g_per_cm3, spectrum_csv)")
        raise MissingSpeciesError(section, None, f"a [{section}] table in the preset for {self.name}")


def two_dye_table(config: Mapping, parameter: str) -> dict:
    """The ``[dye]`` table of ``config`` when it mixes two dyes (``spectrum_csv`` a list of two CSVs);
    MissingSpeciesError saying what to write otherwise."""
    table = config.get("dye")
    csvs = table.get("spectrum_csv") if isinstance(table, dict) else None
    if not (isinstance(csvs, list) and len(csvs) == 2):
        raise MissingSpeciesError("dye.spectrum_csv", csvs, f"two dye spectra for the free parameter {parameter} "
                                                            '(e.g. spectrum_csv = ["congo_red.csv", '
                                                            '"red_dye_band_model.csv"] in the [dye] table)')
    return table


def species_table(config: Mapping, species: str, parameter: str) -> dict:
    """The ``[[particles]]`` table of ``config`` named ``species``; MissingSpeciesError saying what to
    add when there is none."""
    for table in config.get("particles", []) or []:
        if isinstance(table, dict) and str(table.get("name")) == species:
            if "diameter_nm" not in table:
                raise MissingSpeciesError(f"particles[{species}].diameter_nm", None,
                                          f"a monodisperse species (diameter_nm) for the free parameter {parameter}; "
                                          "a log-normal one (median_diameter_nm) cannot be fitted yet")
            return table
    names = [str(t.get("name")) for t in config.get("particles", []) or [] if isinstance(t, dict)]
    template = _SPECIES_TEMPLATES.get(species, f'[[particles]]\nname = "{species}"\n…')
    raise MissingSpeciesError(f"particles[{species}]", None,
                              f"a particle species named {species!r} in the preset for the free parameter "
                              f"{parameter} (the preset has {names or 'none'}); add one to the preset TOML, e.g.\n"
                              f"{template}")



#: Every parameter a fit may free, by name.  The ranges (docs/fitting.md, "Parameters"):
PARAMETERS: dict[str, FitParameter] = {p.name: p for p in (
    FitParameter("void_fraction", f"particles[{VOIDS}].volume_fraction", "", 0.001, 0.55, log=True,
                 note="air in a yarn, from lumens and pores to the space between fibres (a spun yarn packs its "
                      "fibres to 0.4–0.6 of its volume); the medium allows "
                      f"(0, {MAX_VOLUME_FRACTION}) for all species together"),
    FitParameter("void_diameter_um", f"particles[{VOIDS}].diameter_nm", "µm", 0.2, 40.0, log=True, scale=1000.0,
                 note="sub-micron gaps to a fibre's lumen (~10 µm) and the gaps between fibres (of a cotton "
                      "fibre's 12–20 µm diameter and more); the medium allows "
                      f"{bounds.PARTICLE_DIAMETER_NM.low:g}–{bounds.PARTICLE_DIAMETER_NM.high:g} nm, and Mie "
                      "series grow with the size"),
    FitParameter("scatterer_fraction", f"particles[{SCATTERERS}].volume_fraction", "", 0.005, 0.4, log=True,
                 note="crystallites, wax and delustrant: the paper's 0.14 sits mid-range"),
    FitParameter("scatterer_diameter_nm", f"particles[{SCATTERERS}].diameter_nm", "nm", 30.0, 3000.0, log=True,
                 note="from Rayleigh-sized inclusions to a few µm; the paper's 150 nm sits low in it"),
    FitParameter("dye_weight_percent", "dye.weight_percent", "%", 0.1, 10.0, log=True,
                 note="the paper's 1–5 % (§6.2) widened by a factor of ten below and two above; the medium "
                      "allows [0, 100)"),
    FitParameter("dye_share", DYE_SHARE_PATH, "", 0.0, 1.0, log=False,
                 note="the second dye's share of the dye weight in a two-dye mixture: the hue between the two "
                      "dyes' (a dyer's recipe mixes dyes to a shade)"),
    FitParameter("host_absorption_per_mm", "host.absorption_per_mm", "1/mm", 0.01, 30.0, log=True,
                 note="grey absorption of the fibre itself (impurities, lignin, a shade of dark in the dyeing), "
                      "beside the dye's spectrum: 0.01 /mm is nothing across a 0.2 mm yarn, 30 /mm absorbs within "
                      "a fibre's 15 µm twice over"),
    FitParameter("fibre_fraction", "fibres.volume_fraction", "", 0.2, 0.8, log=False,
                 note="the share of a yarn's volume its fibres fill: 0.4–0.6 in spun yarns, less in a loose "
                      "or brushed one, more in a compacted one; the medium allows (0, 0.9)"),
    FitParameter("fibre_diameter_um", "fibres.diameter_um", "µm", 5.0, 40.0, log=True,
                 note="fine microfibres to coarse wool; cotton 12–20 µm"),
    FitParameter("fibre_absorption_per_mm", "fibres.absorption_per_mm", "1/mm", 0.01, 100.0, log=True,
                 note="grey absorption of the fibre material beside its dye: 100 /mm takes 1/e within 10 µm, a "
                      "fibre's width"),
    FitParameter("fibre_spread_deg", "fibres.orientation_spread_deg", "°", 0.0, 60.0, log=False,
                 note="with fibres along the yarn axis (fibres.orientation = \"yarn_axis\"): σ of their spread "
                      "about the twist's helix, from a combed, parallel yarn to a hairy, migrating one"),
    FitParameter("fibre_roughness_deg", "fibres.roughness_deg", "°", 0.0, 60.0, log=False,
                 note="with fibres along the yarn axis: σ of the blur of the light a fibre sends on, from a "
                      "smooth cylinder's cone (0) to an irregular, convoluted fibre's broad lobes"),
    FitParameter("twist_angle_deg", "yarn.twist_angle_deg", "°", 0.0, 45.0, log=False,
                 note="the surface fibres' helix angle: 0 is an untwisted yarn, 20–30° a cotton's, 45° a "
                      "hard-twisted crepe; with fibres along the yarn axis it sets their helices (the close-ups' "
                      "plies take it too)"),
    FitParameter("yarn_radius_mm", "yarn.radius_mm", "mm", 0.03, 0.5, log=True,
                 note="fine (Ne 100) to coarse (Ne 2) yarns after Peirce's d = 1/(28 √Ne) inch; the medium "
                      f"allows {bounds.YARN_RADIUS_MM.low:g}–{bounds.YARN_RADIUS_MM.high:g} mm"),
    FitParameter("specular_weight", "specular_weight", "", 0.0, 3.0, log=False,
                 note="the Cook–Torrance term's weight (shader default 1): 0 is no sheen"),
    FitParameter("specular_slope", "specular_slope", "", 0.05, 1.0, log=True,
                 note="the Beckmann rms slope m (the paper's 0.8): below 0.05 the lobe falls between the "
                      "measured views; 1.0 is the garment closure fit's largest gloss roughness"),
    FitParameter("fuzz_albedo", "fuzz_albedo", "", 0.0, 1.0, log=False,
                 note="the single-scattering albedo of the surface fibres' layer (the shader's FuzzAlbedo, "
                      "precompute.optics.lommel_seeliger; its green where it is tinted): 0 is none, 1 fibres "
                      "that absorb nothing (a layer of white fibres deep enough scatters most of its light "
                      "more than once, which one scattering at a higher albedo stands for)"),
    FitParameter("fuzz_depth", "fuzz_depth", "", 0.0, 2.0, log=False,
                 note="the optical depth of the surface fibres along the cloth normal (the shader's FuzzDepth, "
                      "precompute.optics.lommel_seeliger): they reflect as a layer that deep and shade the yarn "
                      "beneath by exp(−τ (1/μi + 1/μo)); 0 keeps the fuzz a veneer that shades nothing, 2 "
                      "hides the yarn from a normal view but for 2 %"),
    FitParameter("fuzz_asymmetry", "fuzz_asymmetry", "", -0.5, 0.9, log=False,
                 note="the Henyey–Greenstein g of the surface fibres' scattering (the shader's FuzzAsymmetry, "
                      "precompute.optics.lommel_seeliger): 0 is isotropic, the Lommel–Seeliger law; a fibre "
                      "scatters forward (its transmission lobe), 0.9 nearly all within 25° of straight on"),
    FitParameter("fuzz_tint_red", "fuzz_tint_red", "", 0.1, 10.0, log=True,
                 note="the fuzz's red albedo over its green (the shader's FuzzTint): 1 is white; dyed surface "
                      "fibres colour what they scatter, a red cotton's 3–5 times"),
    FitParameter("fuzz_tint_blue", "fuzz_tint_blue", "", 0.1, 10.0, log=True,
                 note="the fuzz's blue albedo over its green (the shader's FuzzTint): 1 is white"),
    FitParameter("fuzz_flatness", "fuzz_flatness", "", 0.0, 1.0, log=False,
                 note="the share of the surface fibres that lie in the cloth's plane (the shader's FuzzFlatness, "
                      "precompute.optics.lommel_seeliger.fuzz_projected_area), the rest in every direction: "
                      "0 is a layer that shows every direction the same area, 1 one that shows a grazing "
                      "direction 2/π of what it shows the normal (a felt, a brushed cloth)"),
)}


def parse_free(names: str | Iterable[str]) -> tuple[FitParameter, ...]:
    """The parameters named in ``names`` (a comma-separated string or a sequence), in that order;
    UnknownFitParameterError naming the allowed ones for any other name, ParameterError for none or
    a repeated one."""
    if isinstance(names, str):
        names = [name.strip() for name in names.split(",") if name.strip()]
    names = list(names)
    allowed = ", ".join(PARAMETERS)
    if not names:
        raise ParameterError("--free", "", f"one or more of {allowed}, comma-separated")
    chosen = []
    for name in names:
        if name not in PARAMETERS:
            raise UnknownFitParameterError("--free", name, f"one or more of {allowed}, comma-separated")
        if PARAMETERS[name] in chosen:
            raise ParameterError("--free", name, "each parameter once")
        chosen.append(PARAMETERS[name])
    return tuple(chosen)


def initial_values(free: Sequence[FitParameter], config: Mapping, specular: Mapping | None = None) -> dict[str, float]:
    """Each free parameter's value in ``config`` (and ``specular``), clipped to its fit range: where the
    optimiser starts.  MissingSpeciesError when the preset lacks what one sets."""
    return {p.name: min(max(p.get(config, specular), p.low), p.high) for p in free}


def apply(config: Mapping, specular: Mapping | None, values: Mapping[str, float]) -> tuple[dict, dict]:
    """A deep copy of ``config`` with the medium parameters of ``values`` set, and the specular
    keywords ``{"specular_weight", "specular_slope"}`` (those of ``specular`` or the shader's defaults,
    overridden by ``values``)."""
    new = copy.deepcopy(dict(config))
    keywords = {key: float((specular or {}).get(key, default)) for key, default in SPECULAR_DEFAULTS.items()}
    for name, value in values.items():
        parameter = PARAMETERS[name]
        if parameter.is_specular:
            keywords[parameter.path] = float(value)
        else:
            parameter.set(new, value)
    return new, keywords


def total_volume_fraction(config: Mapping) -> float:
    """The volume fractions of every particle species of ``config``, summed."""
    return float(sum(float(t.get("volume_fraction", 0.0)) for t in config.get("particles", []) or []
                     if isinstance(t, dict)))


__all__ = ["PARAMETERS", "SCATTERERS", "VOIDS", "FitParameter", "MissingSpeciesError",
           "UnknownFitParameterError", "apply", "initial_values", "parse_free", "species_table",
           "total_volume_fraction", "two_dye_table"]
