"""A shade recipe for a colour: how much red, blue and yellow dye gives cloth the colour asked for (issue 44).

The colour of cloth is the §6.1 swatch's, the paper's own (Table 1): the woven sample lit and seen
along its normal, as the cloth gonioreflectometer measures it (the forward model's front swatch,
:data:`.forward.SWATCH_VIEWS`), its reflectance factor R = π f in linear Rec.709 under D65, with
the specular component excluded, as textile colour is measured and matched (d/8° spectrophotometry
in SCE mode, e.g. AATCC EP6, ISO 105-J01): the sheen, white and the same for every dye, would add a
glint that only this exact geometry shows.  A picker's sRGB colour is compared with it in CIELAB by
CIEDE2000.

A recipe is K dye amounts w_k (% of fibre weight) and the fibre's own grey absorption a (1/mm, greige
to bleached).  Both only absorb (:func:`precompute.optics.medium.dye_mixture_spectrum`: μa = μa,clear
+ a + Σ_k ε_k w_k ρ_f / 10, the yarn's host's, or inside the fibres for fibres along the yarn axis:
``MediumParameters.dye_only_absorbs``), so one transport of the clear yarn (no dye, no absorption of its own),
its exits tallied at absorption steps up to every dye at :data:`MAX_DYE_PERCENT` and a at its most
at once, reads any recipe's ρ (:mod:`precompute.transport.absorption`;
:func:`.forward.absorption_series`), in milliseconds for the few cells of ρ the swatches read.  The
series is cached per base medium; the response that maps ρ to the swatch is the forward model's (a
few renders, cached).  The recipe minimises the CIELAB difference (trust-region least squares in
log w and log a from the nearest recipes of a coarse grid) and is reported with its CIEDE2000.

A colour the recipes cannot reach (lighter than the clear yarn's cloth, or more saturated than the
dyes make it) gets the nearest recipe, and the caller is told how far it stays
(:attr:`ShadeMatch.reached`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import pathlib
import time
from collections.abc import Callable, Sequence

import numpy as np

from precompute.cache.entries import cache_key, default_cache_dir, lookup, store
from precompute.cache.sources import stage_digest
from precompute.errors import ParameterError
from precompute.optics.coefficients import medium_optics
from precompute.optics.dye import dye_absorption_coefficient
from precompute.optics.medium import Dye, PRESET_DIR, dye_mixture_spectrum, medium_from_dict
from precompute.tables.color import delta_e_2000, linear_rgb_to_lab, srgb_to_linear_rgb
from precompute.tables.layout import atlas_pixel_cells

from . import forward

PROJECT_ROOT = pathlib.Path(__file__).resolve().parents[2]
#: The recipe's dyes, measured spectra of dyes that dye cotton directly (precompute/data: red, blue, yellow).
RECIPE_DYES = ("congo_red.csv", "evans_blue.csv", "curcumin.csv")
#: The most of each dye a recipe holds, % of fibre weight: deep shades on cotton take 4–6 % o.w.f.
MAX_DYE_PERCENT = 5.0
#: The least a recipe's dye is set to (a dye below it changes no colour by ΔE 0.1 on this yarn).
MIN_DYE_PERCENT = 1e-4
#: A match: CIEDE2000 at most this (issue 44): a difference hardly seen side by side.
MATCH_DELTA_E = 2.0
#: Relative error of the series' transport: a cloth swatch to about 1 % per channel.
SERIES_RELATIVE_ERROR = 0.02
SERIES_NAMESPACE = "shade_series"
SERIES_FILE = "series.npz"
#: The coarse grid the solve starts from, % of each dye: none, pale, deep (a decade apart).
GRID_PERCENT = (MIN_DYE_PERCENT, 0.05, 0.5)
#: The least-squares refinement's residual evaluations at most (each Jacobian takes K more).
REFINE_EVALUATIONS = 25
#: Grid recipes the refinement starts from, nearest first, until one reaches half :data:`MATCH_DELTA_E`.
REFINE_STARTS = 3
#: The most absorption of its own a recipe gives the fibre, 1/mm (greige cotton; more than any fitted preset's).
MAX_FIBRE_ABSORPTION_PER_MM = 2.0
#: Below this the fibre's absorption barely shows across a yarn: the log scale's floor, 1/mm.
FIBRE_ABSORPTION_FLOOR_PER_MM = 0.01
#: CIELAB units per e-fold of the fibre's absorption away from the preset's: a pull weak enough to
#: yield where the colour needs a lighter (bleached) or greyer fibre, strong enough to keep it otherwise.
FIBRE_PULL = 0.3
#: :func:`recipe_for_ratios`: CIELAB-like weight of a ratio's log error, and of the red's log distance
#: from the clear cloth's (the pull towards the lightest recipe that meets the ratios).
RATIO_WEIGHT = 10.0
LIGHTNESS_PULL = 0.3
#: Fibre density of a recipe on a preset without a [dye] table, g/cm³ (cotton, as the presets).
COTTON_DENSITY_G_PER_CM3 = 1.52


@dataclasses.dataclass(frozen=True)
class ShadeMatch:
    """A shade recipe and the colour it gives.

    ``recipe`` (K + 1,) % of fibre weight per dye of ``dyes``, then the fibre's own absorption, 1/mm
    (:func:`recipe_config`); ``cloth_rgb`` (3,) the swatch's
    reflectance factor, linear Rec.709; ``target_rgb`` (3,) the colour asked for, linear;
    ``delta_e`` CIEDE2000 between them; ``config`` the preset's TOML content with the recipe as its
    ``[dye]``; ``seconds`` the solve's wall time (the series and response not counted when cached)."""

    dyes: tuple[str, ...]
    recipe: np.ndarray
    cloth_rgb: np.ndarray
    target_rgb: np.ndarray
    delta_e: float
    evaluations: int
    seconds: float
    config: dict

    @property
    def reached(self) -> bool:
        return self.delta_e <= MATCH_DELTA_E


