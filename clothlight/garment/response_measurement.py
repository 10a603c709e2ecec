"""A yarn's cloth measurement from the weave's cloth response: the cloth gonioreflectometer's
measurement as a linear map of the yarn tables, in seconds instead of an hour of renders (issue 44).

A patch's ρ is the weighted mean of what its camera samples emit (:func:`.goniometry.patch_rho`),
and a sample emits what the sun-mode shader reads of the yarn tables at its yarn-frame directions
(:mod:`.response`)::

    ρ_patch(ω_i, ω_o) = Σ_q w_q (ρ(ω_i,q, ω_o,q) + ρ_u(ω_i,q, ω_o,q)) / Σ_p w_p + w_s f_CT(ω_i, ω_o) cos θ_i V

over the patch's lit samples q, p all its samples (lit, shadowed or in a gap), w a sample's weight.
The shader reads ρ as a fixed blend of 16 atlas pixels (:func:`precompute.tables.layout.rho_taps`)
and ρ_u as a fixed blend of attenuation-table pixels
(:func:`precompute.optics.ballistic.unscattered_cone_weights`,
:func:`precompute.tables.layout.attenuation_taps`); the specular term is the Cook–Torrance lobe
(weight w_s) about the cloth normal on the viewer's side (§5.2, ``cl_cloth_specular``), the same at
every point of a patch, times V, the share of the patch where it shines (lit yarn facing the sun).
All three are linear in the tables and are evaluated here on the response's samples as the shader
evaluates them on a render's (``tests/test_garment_response_render.py`` holds the two together
sample by sample), so the measurement is the render-based one's estimate from other camera samples
(:func:`clothlight.blender.garment.measure.measure_cloth`, kept as its check).  No Blender.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError
from precompute.optics import ballistic
from precompute.optics.cook_torrance import DEFAULT_SLOPE, DEFAULT_WEIGHT, cook_torrance
from precompute.optics.cook_torrance import fuzz_tint
from precompute.optics.lommel_seeliger import fuzz_brdf, fuzz_transmittance
from precompute.tables import exr
from precompute.tables import layout as table_layout
from precompute.tables.grids import AngularGrid

from ..validation.response import TableLayout
from .goniometry import SIDES, ClothMeasurement
from .response import GarmentResponse, ResponseView

#: Threads that evaluate the views: NumPy's gathers and sums release the GIL, and each view is
#: evaluated alone and put in its place, so the result does not depend on the count.
DEFAULT_THREADS = 2


@dataclass(frozen=True)
class YarnLookup:
    """What the sun-mode yarn shader reads of a yarn's tables: the BRDF atlas (N_i·N_o, N_i·N_o, C)
    (``brdf.exr``), the unscattered light's attenuation (M, C) (``unscattered.exr``), their layout
    (grids, host index, the sun mode's cone) and the specular term's ``weight``, ``slope`` (Beckmann
    rms slope m) and ``ior``, as the shader's sockets hold them (float32), and its fuzz albedo, depth,
    asymmetry, tint and flatness (``FuzzAlbedo``, ``FuzzDepth``, ``FuzzAsymmetry``, ``FuzzTint`` RGB,
    ``FuzzFlatness``, :mod:`precompute.optics.lommel_seeliger`), part of ρ as the sun mode emits it."""

    atlas: np.ndarray
    attenuation: np.ndarray
    layout: TableLayout
    specular: dict
    fuzz_albedo: float = 0.0
    fuzz_depth: float = 0.0
    fuzz_asymmetry: float = 0.0
    fuzz_tint: tuple = (1.0, 1.0, 1.0)
    fuzz_flatness: float = 0.0


def yarn_lookup(tables) -> YarnLookup:
    """The :class:`YarnLookup` of a :class:`clothlight.yarn_tables.YarnTableFiles`, as the sun-mode
    material reads it (``clothlight.blender.materials``: the tables' host index as IOR, the bake's
    specular term, its index included, or the shader's defaults, the sun mode's unscattered cone)."""
    specular = tables.specular or {}
    attenuation = exr.read_table(tables.unscattered_path, "unscattered").pixels
    layout = TableLayout(tables.incidence_resolution, tables.exit_resolution, tables.unscattered_samples,
                         tables.host_index, ballistic.SUN_MODE_SPREAD_RAD)
    return YarnLookup(exr.read_table(tables.brdf_path, "brdf").pixels,
                      np.asarray(attenuation, float).reshape(-1, attenuation.shape[-1]), layout,
                      {"weight": _socket(specular.get("weight", DEFAULT_WEIGHT)),
                       "slope": _socket(specular.get("slope", DEFAULT_SLOPE)), "ior": _socket(tables.specular_index)},
                      _socket(specular.get("fuzz_albedo", 0.0)), _socket(specular.get("fuzz_depth", 0.0)),
                      _socket(specular.get("fuzz_asymmetry", 0.0)),
                      tuple(_socket(v) for v in fuzz_tint(specular)), _socket(specular.get("fuzz_flatness", 0.0)))


def _socket(value: float) -> float:
    """``value`` as a shader socket holds it (float32): both measurements record the same."""
    return float(np.float32(value))


def response_rho(response: GarmentResponse, yarn: YarnLookup, threads: int = DEFAULT_THREADS) -> dict:
    """ρ + ρ_u per side (N_i², N_o², C), 1/sr, without the specular term: the yarn tables looked up
    at every lit sample exactly as the shader reads them, weighted and summed per patch."""
    layout = yarn.layout
    side = layout.incidence_resolution * layout.exit_resolution
    atlas = np.asarray(yarn.atlas, float)
    if atlas.ndim != 3 or atlas.shape[:2] != (side, side):
        raise ParameterError("atlas", atlas.shape, f"({side}, {side}, C): the layout's atlas")
    pixels = atlas.reshape(side * side, -1)
    attenuation = np.asarray(yarn.attenuation, float)
    if attenuation.shape != (layout.unscattered_samples, pixels.shape[1]):
        raise ParameterError("attenuation", attenuation.shape,
                             f"({layout.unscattered_samples}, {pixels.shape[1]}): the layout's attenuation table")
    patches = response.incidence_resolution**2

    def one(view: ResponseView) -> np.ndarray:
        return _patch_rho(view, pixels, attenuation, layout, patches)

    with ThreadPoolExecutor(max(1, int(threads))) as pool:
        return response.per_side(list(pool.map(one, response.views)))


def _patch_rho(view: ResponseView, pixels: np.ndarray, attenuation: np.ndarray, layout: TableLayout,
               patches: int) -> np.ndarray:
    """ρ + ρ_u (N_i², C) of every patch of one view: each lit sample's lookups (``cl_yarn_rho`` and
    ``cl_unscattered_rho`` through their NumPy twins' taps), weighted and summed per patch over the
    patch's summed weight."""
    wi, wo = view.incidence.astype(float), view.exit.astype(float)
    index, taps = table_layout.rho_taps(layout.incidence_resolution, layout.exit_resolution, wi, wo)
    values = np.einsum("sk,skc->sc", taps, pixels[index])
    cone, length = ballistic.unscattered_cone_weights(wi, wo, layout.index, layout.unscattered_spread)
    # Outside its cone's cutoff a path adds exactly nothing (cl_unscattered_rho): only the few
    # (sample, path) pairs inside one are looked up.
    sample, path = np.nonzero(cone > 0.0)
    lower, fraction = table_layout.attenuation_taps(layout.unscattered_samples, length[sample, path])
    blend = (1.0 - fraction)[:, None] * attenuation[lower] + fraction[:, None] * attenuation[lower + 1]
    unscattered = cone[sample, path][:, None] * blend
    values += np.stack([np.bincount(sample, unscattered[:, c], len(wi)) for c in range(values.shape[1])], axis=-1)
    weight = view.weight.astype(float)
    summed = np.stack([np.bincount(view.patch, weight * values[:, c], patches) for c in range(values.shape[1])],
                      axis=-1)
    return summed / view.counted[:, None]


def _lit_facing_cells(response: GarmentResponse):
    """Per side, the share of each patch that is lit yarn facing the sun (N_i², N_o²) (ω_i·z > 0 in the
    yarn frame), and the cells' directions toward the sun (N_i², 1, 3) and the camera (1, N_o², 3), in
    each side's own frame, where the viewer's cloth normal is +z."""
    patches = response.incidence_resolution**2
    facing = response.per_side([np.bincount(v.patch, v.weight * (v.incidence[:, 2] > 0.0), patches) / v.counted
                                for v in response.views])
    toward_sun = AngularGrid("sphere", response.incidence_resolution).cell_centers()[:, None, :]
    toward_camera = AngularGrid("hemisphere", response.exit_resolution).cell_centers()[None, :, :]
    return facing, toward_sun, toward_camera


def response_specular(response: GarmentResponse, weight: float, slope: float, ior: float) -> tuple[dict, dict]:
    """The specular term's part of ρ per side (N_i², N_o²), 1/sr, and its visibility V (N_i², N_o²):
    ``weight`` f_CT(ω_i, ω_o) cos θ_i V about the cloth normal on the viewer's side (``cl_cloth_specular``),
    V the share of the patch that is lit yarn facing the sun (ω_i·z > 0 in the yarn frame), and none
    where the term itself is 0 (the sun on the other side: the shader marks nothing there)."""
    facing, toward_sun, toward_camera = _lit_facing_cells(response)
    f_cos = weight * cook_torrance(toward_sun, toward_camera, slope, ior) * np.maximum(toward_sun[..., 2], 0.0)
    visibility = {side: np.where(f_cos > 0.0, facing[side], 0.0) for side in SIDES}
    return {side: f_cos * visibility[side] for side in SIDES}, visibility


def response_fuzz(response: GarmentResponse, albedo: float, depth: float = 0.0, asymmetry: float = 0.0,
                  flatness: float = 0.0) -> dict:
    """The fuzz term's part of ρ per side (N_i², N_o²), 1/sr: f_fuzz(ω_i, ω_o) cos θ_i about the cloth
    normal on the viewer's side (``cl_cloth_fuzz``, a fuzz of optical depth ``depth``, asymmetry
    ``asymmetry`` and flatness ``flatness``) on the share of the patch that is lit yarn facing the sun,
    as for the specular term."""
    facing, toward_sun, toward_camera = _lit_facing_cells(response)
    f_cos = (fuzz_brdf(toward_sun, toward_camera, albedo, depth, asymmetry, flatness)
             * np.maximum(toward_sun[..., 2], 0.0))
    return {side: f_cos * facing[side] for side in SIDES}


def response_fuzz_transmittance(response: GarmentResponse, depth: float, flatness: float = 0.0) -> np.ndarray:
    """(N_i², N_o²) the share of the yarn's light that crosses a fuzz of optical depth ``depth`` and
    flatness ``flatness`` in and out about the cloth normal, as the sun mode shades the yarn's tables
    (either side alike)."""
    _, toward_sun, toward_camera = _lit_facing_cells(response)
    return fuzz_transmittance(toward_sun[..., 2], toward_camera[..., 2], depth, flatness)


def measurement_from_response(response: GarmentResponse, yarn: YarnLookup,
                              threads: int = DEFAULT_THREADS) -> ClothMeasurement:
    """The cloth measurement of the yarn ``yarn`` on ``response``'s weave: what
    ``clothlight.blender.garment.measure.measure_cloth`` renders, from the response's samples.
    Its ``render_seconds`` are the response's renders, once for every yarn (none where it was traced)."""
    rho = response_rho(response, yarn, threads)
    if yarn.fuzz_depth > 0.0:
        shade = response_fuzz_transmittance(response, yarn.fuzz_depth, yarn.fuzz_flatness)[..., None]
        rho = {side: rho[side] * shade for side in SIDES}
    if yarn.fuzz_albedo > 0.0:
        fuzz = response_fuzz(response, yarn.fuzz_albedo, yarn.fuzz_depth, yarn.fuzz_asymmetry, yarn.fuzz_flatness)
        rho = {side: rho[side] + fuzz[side][..., None] * np.asarray(yarn.fuzz_tint) for side in SIDES}
    specular, visibility = response_specular(response, **yarn.specular)
    return ClothMeasurement({side: rho[side] + specular[side][..., None] for side in SIDES}, specular, visibility,
                            dict(yarn.specular), response.coverage(), float(response.shape["patch_mm"]),
                            tuple(float(v) for v in response.shape["sample_size_mm"]),
                            float(response.shape["half_thickness_mm"]),
                            float(response.metadata.get("render_seconds", 0.0)))
