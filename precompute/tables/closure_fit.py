"""A yarn BRDF as a mixture of Cycles closures, for rendering under arbitrary lighting.

Cycles' OSL supports only its built-in closures, so a shader cannot evaluate a
tabulated BRDF for the lights Cycles samples itself.  For each exit direction
ω_o the yarn BRDF ρ(·, ω_o) (``rho = L_o / E⊥``, 1/sr, over the full sphere of
incidence; docs/transport.md) is approximated by a non-negative combination of
five closures laid in the yarn frame (x = yarn axis, z = outward normal)::

    ρ(ω_i, ω_o) ≈ Σ_k w_k(ω_o) · f_k(ω_o, ω_i)

=====================  ==========================================  ==============================
lobe                   Cycles closure                              what it carries
=====================  ==========================================  ==============================
``diffuse``            ``diffuse(z)``                              light scattered many times, lit
                                                                   from the front
``translucent``        ``translucent(z)``                          the same, lit from behind
``fibre_reflection``   ``hair_reflection(z, r₁, r₂, x, 0)``        the fibre's specular cone
                                                                   (internal reflections of a
                                                                   cylinder keep the angle to its
                                                                   axis: ω_i·x = −ω_o·x)
``fibre_transmission`` ``hair_transmission(z, r₁, r₂, x, 0)``      light through the yarn, on the
                                                                   same cone, forward
``retroreflection``    ``microfacet("ggx", ω_o, α, ·, 0)``         back-scatter about the view
=====================  ==========================================  ==============================

f_k are Cycles' own responses (:mod:`precompute.tables.cycles_closures`, checked
against renders), so the weights ``w_k`` — one set per exit cell and colour
channel, stored as ``lobes.exr`` — are all the general-lighting shader needs.
The paper's medium makes a yarn of red light close to a glass rod (μ_t·R ≈ 0.16
at 700 nm), and the two fibre lobes are the shape such a rod gives its light;
the paper (§7) names general lighting and inter-reflection as its open limitation,
and this mixture is how ClothLight lifts it.

The weights are fitted to ρ *as the sun-mode shader reads it* (bilinear between
cell centres, :func:`precompute.tables.layout.interpolate_rho`) at sub-cell
sample directions, by non-negative least squares on the relative residual
``(fit − ρ) / (ρ + mean ρ)``: an absolute fit would spend everything on the
few cells of direct transmission, whose values are ~50× the rest.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import nnls

from precompute.tables import cycles_closures
from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import interpolate_rho

#: The lobes in the order of ``lobes.exr``'s tiles and of the shader's sum.
LOBES = ("diffuse", "translucent", "fibre_reflection", "fibre_transmission", "retroreflection")
#: A lobe whose weight (mean over channels) is below this share of the exit cell's mixture is left
#: out and the others refitted without it: each closure costs Cycles an evaluation per light
#: sample, and the fibre cones carry < 1 % of the red cotton's ρ in most exit cells.  The shader
#: adds no closure of zero weight.
MIN_LOBE_SHARE = 0.01
YARN_AXIS = np.array([1.0, 0.0, 0.0])
YARN_NORMAL = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class LobeShape:
    """Roughness of the shaped lobes, the same for every exit cell (shader parameters).

    Attributes
    ----------
    reflection_longitudinal, reflection_azimuthal
        ``hair_reflection`` roughness r₁ (Cauchy width of the half angle to the
        fibre's normal plane, radians) and r₂ (azimuthal, dimensionless); Cycles clamps
        both to ``cycles_closures.HAIR_ROUGHNESS_RANGE``, which every value must lie in.
    transmission_longitudinal, transmission_azimuthal
        The same for ``hair_transmission`` (r₂: Cauchy width about the forward
        azimuth, radians).
    retroreflection_alpha
        GGX α of the back-scatter lobe.
    gloss_alpha
        Beckmann α (rms slope) of the ``gloss`` lobe about the normal: not one of the yarn's
        :data:`LOBES`; the garment mixture's lobe for the yarns' Cook–Torrance term (§5.2), whose
        Beckmann distribution it shares: the cloth tables set the yarn material's slope m
        (default: the paper's 0.8).  With a GGX α = 0.5 instead the garment's general mode came
        to 28 % of the yarn sample on the validation sweep, with this 15 % (docs/garment.md).

    The defaults were chosen on the paper's red cotton: a coordinate search over
    r₁ ∈ {0.05, 0.1, 0.2}, r₂ ∈ {0.3, 0.6, 1.0}, α ∈ {0.1, 0.2, 0.4} minimised the
    fit's relative residual; then the transmission lobe was narrowed to the
    forward direction (r₁ 0.1 → 0.04, r₂ 1.0 → 0.06) until the general mode's red
    radiance lit from straight behind (the glow of §6.1, Figure 9b) came to 0.94
    of the sun mode's, from 0.07: the relative fit alone spends little on the few
    cells of direct transmission.  The validation sweep (lit from the front) did not
    move with it.
    """

    reflection_longitudinal: float = 0.05
    reflection_azimuthal: float = 0.3
    transmission_longitudinal: float = 0.04
    transmission_azimuthal: float = 0.06
    retroreflection_alpha: float = 0.4
    gloss_alpha: float = 0.8

    def __post_init__(self):
        low, high = cycles_closures.HAIR_ROUGHNESS_RANGE
        for name, value in asdict(self).items():
            if not (isinstance(value, (int, float)) and low <= value <= high):
                raise ParameterError(name, value, f"a roughness in [{low:g}, {high:g}]")

    def to_dict(self) -> dict:
        return asdict(self)


def lobe_responses(view: np.ndarray, light: np.ndarray, shape: LobeShape = LobeShape(),
                   lobes: tuple[str, ...] = LOBES) -> np.ndarray:
    """Cycles' response f_k(ω_o, ω_i) of each of ``lobes`` (names from :data:`LOBES`), 1/sr,
    shape (…, len(lobes)).

    ``view`` (3,) is ω_o and ``light`` (…, 3) the directions ω_i toward the
    light, both in the yarn frame.  Besides :data:`LOBES`, the garment mixture's ``uniform``
    (Cycles' diffuse toon of size 1: the same ρ at every incidence above the plane) and ``gloss``.
    """
    view = np.asarray(view, float)
    light = np.asarray(light, float)
    cc = cycles_closures
    response = {
        "diffuse": lambda: cc.diffuse_eval(YARN_NORMAL, light),
        "uniform": lambda: cc.uniform_eval(YARN_NORMAL, light),
        "translucent": lambda: cc.translucent_eval(YARN_NORMAL, light),
        "fibre_reflection": lambda: cc.hair_reflection_eval(YARN_NORMAL, YARN_AXIS, view, light,
                                                            shape.reflection_longitudinal,
                                                            shape.reflection_azimuthal),
        "fibre_transmission": lambda: cc.hair_transmission_eval(YARN_NORMAL, YARN_AXIS, view, light,
                                                                shape.transmission_longitudinal,
                                                                shape.transmission_azimuthal),
        "retroreflection": lambda: cc.ggx_reflection_eval(view, view, light, shape.retroreflection_alpha),
        "gloss": lambda: cc.beckmann_reflection_eval(YARN_NORMAL, view, light, shape.gloss_alpha),
    }
    unknown = [name for name in lobes if name not in response]
    if unknown or not lobes:
        raise ParameterError("lobes", lobes, f"names from {tuple(response)}")
    return np.stack([response[name]() for name in lobes], axis=-1)


def incidence_samples(grid: AngularGrid, subsamples: int) -> np.ndarray:
    """Directions (n_cells·subsamples², 3) on a ``subsamples × subsamples`` lattice inside every
    cell of the equal-area square of ``grid``: uniform in solid angle."""
    return grid.cell_samples(subsamples).reshape(-1, 3)


def fit_closure_weights(
    atlas: np.ndarray,
    incidence_resolution: int,
    shape: LobeShape = LobeShape(),
    subsamples: int = 3,
    lobes: tuple[str, ...] = LOBES,
    views: np.ndarray | None = None,
    weighting: str = "relative",
) -> tuple[np.ndarray, np.ndarray]:
    """Non-negative lobe weights per exit cell and channel, and the fit's relative error.

    Parameters
    ----------
    atlas
        A BRDF atlas (:func:`precompute.tables.layout.brdf_atlas`), 1/sr.
    incidence_resolution
        N_i of the atlas.
    shape
        Roughness of the shaped lobes.
    subsamples
        Incidence samples per cell side.
    lobes
        The lobes to fit (names from :data:`LOBES`, in the order of the result).
    views
        Exit directions (n, 3) to fit at; None: the centres of the atlas' exit cells.
    weighting
        What the least squares weigh: ``"relative"`` the residual over ρ + mean ρ (every
        incidence alike, dark ones included), ``"absolute"`` the residual itself (where ρ is
        large, as in the light a mixture reflects under broad lighting, an integral of ρ).

    Returns
    -------
    weights
        Shape (n_views, len(lobes), C), dimensionless (each lobe integrates to at
        most 1, so a weight is the lobe's albedo); lobes below ``MIN_LOBE_SHARE`` of a
        view's mixture are zero in every channel.
    relative_error
        Shape (n_views, C): RMS over the samples of ``(fit − ρ) / (ρ + mean ρ)``.
    """
    atlas = np.asarray(atlas, float)
    if atlas.ndim != 3 or atlas.shape[0] != atlas.shape[1] or atlas.shape[0] % incidence_resolution:
        raise ParameterError("atlas", atlas.shape, f"a square BRDF atlas of {incidence_resolution}² tiles")
    if not np.all(np.isfinite(atlas)) or atlas.min() < 0:
        raise ParameterError("atlas", "negative or non-finite values", "finite values ≥ 0")
    if views is None:
        views = AngularGrid("hemisphere", atlas.shape[0] // incidence_resolution).cell_centers()
    views = np.asarray(views, float).reshape(-1, 3)
    if weighting not in ("relative", "absolute"):
        raise ParameterError("weighting", weighting, "'relative' or 'absolute'")
    light = incidence_samples(AngularGrid("sphere", incidence_resolution), subsamples)
    channels = atlas.shape[2]
    weights = np.zeros((len(views), len(lobes), channels))
    relative_error = np.zeros((len(views), channels))
    for exit_cell, view in enumerate(views):
        target = interpolate_rho(atlas, incidence_resolution, light, np.broadcast_to(view, light.shape))
        design = lobe_responses(view, light, shape, lobes)
        relative = 1.0 / (target + target.mean(axis=0) + 1e-30)
        scale = relative if weighting == "relative" else np.ones_like(relative)

        def fit(kept):
            w = np.zeros((len(lobes), channels))
            for channel in range(channels):
                column = scale[:, channel]
                w[kept, channel], _ = nnls(design[:, kept] * column[:, None], target[:, channel] * column)
            return w

        w = fit(np.arange(len(lobes)))
        minor = w.mean(axis=1) < MIN_LOBE_SHARE * w.mean(axis=1).sum()
        if minor.any() and not minor.all():
            w = fit(np.flatnonzero(~minor))
        weights[exit_cell] = w
        relative_error[exit_cell] = np.sqrt(np.mean(((design @ w - target) * relative) ** 2, axis=0))
    return weights, relative_error


def evaluate_closure_mixture(weights: np.ndarray, view: np.ndarray, light: np.ndarray,
                             shape: LobeShape = LobeShape(), lobes: tuple[str, ...] = LOBES) -> np.ndarray:
    """ρ rebuilt from one exit cell's ``weights`` (len(lobes), C) for ``light`` (…, 3): (…, C)."""
    return lobe_responses(view, light, shape, lobes) @ np.asarray(weights, float)