def parse_srgb(text: str, option: str = "--target") -> np.ndarray:
    """``#rrggbb`` / ``rrggbb`` or three comma-separated values in [0, 1] → sRGB (3,)."""
    value = str(text).strip()
    hex_digits = value[1:] if value.startswith("#") else value
    if len(hex_digits) == 6 and all(c in "0123456789abcdefABCDEF" for c in hex_digits):
        return np.array([int(hex_digits[i:i + 2], 16) / 255.0 for i in (0, 2, 4)])
    try:
        parts = [float(v) for v in value.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in parts):
        raise ParameterError(option, text, "an sRGB colour: #rrggbb, or three values in [0, 1] as R,G,B")
    return np.array(parts)


def grey_absorption_table(config: dict) -> str:
    """The table of a preset's TOML content ``config`` whose ``absorption_per_mm`` is the fibre's own
    grey absorption: ``fibres`` in a yarn of fibres, else the ``host`` (the fibre material as one medium)."""
    return "fibres" if "fibres" in config else "host"


def recipe_config(base: dict, recipe: Sequence[float], dyes: Sequence[str] = RECIPE_DYES) -> dict:
    """``base`` (a preset's TOML content) with a recipe: ``recipe`` (K + 1,) the % of fibre weight of
    each of the K ``dyes``, then the fibre's own absorption, 1/mm (:func:`grey_absorption_table`).  The
    dyes go into ``[dye]`` as the total and each one's share (precompute/optics/medium.py); a dye at
    no weight is left out."""
    recipe = np.asarray(recipe, float)
    if recipe.shape != (len(dyes) + 1,) or not np.all(np.isfinite(recipe)) or np.any(recipe < 0):
        raise ParameterError("recipe", recipe.tolist(), f"{len(dyes)} dye amounts (%) and the fibre's absorption "
                                                        "(1/mm), all finite and ≥ 0")
    percent = recipe[:-1]
    keep = [k for k in range(len(dyes)) if percent[k] > 0]
    if not keep:
        raise ParameterError("recipe", recipe.tolist(), "some dye (> 0 %)")
    total = float(percent[keep].sum())
    density = (base.get("dye") or {}).get("fiber_density_g_per_cm3", COTTON_DENSITY_G_PER_CM3)
    config = {key: value for key, value in base.items() if key != "dye"}
    grey = grey_absorption_table(base)
    config[grey] = {**base.get(grey, {}), "absorption_per_mm": float(recipe[-1])}
    config["dye"] = {"weight_percent": total, "fiber_density_g_per_cm3": density,
                     "spectrum_csv": [dyes[k] for k in keep],
                     "shares": [float(percent[k] / total) for k in keep]}
    return config


