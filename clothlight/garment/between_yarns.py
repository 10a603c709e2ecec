"""Light scattered between yarns: what the cloth gonioreflectometer's single-scattering model leaves
out, put back into the cloth BSDF (issue 44).

The measurement (:mod:`.goniometry`, :mod:`.response_measurement`) is the paper's model (§7): a yarn
is lit by the sun alone, shadowed by other yarns, and the light it sends toward another yarn is
lost.  Per unit of flux from ω the yarns send E(ω) out of the cloth (the measurement's reflected +
transmitted energy, the specular term aside).  Of all the light yarns send away a share q meets
another yarn (:data:`LOST_TO_YARNS`), so E/(1 − q) left the yarns and E q/(1 − q) met others; that
is scattered again with the yarns' albedo under broad light a (:func:`broad_light_albedo`), a share
1 − q of it leaves, q meets a yarn again, and so on.  Summed over the generations the light
between yarns that leaves the cloth is

    E_between(ω) = E(ω) g,    g = a q / (1 − a q)

(a geometric series, as the multiple-scattering compensation of microfacet models sums the
bounces their single-scattering BRDF leaves out — Kulla & Conty 2017 — the weave in place of the
microsurface).  q is the weave's, measured once by path tracing (:data:`LOST_TO_YARNS`); a is the
yarn's, from its tables, so a new dye or medium gets its own light between yarns with no render.
The light leaves as the cloth sends light it receives from all around: its angular shape is the
single-scattering ρ under uniform light from both sides, the same for both sides' tables (after a
bounce inside the layer the light no longer knows the side it came from), normalised to unit
energy: ρ_between(ω_i, ω_o) = E_between(ω_i) |cos θ_i| s(ω_o), ∫ s cos θ_o dω_o = 1 over both
hemispheres (:func:`broad_light_shape`).

The check is the woven sample path-traced (``clothlight.blender.garment.path_traced``: the yarn's
general-lighting material, Cycles following light from yarn to yarn):
``python benchmarks/bench_cloth_energy.py`` (docs/garment.md, "Light between yarns").
"""

from __future__ import annotations

import numpy as np

from precompute.errors import ParameterError
from precompute.optics import ballistic
from precompute.tables import layout as table_layout
from precompute.tables.grids import AngularGrid

from .goniometry import SIDES

#: q: the share of the light that yarns send away that meets another yarn, on the validation weave
#: (plain, 0.1 mm yarns at 20 threads/cm).  Measured with the path-traced sample of ``voided_red_cotton``
#: at normal incidence, where its red gains G = 1.143 from light between yarns over the same
#: material without it: q = (G − 1) / (G a), a = 0.597 (``python benchmarks/bench_cloth_energy.py``
#: prints the q each run implies; the round-yarn white cotton of docs/garment.md, a = 0.49, is the
#: check).  Used for every density: how it changes with the weave is not measured.
LOST_TO_YARNS = 0.21
#: Points around a yarn's circumference in :func:`cylinder_albedo`'s integral.
ROUND_STEPS = 96
#: N of the sphere grid over which :func:`broad_light_albedo` averages.
BROAD_LIGHT_RESOLUTION = 11
#: How far above 1 a yarn's albedo may come out of its tables' quadrature before it is refused.
ALBEDO_TOLERANCE = 0.05


def yarn_exit_flux(atlas: np.ndarray, incidence_resolution: int) -> np.ndarray:
    """e(ω_i) = Σ_o ρ(ω_i, ω_o) cos θ_o Ω_o per incidence cell (N_i², C): the flux a point of the
    yarn's surface sends out per unit of the sun's irradiance (its exit cells' centres the
    quadrature).  ρ (1/sr, the atlas's) is the whole lit yarn's light leaving at the point, so the
    points whose local incidence is below their horizon (the yarn's dark side) send light too."""
    rho = table_layout.rho_from_brdf_atlas(np.asarray(atlas, float), incidence_resolution)
    n_o = int(round(np.sqrt(rho.shape[1])))
    exits = AngularGrid("hemisphere", n_o)
    return np.einsum("o,ioc->ic", exits.cell_centers()[:, 2] * exits.cell_solid_angle, rho)


