"""The cloth BSDF as tables: what the gonioreflectometer measured, in the yarn tables' layout.

Per side (``front``, ``back``; frames: :mod:`.goniometry`), in that side's frame and in the
self-describing OpenEXR conventions of docs/table-spec.md:

``<side>_brdf.exr``
    A BRDF atlas (incidence over the sphere × exit over the side's hemisphere) of the cloth's
    ρ = f |cos θ_i|, 1/sr, without the yarns' specular term: incidence from the side's own
    hemisphere is reflection, from the other one transmission through the cloth.  Read exactly
    like a yarn's (``cl_yarn_rho``), which holds the yarn's ρ without it too.
``<side>_specular_visibility.exr``
    The same atlas of the specular visibility V (grey, no unit): the fraction of the cloth where
    the yarns' specular term of §5.2 shines (yarn facing the sun, lit, seen).  That term is a
    Cook–Torrance lobe about the cloth normal, the same at every point of the cloth, so the cloth
    reflects ``weight`` f_CT(ω_i, ω_o) cos θ_i V(ω_i, ω_o) of it (:data:`SPECULAR_KEYS` in the
    summary): the shader evaluates f_CT exactly and reads only the smooth V from a table, where
    bilinear interpolation between the grid's cells would flatten the peak near grazing.

and for both sides together:

``lobes.exr``
    The general-lighting closure mixture: per view, the weights of :data:`GARMENT_LOBES`
    for each side's ρ (the gloss lobe from the specular term, :func:`gloss_weights`; the others
    fitted to the rest, :func:`precompute.tables.closure_fit.fit_closure_weights`), and the open
    weave, 1 − the fraction of the cloth hidden by yarn along the view, through which light
    passes unscattered (a transparent closure).  Laid out for a node-based material
    (:func:`lobe_image`): views on a square grid over the projected hemisphere, front side on top.

``summary.json`` (schema :data:`SUMMARY_SCHEMA`) says how they were made and holds the checks:
the energy balance per incidence cell and the fit errors.

The measurement is the paper's single-scattering model; the tables add the light scattered between
yarns to ρ (:func:`with_light_between_yarns`, :mod:`.between_yarns`), and the summary records it.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import pathlib
import time

import numpy as np

from ..weave import WeaveParameters
from . import between_yarns
from .goniometry import SIDES, side_to_world
from .response_measurement import yarn_lookup
from .traced_response import tracing_available, yarn_to_yarn_share

from precompute.tables import exr as precompute_tables
from precompute.tables import layout as table_layout
from precompute.tables import closure_fit, cycles_closures
from precompute.tables.grids import AngularGrid

SUMMARY_SCHEMA = "clothlight-cloth/3"
#: The garment material's closure mixture (names of precompute.tables.closure_fit lobes, in tile order).
#: Per view, a cloth's ρ falls more slowly with the incidence than a Lambertian lobe's cos θ_i (light
#: meets the yarns' sides) and rises toward the light (shadow hiding): with diffuse, translucent and
#: fibre transmission alone the mixture was 1.12–1.19 of voided_red_cotton's ρ at normal incidence and
#: 0.61–0.87 at 60°.  A uniform lobe (the same ρ at every incidence) and the yarn mixture's GGX
#: retro-reflection lobe follow both: against the cloth BSDF over the validation sweep, 16.2 % →
#: 6.0 % RGB (benchmarks/bench_garment_lobes.py).  The gloss lobe is the yarns' Cook–Torrance term
#: itself (:func:`gloss_weights`).
GARMENT_LOBES = ("diffuse", "uniform", "retroreflection", "translucent", "fibre_transmission", "gloss")
#: The garment mixture is fitted where ρ is large (precompute.tables.closure_fit.fit_closure_weights):
#: a garment under broad light reflects an integral of ρ.
FIT_WEIGHTING = "absolute"
#: The lobe that carries the specular term (the yarns' Cook–Torrance, whose Beckmann distribution it
#: shares), weighted from that term alone (:func:`gloss_weights`), and the other lobes fitted to ρ
#: without it: fitted among them to all of ρ, the white, narrow peak bent the coloured lobes
#: (voided_red_cotton's general mode vs the yarn sample over the validation sweep: 37.1 % → 21.2 % RGB, blue
#: 79.8 % → 41.6 %; docs/garment.md).
SPECULAR_LOBE = "gloss"
SUMMARY_FILE = "summary.json"
#: How far above 1 a cloth's reflected + transmitted + open share of the incident light may come before
#: it is refused: the yarn tables' Monte-Carlo error (a few % a cell) and the measurement's pixel sums.
ENERGY_TOLERANCE = 0.05
#: Tiles of ``lobes.exr``, left to right: the fitted lobes, then the open weave.
LOBE_TILES = (*GARMENT_LOBES, "open_weave")
#: Views per side of the lobe image's projected-hemisphere grid.
LOBE_GRID_RESOLUTION = 16
BRDF_FILES = {side: f"{side}_brdf.exr" for side in SIDES}
SPECULAR_VISIBILITY_FILES = {side: f"{side}_specular_visibility.exr" for side in SIDES}
#: The yarn material's specular parameters the summary records (``specular``): the term's weight,
#: the Beckmann rms slope m and the host's refractive index.
SPECULAR_KEYS = ("weight", "slope", "ior")
LOBE_FILE = "lobes.exr"
#: The weave detail texture (:mod:`.detail` renders it; RGBA, not a table).
DETAIL_FILE = "weave_detail.exr"
#: Every file of a cloth bake folder (``python -m clothlight.garment bake --out``).
CLOTH_FOLDER_FILES = (*BRDF_FILES.values(), *SPECULAR_VISIBILITY_FILES.values(), LOBE_FILE, DETAIL_FILE,
                      SUMMARY_FILE)
UNITS = {"rho": "1/sr (ρ = f |cos θ_i|: radiance per irradiance on a plane facing the sun)",
         "coverage": "fraction of the cloth's area hidden by yarn along the view",
         "specular_visibility": "fraction of the cloth's area where the yarns' specular term shines",
         "lengths": "mm", "angles": "unit vectors in the side's frame"}


def projected_view_grid(resolution: int) -> np.ndarray:
    """Views (resolution², 3) of the lobe image's grid, row-major from the top-left pixel: pixel
    (column i, row j) looks along ω with (ω_x, ω_y) = (−1 + 2i/(n − 1), 1 − 2j/(n − 1)), the
    hemisphere seen from above with its rim on the image's border; corners outside the unit
    disk are taken to the rim.  Pixel centres span the square edge to edge, so a lookup held
    between them (the material's mapping) never mixes tiles."""
    n = int(resolution)
    if n < 2:
        raise ValueError(f"a projected view grid needs ≥ 2 views per side, not {resolution}")
    line = np.linspace(-1.0, 1.0, n)
    x, y = np.meshgrid(line, -line)
    radius = np.hypot(x, y)
    scale = np.where(radius > 1.0, 1.0 / np.maximum(radius, 1e-12), 1.0)
    x, y = x * scale, y * scale
    z = np.sqrt(np.clip(1.0 - x * x - y * y, 0.0, 1.0))
    views = np.stack([x, y, np.maximum(z, 1e-3)], axis=-1).reshape(-1, 3)
    return views / np.linalg.norm(views, axis=-1, keepdims=True)


def lobe_image(tiles: dict) -> np.ndarray:
    """``tiles[side]`` (n², len(LOBE_TILES), 3) weights on :func:`projected_view_grid` → the
    image (2n, len(LOBE_TILES)·n, 3): tile k in column block k, front in the top row block."""
    blocks = []
    for side in SIDES:
        weights = np.asarray(tiles[side], float)
        n = int(round(math.sqrt(weights.shape[0])))
        k = weights.shape[1]
        blocks.append(weights.reshape(n, n, k, 3).transpose(0, 2, 1, 3).reshape(n, k * n, 3))
    return np.concatenate(blocks, axis=0)


def coverage_along(coverage: np.ndarray, views: np.ndarray) -> np.ndarray:
    """A side's per-exit-cell coverage (N_o²,) at ``views`` (…, 3) in its frame, interpolated
    between cell centres as a shader reads an exit tile."""
    coverage = np.asarray(coverage, float)
    tile = table_layout.lobe_atlas(coverage[:, None, None])
    return table_layout.interpolate_exit_tile(tile, views)[..., 0]


def energy_balance(rho: dict, coverage: dict, incidence_resolution: int, side: str = "front") -> dict:
    """Where the light arriving from each of ``side``'s incidence cells goes, per unit of
    incident flux: ``reflected`` (integral of ρ cos θ_o over the lit side's exits / |cos θ_i|),
    ``transmitted`` (the same over the other side's exits, read from that side's table as the
    shader reads it), ``open`` (1 − coverage along the light: the open weave), and ``total``;
    each (N_i², 3) (open: (N_i²,)), indexed by ``side``'s incidence cells (by default the front's:
    light from behind is in its lower cells, so every direction is checked once)."""
    n_i = incidence_resolution
    atlases = {side: table_layout.brdf_atlas(rho[side]) for side in SIDES}
    n_o = int(round(math.sqrt(rho["front"].shape[1])))
    exit_grid = AngularGrid("hemisphere", n_o)
    exits = exit_grid.cell_centers()
    weight = exits[:, 2] * exit_grid.cell_solid_angle
    incident = side_to_world(AngularGrid("sphere", n_i).cell_centers(), side)
    result = {"reflected": [], "transmitted": [], "open": [], "total": []}
    for direction in incident:
        lit = "front" if direction[2] > 0 else "back"
        dark = "back" if lit == "front" else "front"
        cos_i = abs(direction[2])
        parts = {}
        for name, exit_side in (("reflected", lit), ("transmitted", dark)):
            local = side_to_world(direction, exit_side)
            values = table_layout.interpolate_rho(atlases[exit_side], n_i, np.broadcast_to(local, exits.shape), exits)
            parts[name] = weight @ values / cos_i
        toward_light = side_to_world(direction, lit)
        parts["open"] = 1.0 - float(coverage_along(coverage[lit], toward_light))
        for name, value in parts.items():
            result[name].append(value)
        result["total"].append(parts["reflected"] + parts["transmitted"] + parts["open"])
    return {name: np.asarray(value) for name, value in result.items()}


def check_energy(energy: dict, incidence_resolution: int) -> None:
    """Refuse a cloth that sends more light away than it receives: ``energy`` (:func:`energy_balance`)
    whose total exceeds 1 + :data:`ENERGY_TOLERANCE` in any channel, from any incidence cell.  The
    cloth inherits its energy from the yarn tables it was measured with, so the fault is theirs:
    :class:`~precompute.tables.exr.TableError` (bad input, exit code 2)."""
    total = np.asarray(energy["total"], float)
    if np.all(total <= 1.0 + ENERGY_TOLERANCE):
        return
    worst = np.unravel_index(int(np.argmax(total)), total.shape)
    direction = side_to_world(AngularGrid("sphere", incidence_resolution).cell_centers(), "front")[worst[0]]
    raise precompute_tables.TableError(
        f"the yarn tables break energy conservation: the cloth measured with them reflects, transmits and lets "
        f"through {total[worst]:.4g} of the light arriving from {np.round(direction, 3).tolist()} (channel "
        f"{'RGB'[worst[1]]}), at most 1 + {ENERGY_TOLERANCE:g} allowed; were the tables' values scaled?")


def lost_to_yarns(weave: WeaveParameters | None) -> tuple[float, dict]:
    """q of ``weave`` (None: the validation weave) and how it was found: the path-traced share of the
    validation weave (:data:`.between_yarns.LOST_TO_YARNS`) times the ratio of the two weaves'
    geometric shares (:func:`.traced_response.yarn_to_yarn_share`); the validation weave's own where
    Embree is missing (it traces them)."""
    if weave is None or not tracing_available():
        return between_yarns.LOST_TO_YARNS, {"scaled_by_geometry": False}
    # The validation weave: WeaveParameters' defaults (its yarn counts do not matter here).
    shares = {"weave": yarn_to_yarn_share(weave), "validation_weave": yarn_to_yarn_share(WeaveParameters())}
    return between_yarns.LOST_TO_YARNS * shares["weave"] / shares["validation_weave"], {
        "scaled_by_geometry": True, "yarn_to_yarn_share": shares}


def with_light_between_yarns(measurement, yarn, weave: WeaveParameters | None = None) -> tuple:
    """``measurement`` (a :class:`.goniometry.ClothMeasurement`) with the light scattered between yarns
    added to ρ (:mod:`.between_yarns`: the single-scattering cloth's energy without its specular term
    times the gain of the yarn ``yarn``'s albedo, a :class:`.response_measurement.YarnLookup`, on
    ``weave``, :func:`lost_to_yarns`), and a record of it for the summary: the yarns' albedo under
    broad light, the weave's share lost to yarns, the gain, and the light between yarns at normal
    incidence (its energy per unit flux, and its ρ seen along the normal, 1/sr)."""
    n_i = int(round(math.sqrt(measurement.rho["front"].shape[0])))
    single = {side: np.maximum(measurement.rho[side] - measurement.specular[side][..., None], 0.0) for side in SIDES}
    escaped = {}
    for side in SIDES:
        balance = energy_balance(single, measurement.coverage, n_i, side)
        escaped[side] = balance["reflected"] + balance["transmitted"]
    albedo = between_yarns.broad_light_albedo(yarn)
    lost, how = lost_to_yarns(weave)
    gain = between_yarns.between_yarns_gain(albedo, lost)
    added = between_yarns.between_yarns_rho(escaped, gain, between_yarns.broad_light_shape(single), n_i)
    normal = int(np.argmax(AngularGrid("sphere", n_i).cell_centers()[:, 2]))
    up = np.array([0.0, 0.0, 1.0])
    record = {"yarn_albedo_broad_light_rgb": albedo.tolist(), "lost_to_yarns": lost, "lost_to_yarns_found": how,
              "gain_rgb": gain.tolist(),
              "normal_incidence_energy_rgb": (escaped["front"][normal] * gain).tolist(),
              "normal_incidence_and_view_rho_rgb":
                  table_layout.interpolate_rho(table_layout.brdf_atlas(added["front"]), n_i, up, up).tolist()}
    rho = {side: measurement.rho[side] + added[side] for side in SIDES}
    return dataclasses.replace(measurement, rho=rho), record


def mixture_weights(rho: np.ndarray, specular: np.ndarray, visibility: np.ndarray, specular_parameters: dict,
                    incidence_resolution: int, shape: closure_fit.LobeShape,
                    views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The general-lighting mixture of one side standing for all of ``rho`` (n_in, n_out, 3), 1/sr,
    whose ``specular`` term (n_in, n_out), 1/sr, of visibility ``visibility`` (n_in, n_out) and
    parameters ``specular_parameters`` (:data:`SPECULAR_KEYS`) is carried by :data:`SPECULAR_LOBE`
    alone (:func:`gloss_weights`): weights (n_views, len(GARMENT_LOBES), 3) at ``views``, and the
    mixture's relative error against ``rho`` (:func:`mixture_error`)."""
    specular = np.broadcast_to(np.asarray(specular, float)[..., None], rho.shape)
    weights = np.zeros((len(views), len(GARMENT_LOBES), rho.shape[-1]))
    others = tuple(k for k in GARMENT_LOBES if k != SPECULAR_LOBE)
    fitted, _ = closure_fit.fit_closure_weights(table_layout.brdf_atlas(np.maximum(rho - specular, 0.0)),
                                                incidence_resolution, shape, lobes=others, views=views,
                                                weighting=FIT_WEIGHTING)
    weights[:, [GARMENT_LOBES.index(k) for k in others]] = fitted
    weights[:, GARMENT_LOBES.index(SPECULAR_LOBE)] = gloss_weights(visibility, specular_parameters,
                                                                   incidence_resolution, views)[:, None]
    error = mixture_error(table_layout.brdf_atlas(rho), incidence_resolution, weights, shape, views,
                          specular_parameters["ior"])
    return weights, error


def gloss_weights(visibility: np.ndarray, specular_parameters: dict, incidence_resolution: int,
                  views: np.ndarray) -> np.ndarray:
    """The gloss lobe's weight (n_views,) at ``views`` (n_views, 3), the side's frame, standing for
    the specular term w_s f_CT(ω_i, ω_o) cos θ_i V(ω_i, ω_o) (``specular_parameters``: w_s, slope m,
    index n; ``visibility`` V (n_in, n_out)).  The lobe is f_CT cos θ_i itself, Fresnel included
    (:func:`garment_lobe_responses`); V is close to its value at the mirror direction where the lobe
    is, so the weight is w_s V(mirror of ω_o, ω_o).  A least-squares fit to the tabulated term cannot
    do this: cell centres 16–20° apart sample a peak a few degrees wide (voided_red_cotton's m = 0.094)
    anywhere from its top to nothing, view by view."""
    views = np.asarray(views, float)
    mirror = views * np.array([-1.0, -1.0, 1.0])
    v_at_mirror = table_layout.interpolate_rho(
        table_layout.brdf_atlas(np.asarray(visibility, float)[..., None]), incidence_resolution, mirror, views)[:, 0]
    return specular_parameters["weight"] * v_at_mirror


def garment_lobe_responses(view: np.ndarray, light: np.ndarray, shape: closure_fit.LobeShape,
                           ior: float) -> np.ndarray:
    """Cycles' response (…, len(GARMENT_LOBES)), 1/sr, of each of the garment's lobes
    (:func:`precompute.tables.closure_fit.lobe_responses`), the gloss lobe the Metallic BSDF of the
    yarns' index ``ior`` the material uses (``cycles_closures.beckmann_conductor_eval``): the
    Cook–Torrance term, whose Fresnel factor changes fast across a narrow lobe seen near grazing."""
    others = tuple(k for k in GARMENT_LOBES if k != SPECULAR_LOBE)
    response = np.zeros(np.shape(light)[:-1] + (len(GARMENT_LOBES),))
    response[..., [GARMENT_LOBES.index(k) for k in others]] = closure_fit.lobe_responses(view, light, shape, others)
    response[..., GARMENT_LOBES.index(SPECULAR_LOBE)] = cycles_closures.beckmann_conductor_eval(
        closure_fit.YARN_NORMAL, view, light, shape.gloss_alpha, ior)
    return response


def mixture_error(atlas: np.ndarray, incidence_resolution: int, weights: np.ndarray, shape: closure_fit.LobeShape,
                  views: np.ndarray, ior: float, subsamples: int = 3) -> np.ndarray:
    """The relative error (n_views, C) of the mixture ``weights`` (n_views, len(GARMENT_LOBES), C) of
    :func:`garment_lobe_responses` against ``atlas``, as
    :func:`precompute.tables.closure_fit.fit_closure_weights` measures its own fit's: RMS over the
    incidence samples of (mixture − ρ) / (ρ + mean ρ)."""
    grid = AngularGrid("sphere", incidence_resolution)
    light = closure_fit.incidence_samples(grid, subsamples)
    error = np.zeros((len(views), atlas.shape[2]))
    for exit_cell, view in enumerate(views):
        target = closure_fit.interpolate_rho(atlas, incidence_resolution, light, np.broadcast_to(view, light.shape))
        mixture = garment_lobe_responses(view, light, shape, ior) @ weights[exit_cell]
        error[exit_cell] = np.sqrt(np.mean(((mixture - target) / (target + target.mean(axis=0) + 1e-30)) ** 2, axis=0))
    return error


def write_cloth_tables(folder, measurement, settings, yarn_tables, *, cache_key: str, code_digest: str) -> dict:
    """Write the tables of a :class:`.goniometry.ClothMeasurement` of the yarn of ``yarn_tables`` (a
    :class:`clothlight.yarn_tables.YarnTableFiles`), with the light between yarns added, into
    ``folder`` (created) and its summary; returns the summary."""
    start = time.perf_counter()
    measurement, light_between_yarns = with_light_between_yarns(measurement, yarn_lookup(yarn_tables), settings.weave)
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    yarn = precompute_tables.read_table(yarn_tables.brdf_path, "brdf").metadata
    n_i, n_o = settings.incidence_resolution, settings.exit_resolution
    shape = closure_fit.LobeShape(gloss_alpha=float(measurement.specular_parameters["slope"]))
    header = {key: yarn[key] for key in precompute_tables.REQUIRED_METADATA if key not in ("cache_key",)}
    header.update(
        cache_key=cache_key,
        code_digest={"yarn": yarn.get("code_digest"), "cloth_tables": code_digest},
        yarn_cache_key=yarn["cache_key"],
        goniometer=settings.to_dict(),
        sample={"patch_mm": measurement.patch_mm, "size_mm": list(measurement.sample_size_mm),
                "half_thickness_mm": measurement.half_thickness_mm},
        units={**yarn["units"], **UNITS},
    )
    layout = {"incidence_resolution": n_i, "exit_resolution": n_o}
    views = projected_view_grid(LOBE_GRID_RESOLUTION)
    fit_error, tiles = {}, {}
    for side in SIDES:
        specular = measurement.specular[side][..., None]
        without_specular = np.maximum(measurement.rho[side] - specular, 0.0)
        precompute_tables.write_table(folder / BRDF_FILES[side], table_layout.brdf_atlas(without_specular),
                                      {**header, "side": side, "layout": layout, "table": "brdf"})
        visibility = np.repeat(measurement.specular_visibility[side][..., None], 3, axis=-1)
        precompute_tables.write_table(folder / SPECULAR_VISIBILITY_FILES[side], table_layout.brdf_atlas(visibility),
                                      {**header, "side": side, "layout": layout, "table": "brdf",
                                       "quantity": "specular visibility", "specular": measurement.specular_parameters})
        weights, error = mixture_weights(measurement.rho[side], measurement.specular[side],
                                         measurement.specular_visibility[side], measurement.specular_parameters,
                                         n_i, shape, views)
        fit_error[side] = np.median(error, axis=0).tolist()
        open_weave = 1.0 - coverage_along(measurement.coverage[side], views)
        tiles[side] = np.concatenate([weights, np.repeat(open_weave[:, None, None], 3, axis=-1)], axis=1)
    precompute_tables.write_table(
        folder / LOBE_FILE, lobe_image(tiles),
        {**header, "table": "cloth_lobes", "tiles": list(LOBE_TILES), "lobe_shape": shape.to_dict(),
         "layout": {"incidence_resolution": n_i, "exit_resolution": LOBE_GRID_RESOLUTION,
                    "lobe_count": len(LOBE_TILES), "views": "projected hemisphere, front rows on top"}})
    energy = energy_balance(measurement.rho, measurement.coverage, n_i)
    check_energy(energy, n_i)
    total = energy["total"]
    worst = np.unravel_index(int(np.argmax(total)), total.shape)
    summary = {
        **header,
        "schema": SUMMARY_SCHEMA,
        "table_schema": precompute_tables.SCHEMA,
        "files": {"brdf": BRDF_FILES, "specular_visibility": SPECULAR_VISIBILITY_FILES, "lobes": LOBE_FILE},
        "specular": {key: float(measurement.specular_parameters[key]) for key in SPECULAR_KEYS},
        "incidence_resolution": n_i,
        "exit_resolution": n_o,
        "lobe_tiles": list(LOBE_TILES),
        "lobe_grid_resolution": LOBE_GRID_RESOLUTION,
        "lobe_shape": shape.to_dict(),
        "closure_fit_relative_error_median_rgb": fit_error,
        "coverage_normal": {side: float(coverage_along(measurement.coverage[side], np.array([0.0, 0.0, 1.0])))
                            for side in SIDES},
        "light_between_yarns": light_between_yarns,
        "energy": {
            "max_total": float(total.max()),
            "worst_incidence_front_frame":
                side_to_world(AngularGrid("sphere", n_i).cell_centers(), "front")[worst[0]].tolist(),
            "per_incidence_total_rgb": total.tolist(),
            "per_incidence_open": energy["open"].tolist(),
        },
        "seconds": {"renders": measurement.render_seconds, "tables": time.perf_counter() - start},
    }
    write_cloth_summary(folder, summary)
    return summary


def write_cloth_summary(folder, summary: dict) -> None:
    """Write a cloth bake's ``summary.json`` with the SHA-256 of every file of the folder
    (``precompute.tables.folder.FILE_HASHES_KEY``), last."""
    from precompute.tables import folder as table_folder
    hashes = table_folder.file_hashes(folder, [name for name in CLOTH_FOLDER_FILES if name != SUMMARY_FILE])
    summary[table_folder.FILE_HASHES_KEY] = hashes
    (pathlib.Path(folder) / SUMMARY_FILE).write_text(json.dumps(summary, indent=1))


def check_cloth_table_folder(folder):
    """Check a cloth bake folder as a whole, as ``precompute.tables.folder`` checks a yarn's: its summary
    (this schema, measured from yarn tables of this table schema, these lobe tiles), every table read
    and validated against its kind, the summary's resolutions, side and quantity, and the bake's cache
    key, the weave detail texture, and every file's bytes against the summary's list.  Returns the
    ``CheckedFolder``; ``precompute.tables.exr.TableError`` naming the file and the reason otherwise."""
    from precompute.tables import folder as table_folder
    TableError = precompute_tables.TableError
    folder = pathlib.Path(folder).absolute()
    summary = table_folder.load_summary(folder, SUMMARY_SCHEMA, "bake the cloth again")
    summary_path = folder / SUMMARY_FILE
    if summary.get("table_schema") != precompute_tables.SCHEMA:
        # measured from yarn tables of another schema: what their ρ held differs (docs/table-spec.md)
        raise TableError(f"{summary_path}: measured from tables of schema {summary.get('table_schema')!r}, "
                         f"this ClothLight reads {precompute_tables.SCHEMA!r}: bake the cloth again")
    if summary.get("lobe_tiles") != list(LOBE_TILES):
        raise TableError(f"{summary_path}: lobe tiles {summary.get('lobe_tiles')}, this ClothLight reads "
                         f"{list(LOBE_TILES)}: bake the cloth again")
    grid = {key: table_folder.summary_integer(summary, key, folder)
            for key in ("incidence_resolution", "exit_resolution")}
    lobe_resolution = table_folder.summary_integer(summary, "lobe_grid_resolution", folder)
    lobe_shape = table_folder.summary_numbers(summary, "lobe_shape", folder)
    specular = summary.get("specular")
    if not isinstance(specular, dict):
        raise TableError(f"{summary_path}: specular {specular!r} is not an object")
    for key in SPECULAR_KEYS:
        table_folder.summary_number(specular, key, folder)
    Rule = table_folder.TableRule
    rules = {}
    for side in SIDES:
        rules[BRDF_FILES[side]] = Rule("brdf", grid, metadata={"side": side, "quantity": None})
        rules[SPECULAR_VISIBILITY_FILES[side]] = Rule("brdf", grid, metadata={"side": side,
                                                                              "quantity": "specular visibility"})
    rules[LOBE_FILE] = Rule("cloth_lobes", {"incidence_resolution": grid["incidence_resolution"],
                                            "exit_resolution": lobe_resolution, "lobe_count": len(LOBE_TILES)},
                            metadata={"tiles": list(LOBE_TILES), "lobe_shape": lobe_shape})
    other = {}
    detail = summary.get("weave_detail")
    if detail is not None:
        if not (isinstance(detail, dict) and detail.get("file") == DETAIL_FILE):
            raise TableError(f"{summary_path}: weave_detail {detail!r} does not describe {DETAIL_FILE}")
        other[DETAIL_FILE] = (True, lambda path, data: _check_weave_detail(path, data, detail))
    return table_folder.check_files(folder, summary, rules, other)


def _check_weave_detail(path: pathlib.Path, data: bytes, detail: dict) -> None:
    """The weave detail texture (:mod:`.detail`) is the one ``detail`` (the summary's
    ``weave_detail``) describes: RGBA float32 of its resolution, its header's description, values in
    [0, 1]."""
    TableError = precompute_tables.TableError
    import OpenEXR

    if data[:4] != precompute_tables.EXR_MAGIC:
        raise TableError(f"{path}: not an OpenEXR file")
    header = precompute_tables.exr_header(data, path)
    described = {key: value for key, value in detail.items() if key != "file"}
    try:
        own = json.loads(header["clothlight_weave_detail"])
    except (KeyError, TypeError, ValueError):
        raise TableError(f"{path}: not a ClothLight weave detail texture (no readable "
                         "'clothlight_weave_detail' header attribute)") from None
    if own != described:
        raise TableError(f"{path}: describes another weave detail than the folder's {SUMMARY_FILE}: not of this bake")
    resolution, coverage = described.get("resolution"), described.get("mean_coverage")
    if isinstance(resolution, bool) or not isinstance(resolution, int) or not 1 <= resolution <= 1 << 12:
        raise TableError(f"{path}: resolution {resolution!r} is not an integer in [1, 4096]")
    if isinstance(coverage, bool) or not isinstance(coverage, (int, float)) or not 0.0 <= coverage <= 1.0:
        raise TableError(f"{path}: mean coverage {coverage!r} is not a number in [0, 1]")
    if precompute_tables.data_window_shape(header) != (resolution, resolution):
        raise TableError(f"{path}: {precompute_tables.data_window_shape(header)} pixels, not {resolution}²")
    try:
        with OpenEXR.File(io.BytesIO(data)) as exr:
            channel = exr.channels()["RGBA"]
            pixel_type, pixels = channel.type(), np.array(channel.pixels)
    except Exception as exc:  # noqa: BLE001 - OpenEXR raises plain exceptions for truncated or corrupt files
        raise TableError(f"{path}: truncated or corrupt OpenEXR file, or not RGBA ({exc})") from None
    if pixel_type != OpenEXR.FLOAT or pixels.shape != (resolution, resolution, 4):
        raise TableError(f"{path}: {pixels.shape} {pixel_type} pixels, not RGBA float32 of {resolution}²")
    if not (np.all(np.isfinite(pixels)) and np.all((pixels >= -1e-6) & (pixels <= 1.0 + 1e-6))):
        raise TableError(f"{path}: holds values outside [0, 1]")