class ShadeModel:
    """The swatch colour of every recipe of ``dyes`` on ``base`` (a preset's TOML content, its own
    ``[dye]`` and fibre absorption replaced): ``model(recipe)`` → linear Rec.709 reflectance factor
    (3,) of the cloth lit and seen along its normal (:func:`recipe_config` for ``recipe``).

    ``progress(text)`` names each step that takes minutes the first time; ``building(done, total)``
    follows the swatch response's renders, which run inside ``while_building()`` (the command line
    holds a Ctrl-C there until a render ends, as the fit does: Blender drops one raised in a render)."""

    def __init__(self, base: dict, base_dir: pathlib.Path = PRESET_DIR, dyes: Sequence[str] = RECIPE_DYES, *,
                 cache_dir=None, seed: int = 0, threads: int | None = None,
                 progress: Callable[[str], None] | None = None, building: Callable[[int, int], None] | None = None,
                 while_building: Callable[[], contextlib.AbstractContextManager] = contextlib.nullcontext):
        from precompute.transport.absorption import reweighted_absorption

        self.base = {key: value for key, value in base.items() if key != "dye"}
        self.base_dir = pathlib.Path(base_dir)
        self.dyes = tuple(dyes)
        self.base_fibre_absorption = float(
            (self.base.get(grey_absorption_table(self.base)) or {}).get("absorption_per_mm", 0.0))
        self.max_fibre_absorption = max(MAX_FIBRE_ABSORPTION_PER_MM, self.base_fibre_absorption)
        clear = recipe_config(self.base, [1.0] * len(self.dyes) + [0.0], self.dyes)
        medium = medium_from_dict(clear, self.base_dir)
        if not medium.dye_only_absorbs:  # randomly oriented fibres: their dye changes how they scatter
            raise ParameterError("preset", medium.name, "a medium whose dye only absorbs: no [fibres], or fibres "
                                                        "along the yarn axis (a dye in random fibres changes how "
                                                        "they scatter, so a recipe would need a simulation each)")
        self.medium = medium.with_dye(0.0)  # the clear yarn: no dye, no absorption of its own
        self.cache_dir = pathlib.Path(cache_dir) if cache_dir is not None else default_cache_dir()
        self.seed = seed
        say = progress or (lambda text: None)
        say("cloth response of the swatches (rendered once, then cached)")
        with while_building():
            self.forward = forward.build_forward_model([], clear, self.base_dir, seed=seed, cache_dir=self.cache_dir,
                                                       threads=threads, progress=building)
        # dyes and the fibre's absorption only absorb: a recipe's optics are the clear yarn's with
        # their μa added (per dye at 1 %, per 1/mm of the fibre's), so a candidate needs no Mie again
        self.clear = medium_optics(self.medium)
        wavelengths = self.clear.wavelengths_nm
        fibre = medium_from_dict(recipe_config(self.base, [1.0] * len(self.dyes) + [1.0], self.dyes),
                                 self.base_dir).with_dye(0.0)  # the clear yarn's fibre absorbing 1 /mm
        self.mu_a_per_unit = np.stack([
            *(dye_absorption_coefficient(Dye(1.0, medium.dye.fiber_density_g_per_cm3,
                                             *dye_mixture_spectrum(name, None, self.base_dir)), wavelengths)
              for name in self.dyes),
            reweighted_absorption(medium_optics(fibre)) - reweighted_absorption(self.clear)])
        say("absorption series of the clear yarn (simulated once per medium, then cached)")
        self.series = self._series(threads)
        self.evaluations = 0
        self._cells_read = None  # the (incidence, exit) cells of ρ the swatches read, from the first evaluation

    def _series(self, threads):
        largest = np.array([MAX_DYE_PERCENT] * len(self.dyes) + [self.max_fibre_absorption])
        inputs = {"schema": "clothlight-shade-series/1", "medium": self.medium.to_dict(), "dyes": list(self.dyes),
                  "largest_recipe": largest.tolist(), "relative_error": SERIES_RELATIVE_ERROR, "seed": self.seed,
                  "transport": self.base.get("transport", {}),
                  "code_digest": stage_digest(PROJECT_ROOT, ["precompute.transport", "precompute.optics.coefficients"],
                                              ["clothlight/fit/forward.py"])}
        key = cache_key(inputs)
        folder = lookup(self.cache_dir, SERIES_NAMESPACE, key)
        if folder is None:
            def write(staging: pathlib.Path) -> None:
                from precompute.transport.absorption import reweighted_absorption

                most = reweighted_absorption(self.clear) + largest @ self.mu_a_per_unit
                reference_mu_a, steps, rho_steps, _ = forward.absorption_series(
                    self.base, self.medium, self.clear, most, relative_error=SERIES_RELATIVE_ERROR, seed=self.seed,
                    threads=threads)
                np.savez(staging / SERIES_FILE, reference_mu_a=reference_mu_a, steps=steps, rho_steps=rho_steps)

            folder, _ = store(self.cache_dir, SERIES_NAMESPACE, key, inputs, write)
        with np.load(folder / SERIES_FILE) as arrays:
            return arrays["reference_mu_a"], arrays["steps"], arrays["rho_steps"]

    def __call__(self, recipe: Sequence[float], *, exact: bool = False) -> np.ndarray:
        """The front swatch of a recipe (:meth:`swatches`)."""
        return self.swatches(recipe, exact=exact)[0]

    def swatches(self, recipe: Sequence[float], *, exact: bool = False) -> np.ndarray:
        """The §6.1 swatches of a recipe, (2, 3) linear Rec.709 reflectance factors π f, specular
        excluded: lit from the front, and from straight behind (what the cloth transmits), both seen
        along the normal.  ``exact``: the optics from the recipe's preset content as a bake reads it
        (the mixed spectrum, Mie included), not from the clear yarn's cached optics (the same to
        rounding; a check of the shortcut)."""
        from precompute.transport import YarnGeometry
        from precompute.transport.absorption import (interpolate_absorption, reweighted_absorption,
                                                     with_reweighted_absorption)

        config = recipe_config(self.base, recipe, self.dyes)
        if exact:
            optics = medium_optics(medium_from_dict(config, self.base_dir))
        else:
            optics = with_reweighted_absorption(
                self.clear, reweighted_absorption(self.clear) + np.asarray(recipe, float) @ self.mu_a_per_unit)
        reference_mu_a, steps, rho_steps = self.series
        if exact or self._cells_read is None:
            rho = interpolate_absorption(rho_steps, reference_mu_a, steps, reweighted_absorption(optics),
                                         optics.wavelengths_nm)
        else:  # the swatches read a few cells of ρ: reweight only those (the rest stay 0, unread)
            incidence, exit = self._cells_read
            rho = np.zeros(rho_steps.shape[:-1], rho_steps.dtype)
            rho[incidence, exit] = interpolate_absorption(rho_steps[incidence, exit], reference_mu_a, steps,
                                                          reweighted_absorption(optics), optics.wavelengths_nm)
        geometry = YarnGeometry(self.medium.yarn.radius_mm, optics.boundary_index)
        atlas, attenuation, layout = forward._candidate_tables(config, optics, geometry, rho)
        if self._cells_read is None:
            self._cells_read = atlas_pixel_cells(self.forward.response.atlas_pixels_read(layout),
                                                 layout.incidence_resolution, layout.exit_resolution)
        swatches = self.forward.cloth_brdf(atlas, attenuation, layout, specular_weight=0.0, specular_slope=1.0)
        self.evaluations += 1
        return math.pi * swatches[-self.forward.swatch_count:]