def cylinder_albedo(yarn, cos_axis, steps: int = ROUND_STEPS) -> np.ndarray:
    """The yarn's albedo (…, C) under a sun at cos α = ``cos_axis`` (…) to its axis: the flux its
    whole surface sends out over the flux it intercepts (2R sin α per unit length and irradiance),

        A(α) = [∫ e(ω_i(φ)) dφ + ∫ cos θ_i(φ)⁺ u(ω_i(φ)) dφ] / (2 sin α),

    φ around the yarn, ω_i(φ) = (cos α, −sin α cos φ, sin α sin φ) the sun in the surface frame
    there (x along the axis, z the outward normal), e the scattered light's exit flux
    (:func:`yarn_exit_flux`, interpolated between incidence cells as the shader reads ρ) and u the
    share of the flux entering there that crosses the yarn unscattered
    (:func:`precompute.optics.ballistic.unscattered_radiance_factor`, by reciprocity).  A round yarn,
    as the yarn tables are made for (paper §4).  ``yarn``: a :class:`.response_measurement.YarnLookup`."""
    layout = yarn.layout
    n_i, n_o = layout.incidence_resolution, layout.exit_resolution
    flux = yarn_exit_flux(yarn.atlas, n_i)
    flat = table_layout.brdf_atlas(np.repeat(flux[:, None, :], n_o * n_o, axis=1))
    cos_axis = np.clip(np.asarray(cos_axis, float), -1.0, 1.0)
    sin_axis = np.sqrt(1.0 - cos_axis**2)
    phi = (np.arange(steps) + 0.5) * (2.0 * np.pi / steps)
    sun = np.stack(np.broadcast_arrays(cos_axis[..., None], -sin_axis[..., None] * np.cos(phi),
                                       sin_axis[..., None] * np.sin(phi)), axis=-1)
    scattered = table_layout.interpolate_rho(flat, n_i, sun, np.broadcast_to([0.0, 0.0, 1.0], sun.shape))
    attenuation = np.asarray(yarn.attenuation, float)
    crossing = ballistic.unscattered_radiance_factor(
        sun, layout.index, lambda length: table_layout.interpolate_attenuation(attenuation, length))
    sent = scattered + np.maximum(sun[..., 2:3], 0.0) * crossing
    return sent.sum(axis=-2) * (2.0 * np.pi / steps) / np.maximum(2.0 * sin_axis, 1e-12)[..., None]


def lit_yarn_albedo(yarn, directions) -> np.ndarray:
    """Ā(ω) (…, C) of the cloth's yarns for light from world ``directions`` (…, 3): the mean of
    :func:`cylinder_albedo` for the warp (along x) and the weft (along y), which take the light in
    equal shares in the plain weave's square repeat (the yarns' crimp left out)."""
    d = np.asarray(directions, float)
    return 0.5 * (cylinder_albedo(yarn, d[..., 0]) + cylinder_albedo(yarn, d[..., 1]))


def broad_light_albedo(yarn) -> np.ndarray:
    """a (C,): the yarns' albedo under light from all around, :func:`lit_yarn_albedo` over the
    sphere's incidence cells weighted by |cos θ| as irradiance from every direction weighs them."""
    directions = AngularGrid("sphere", BROAD_LIGHT_RESOLUTION).cell_centers()
    weight = np.abs(directions[:, 2])
    return weight @ lit_yarn_albedo(yarn, directions) / weight.sum()


def between_yarns_gain(albedo, lost_to_yarns: float = LOST_TO_YARNS) -> np.ndarray:
    """g = a q / (1 − a q) (module docstring): the light between yarns that leaves the cloth per
    unit of the single-scattering cloth's, for yarn albedo a under broad light and the weave's
    share q of yarn-scattered light that meets another yarn."""
    a = np.asarray(albedo, float)
    if not 0.0 <= lost_to_yarns < 1.0:
        raise ParameterError("lost_to_yarns", lost_to_yarns, "a share in [0, 1)")
    if np.any(a < 0.0) or np.any(a > 1.0 + ALBEDO_TOLERANCE):
        raise ParameterError("albedo", a.tolist(), f"yarn albedos in [0, 1 + {ALBEDO_TOLERANCE:g}]")
    bounced = np.minimum(a, 1.0) * lost_to_yarns
    return bounced / (1.0 - bounced)


def broad_light_shape(rho: dict) -> np.ndarray:
    """s(ω_o) (N_o², C), 1/sr: the single-scattering cloth's exit distribution under uniform light
    from both sides (ρ without its specular term summed over every incidence cell, the two sides'
    tables averaged), normalised so that both hemispheres together carry unit energy."""
    shape = 0.5 * sum(np.asarray(rho[side], float).sum(axis=0) for side in SIDES)
    n_o = int(round(np.sqrt(shape.shape[0])))
    exits = AngularGrid("hemisphere", n_o)
    energy = 2.0 * (exits.cell_centers()[:, 2] * exits.cell_solid_angle) @ shape
    return shape / np.where(energy > 0.0, energy, 1.0)


def between_yarns_rho(escaped: dict, gain: np.ndarray, shape: np.ndarray, incidence_resolution: int) -> dict:
    """ρ_between per side (N_i², N_o², C), 1/sr: E(ω_i) g |cos θ_i| s(ω_o) (module docstring).
    ``escaped``: per side (N_i², C), E for each of its incidence cells (its own frame;
    :func:`clothlight.garment.tables.energy_balance` with that side); ``gain`` (C,): g; ``shape``
    (N_o², C): s."""
    cos_i = np.abs(AngularGrid("sphere", incidence_resolution).cell_centers()[:, 2])
    return {side: (np.asarray(escaped[side], float) * np.asarray(gain, float) * cos_i[:, None])[:, None, :]
            * shape[None, :, :] for side in SIDES}