class _LogRecipe:
    """A recipe as the solves vary it: x = (log w_k, log(a + :data:`FIBRE_ABSORPTION_FLOOR_PER_MM`)),
    within the recipes ``model`` can read (``low``, ``high``)."""

    def __init__(self, model: ShadeModel):
        self.count = len(model.dyes)
        floor = FIBRE_ABSORPTION_FLOOR_PER_MM
        self.low = np.array([math.log(MIN_DYE_PERCENT)] * self.count + [math.log(floor)])
        self.high = np.array([math.log(MAX_DYE_PERCENT)] * self.count + [math.log(model.max_fibre_absorption + floor)])

    def recipe(self, x) -> np.ndarray:
        return np.array([*np.exp(x[:self.count]), max(math.exp(x[self.count]) - FIBRE_ABSORPTION_FLOOR_PER_MM, 0.0)])

    def point(self, recipe) -> np.ndarray:
        recipe = np.asarray(recipe, float)
        x = np.append(np.log(recipe[:self.count]), math.log(recipe[self.count] + FIBRE_ABSORPTION_FLOOR_PER_MM))
        return np.clip(x, self.low, self.high)


def match_colour(target_srgb, model: ShadeModel) -> ShadeMatch:
    """The recipe of ``model``'s dyes whose swatch is nearest ``target_srgb`` (sRGB, (3,) in [0, 1]):
    the nearest of a coarse grid of recipes (:data:`GRID_PERCENT` per dye, the fibre's absorption as
    the preset has it or none), refined by least squares on the CIELAB difference in log w and
    log(a + :data:`FIBRE_ABSORPTION_FLOOR_PER_MM`), with a weak pull of a towards the preset's own."""
    from scipy.optimize import least_squares

    target_rgb = srgb_to_linear_rgb(target_srgb)
    target_lab = linear_rgb_to_lab(target_rgb)
    start_time = time.perf_counter()
    start_evaluations = model.evaluations
    count = len(model.dyes)
    grid = np.array([(*dyes, fibre) for fibre in sorted({model.base_fibre_absorption, 0.0})
                     for dyes in itertools.product(GRID_PERCENT, repeat=count)])
    labs = linear_rgb_to_lab(np.array([model(recipe) for recipe in grid]))
    space = _LogRecipe(model)
    own = space.point([MIN_DYE_PERCENT] * count + [model.base_fibre_absorption])[count]

    def residual(x):
        return np.append(linear_rgb_to_lab(model(space.recipe(x))) - target_lab, FIBRE_PULL * (x[count] - own))

    best = None
    for start in grid[np.argsort(delta_e_2000(labs, target_lab))[:REFINE_STARTS]]:
        fit = least_squares(residual, space.point(start), bounds=(space.low, space.high), diff_step=1e-3, xtol=1e-4,
                            ftol=1e-6, max_nfev=REFINE_EVALUATIONS)
        delta = float(delta_e_2000(linear_rgb_to_lab(model(space.recipe(fit.x))), target_lab))
        if best is None or delta < best[1]:
            best = (space.recipe(fit.x), delta)
        if best[1] <= 0.5 * MATCH_DELTA_E:
            break
    recipe = best[0]
    unused = recipe[:count] <= 1.01 * MIN_DYE_PERCENT  # a dye at the floor is left out, unless every one is: a
    if not unused.all():  # recipe holds some dye (the nearest to a colour lighter than the clear cloth, the floor)
        recipe[:count] = np.where(unused, 0.0, recipe[:count])
    cloth = model(recipe, exact=True)
    return ShadeMatch(dyes=model.dyes, recipe=recipe, cloth_rgb=cloth, target_rgb=target_rgb,
                      delta_e=float(delta_e_2000(linear_rgb_to_lab(cloth), target_lab)),
                      evaluations=model.evaluations - start_evaluations,
                      seconds=time.perf_counter() - start_time,
                      config=recipe_config(model.base, recipe, model.dyes))


def recipe_for_ratios(blue_red: float, green_red: float, model: ShadeModel) -> np.ndarray:
    """The lightest recipe of ``model``'s dyes whose front swatch has the channel ratios B/R and G/R
    asked for (the paper's Table 1 gives a cloth's colour so, at normal light and view): the ratios
    met (:data:`RATIO_WEIGHT`), and of the recipes that meet them the one whose red stays nearest
    the clear cloth's (:data:`LIGHTNESS_PULL`), i.e. the least dye and fibre absorption."""
    from scipy.optimize import least_squares

    for name, value in (("B/R", blue_red), ("G/R", green_red)):
        if not (isinstance(value, (int, float)) and 0.0 < value < 1.0):
            raise ParameterError(name, value, "a ratio in (0, 1)")
    count = len(model.dyes)
    space = _LogRecipe(model)
    target = np.log([blue_red, green_red])
    clear_red = math.log(model([MIN_DYE_PERCENT] * count + [0.0])[0])

    def residual(x):
        front = model(space.recipe(x))
        ratios = np.log(np.maximum(front[[2, 1]], 1e-12) / front[0])
        return np.append(RATIO_WEIGHT * (ratios - target), LIGHTNESS_PULL * (math.log(front[0]) - clear_red))

    best = None
    for start in itertools.product((0.05, 0.5, 3.0), repeat=count):
        fit = least_squares(residual, space.point([*start, model.base_fibre_absorption]),
                            bounds=(space.low, space.high), max_nfev=REFINE_EVALUATIONS)
        if best is None or fit.cost < best.cost:
            best = fit
    return space.recipe(best.x)
