"""The cloth response traced without Blender: a new weave's response in seconds (issue 44).

:func:`clothlight.blender.garment.measure.measure_response` renders the response, two Cycles renders
a view, about an hour for the default gonioreflectometer.  What it takes of the renders is geometry
alone (:mod:`.response`): where each camera sample meets the woven sample, the sun-mode shader's
yarn frame there, and whether the region's sun reaches the point.  This module finds the same with
Intel Embree (``embreex``) on the same mesh (:func:`clothlight.weave.build_woven_mesh`, float32 as
Blender stores it), reproducing what the shader computes from Cycles' hit:

* the frame (``cl_yarn_frame``): the smooth normal, the corner-angle-weighted vertex normals
  interpolated over the triangle, and the ``yarn_tangent`` attribute interpolated the same way;
* the exit direction (``cl_exit_direction``), clamped onto the tables' hemisphere;
* the sun's shadow (``cl_sun_occluded``): a point facing away from the sun is first carried to
  where the ray leaves its own yarn, then any surface on the way blocks it;
* the region's sun, from the hit face's centre (:mod:`clothlight.blender.garment.measure`).

Camera samples are the render's: the views of :func:`.goniometry.view_of` with pixels square on
the cloth, one sample a pixel at a random place in it (NumPy's generator, seeded per view, so the
response is the same bit for bit whatever the threads), each pixel weighted by
:func:`.goniometry.patch_weights_at`.  Only the pixels that see a patch are traced.

A regular weave is periodic: its sample is traced as a tile of a few repeats, each ray moved by
whole periods into the tile's central cell (the same geometry, up to float rounding), so that
Embree's tree is built over 10⁵ triangles instead of the sample's 3.5 × 10⁶.  An irregular weave
is traced whole.  ``tests/test_traced_response.py`` checks the tile against the whole sample and
the response against Cycles' render of it.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from precompute.errors import ParameterError

from ..render_bounds import (
    DEFAULT_GONIO_EXIT_RESOLUTION,
    DEFAULT_GONIO_INCIDENCE_RESOLUTION,
    DEFAULT_GONIO_PIXELS_PER_PATCH,
)
from ..weave import WeaveParameters, build_woven_mesh
from .goniometry import (
    RAY_OFFSET_MM,
    SIDES,
    SamplePlan,
    exit_directions,
    incidence_directions,
    max_tilt,
    patch_pixels,
    patch_weights_at,
    plan_sample,
    view_of,
    woven_bounds,
)
from .response import GarmentResponse, ResponseView, view_samples

#: How far outside the slab a camera ray starts, mm.
ENTRY_MARGIN_MM = 0.01
#: Threads that trace the views: Embree releases the GIL, and each view is traced alone.
DEFAULT_THREADS = 2
#: Rays that :func:`yarn_to_yarn_share` casts: its share to ±0.002.
YARN_TO_YARN_RAYS = 100_000


def tracing_available() -> bool:
    """Whether Embree (``embreex``) imports in this Python: what tracing needs."""
    return importlib.util.find_spec("embreex") is not None


class WovenTracer:
    """Rays against a woven sample (:class:`SamplePlan` ``plan``'s weave), in the sample's frame:
    Embree's first hit, with the sun-mode shader's frame at it and the region's sun.  ``tile``:
    trace a periodic weave as a tile of it (module docstring); False traces the whole sample."""

    def __init__(self, plan: SamplePlan, incidence_resolution: int, exit_resolution: int, tile: bool = True):
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        weave = plan.weave
        sample = build_woven_mesh(weave)
        self.center, self.half_size = woven_bounds(sample.vertices)
        self.layout = dataclasses.replace(plan.layout, center=tuple(self.center))
        self.period = periodic_repeat_mm(weave) if tile else None
        traced = sample
        if self.period is not None:
            reach = (2.0 * plan.half_thickness_mm + ENTRY_MARGIN_MM) * max(
                max_tilt(directions(resolution, side)) for side in SIDES
                for directions, resolution in ((exit_directions, exit_resolution),
                                               (incidence_directions, incidence_resolution)))
            traced = build_woven_mesh(tile_of(weave, self.period, reach))
        vertices = np.asarray(traced.vertices, np.float32).astype(float)
        faces = traced.faces
        self.normals, self.face_normals = _smooth_normals(vertices, faces)
        self.tangents = np.asarray(traced.tangent, np.float32).astype(float)
        self.vertices, self.faces = vertices, faces
        self.face_yarn = np.repeat(np.arange(len(traced.yarn_faces)),
                                   [stop - start for start, stop in traced.yarn_faces])
        self.face_centers = vertices[faces].mean(axis=1)
        # The tile's centre is the sample's (both symmetric about their own, and the tile's yarn counts
        # differ from the sample's by whole repeats on each side).
        self.tile_center = woven_bounds(traced.vertices)[0]
        self.scene = rtcore_scene.EmbreeScene()
        TriangleMesh(self.scene, vertices[faces].astype(np.float32))
        self.incidence_resolution = incidence_resolution

    def _shift(self, points: np.ndarray) -> np.ndarray:
        """Whole periods (x, y) that carry ``points`` into the tile's central cell (zero when traced whole)."""
        if self.period is None:
            return np.zeros_like(points)
        shift = np.zeros_like(points)
        shift[:, :2] = self.period * np.round((points[:, :2] - self.tile_center[:2]) / self.period)
        return shift

    def first_hit(self, origins: np.ndarray, directions: np.ndarray):
        """(face, distance, u, v, shift) of each ray's first hit, face −1 for none; the face is the
        traced mesh's, found ``shift`` from the ray (add it to its points for the sample's)."""
        shift = self._shift(origins)
        hit = self.scene.run((origins - shift).astype(np.float32), directions.astype(np.float32), output=1)
        return hit["primID"].astype(np.int64), hit["tfar"].astype(float), hit["u"].astype(float), \
            hit["v"].astype(float), shift

    def sun_occluded(self, points: np.ndarray, geometric_normals: np.ndarray, suns: np.ndarray) -> np.ndarray:
        """``cl_sun_occluded``: whether another yarn hides the sun (directions ``suns``) from ``points``
        on faces of outward geometric normal ``geometric_normals``."""
        origins = points.copy()
        blocked = np.ones(len(points), bool)
        behind = np.einsum("sc,sc->s", geometric_normals, suns) < 0.0
        if np.any(behind):
            k = np.nonzero(behind)[0]
            face, distance, *_ = self.first_hit(points[k] + RAY_OFFSET_MM * suns[k], suns[k])
            # A ray that leaves no yarn (its own is open there) reaches the sun.
            left = face >= 0
            blocked[k[~left]] = False
            k = k[left]
            origins[k] = points[k] + (distance[left] + 2.0 * RAY_OFFSET_MM)[:, None] * suns[k]
        face, *_ = self.first_hit(origins + RAY_OFFSET_MM * suns, suns)
        return blocked & (face >= 0)


def periodic_repeat_mm(weave: WeaveParameters) -> float | None:
    """The period (mm, along x and y alike) by which ``weave``'s sample repeats, or None where it
    does not: an irregular weave or plies (whose twist runs on along the yarn)."""
    if weave.is_irregular or weave.ply_count > 1 or weave.ply_radius_jitter > 0:
        return None
    rows, columns = weave.interlacing.shape
    return math.lcm(rows, columns) * float(weave.spacing_mm)


def tile_of(weave: WeaveParameters, period_mm: float, reach_mm: float) -> WeaveParameters:
    """The smallest sample of ``weave`` that holds every ray starting in its central cell and crossing
    the slab (``reach_mm`` sideways at most), with a yarn's spacing to its ends; its yarn counts differ
    from ``weave``'s by whole periods on each side, so it is the sample's own centre."""
    per_period = int(round(period_mm / weave.spacing_mm))
    needed = 2.0 * (period_mm / 2.0 + reach_mm + weave.spacing_mm)
    periods = weave.warp_count // per_period
    fewest = int(math.ceil(needed / period_mm))
    # Remove an even number of periods, one from each side at a time.
    tile_periods = periods - 2 * ((periods - fewest) // 2)
    if tile_periods >= periods:
        return weave
    return dataclasses.replace(weave, warp_count=tile_periods * per_period, weft_count=tile_periods * per_period)


def _smooth_normals(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Blender's vertex normals (face normals weighted by the corner's angle) and the face normals."""
    corners = vertices[faces]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    face_normals /= np.linalg.norm(face_normals, axis=1, keepdims=True)
    normals = np.zeros_like(vertices)
    for corner in range(3):
        a = vertices[faces[:, (corner + 1) % 3]] - vertices[faces[:, corner]]
        b = vertices[faces[:, (corner + 2) % 3]] - vertices[faces[:, corner]]
        cos = np.einsum("fc,fc->f", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        angle = np.arccos(np.clip(cos, -1.0, 1.0))
        for axis in range(3):
            normals[:, axis] += np.bincount(faces[:, corner], face_normals[:, axis] * angle, len(vertices))
    return normals / np.linalg.norm(normals, axis=1, keepdims=True), face_normals


def trace_view(tracer: WovenTracer, side: str, exit_cell: int, exit_resolution: int, samples_per_side: int,
               seed) -> ResponseView:
    """The response's :class:`.response.ResponseView` of exit cell ``exit_cell`` of ``side``:
    what ``clothlight.blender.garment.measure._GoniometerScene.render_lookups`` renders."""
    layout, n_i = tracer.layout, tracer.incidence_resolution
    view = view_of(exit_directions(exit_resolution, side)[exit_cell], layout, samples_per_side,
                   pixels_square_on_cloth=True)
    rows, columns = patch_pixels(view, layout)
    index, weight = patch_weights_at(view, layout, rows, columns)
    in_patch = index >= 0
    rows, columns, index, weight = rows[in_patch], columns[in_patch], index[in_patch], weight[in_patch]
    jitter = np.random.default_rng(seed).random((2, len(rows)))
    toward_camera, right, up, center = (np.asarray(v, float) for v in (view.toward_camera, view.right, view.up,
                                                                      view.center))
    a = (columns + jitter[0] - view.width / 2.0) * view.pixel_mm
    b = (view.height / 2.0 - (rows + jitter[1])) * view.pixel_mm * view.aspect
    # Start each ray just outside the slab on the camera's side, where an orthographic camera's ray
    # has met nothing yet.
    on_image = center + a[:, None] * right + b[:, None] * up
    entry_z = center[2] + np.sign(toward_camera[2]) * (tracer.half_size[2] + ENTRY_MARGIN_MM)
    origins = on_image + ((entry_z - on_image[:, 2]) / toward_camera[2])[:, None] * toward_camera
    directions = np.broadcast_to(-toward_camera, origins.shape)
    face, distance, u, v, shift = tracer.first_hit(origins, directions)
    seen = face >= 0
    hit = np.nonzero(seen)[0]
    face, u, v = face[hit], u[hit], v[hit]
    barycentric = np.stack([1.0 - u - v, u, v], axis=-1)
    corners = tracer.faces[face]
    normal = np.einsum("sk,skc->sc", barycentric, tracer.normals[corners])
    z = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    tangent = np.einsum("sk,skc->sc", barycentric, tracer.tangents[corners])
    x = tangent - np.einsum("sc,sc->s", tangent, z)[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)

    def in_frame(d):
        return np.stack([np.einsum("sc,sc->s", d, axis) for axis in (x, y, z)], axis=-1)

    exit_direction = in_frame(np.broadcast_to(toward_camera, z.shape))
    exit_direction[:, 2] = np.maximum(exit_direction[:, 2], 0.0)
    exit_direction /= np.linalg.norm(exit_direction, axis=1, keepdims=True)
    region = layout.region_of((tracer.face_centers[face] + shift[hit])[:, :2])
    suns = incidence_directions(n_i, side)[np.where((region >= 0) & (region < n_i * n_i), region, 0)]
    points = origins[hit] + distance[hit, None] * directions[hit]
    lit = ~tracer.sun_occluded(points, tracer.face_normals[face], suns)
    incidence_lookup = np.zeros((len(rows), 4), np.float32)
    exit_lookup = np.zeros((len(rows), 4), np.float32)
    incidence_lookup[hit[lit], :3] = 0.5 + 0.5 * in_frame(suns)[lit]
    exit_lookup[hit, :3] = 0.5 + 0.5 * exit_direction
    return view_samples(side, exit_cell, incidence_lookup, exit_lookup, seen.astype(float), index, weight,
                        n_i * n_i)


def trace_response(weave: WeaveParameters, incidence_resolution: int, exit_resolution: int, *,
                   samples_per_side: int, pixels_per_patch: int, patch_repeats: int = 1, seed: int = 0,
                   threads: int = DEFAULT_THREADS,
                   progress: Callable[[int, int, str], None] | None = None) -> GarmentResponse:
    """The cloth response of ``weave`` traced (module docstring): the gonioreflectometer of
    N_i = ``incidence_resolution``, N_o = ``exit_resolution`` (its guards sized for
    ``pixels_per_patch`` pixels a patch, as the rendered measurement's) with ``samples_per_side``²
    camera samples a patch, the same views and patches as
    :func:`clothlight.blender.garment.measure.measure_response`.  ``seed`` picks the camera samples;
    ``progress(done, total, what)`` after every view."""
    if not (isinstance(samples_per_side, int) and samples_per_side >= 2):
        raise ParameterError("samples_per_side", samples_per_side, "an integer ≥ 2")
    start = time.perf_counter()
    plan = plan_sample(weave, incidence_resolution, exit_resolution, pixels_per_patch, patch_repeats)
    tracer = WovenTracer(plan, incidence_resolution, exit_resolution)
    views = [(side, cell) for side in SIDES for cell in range(exit_resolution**2)]
    with ThreadPoolExecutor(max(1, int(threads))) as pool:
        futures = [pool.submit(trace_view, tracer, side, cell, exit_resolution, samples_per_side, (seed, number))
                   for number, (side, cell) in enumerate(views)]
        traced = []
        try:
            # Progress from this thread, in order: a caller's callback may raise (a cancel) or print.
            for done, (future, (side, cell)) in enumerate(zip(futures, views), start=1):
                traced.append(future.result())
                if progress is not None:
                    progress(done, len(views), f"{side}: exit cell {cell + 1} of {exit_resolution**2}")
        except BaseException:
            for future in futures:
                future.cancel()
            raise
    shape = {"patch_mm": plan.patch_mm,
             "sample_size_mm": tuple(2.0 * float(h) for h in tracer.half_size[:2]),
             "half_thickness_mm": plan.half_thickness_mm}
    return GarmentResponse(traced, incidence_resolution, exit_resolution, shape,
                           {"samples_per_side": samples_per_side, "seed": seed,
                            "traced_seconds": time.perf_counter() - start})


def yarn_to_yarn_share(weave: WeaveParameters, rays: int = YARN_TO_YARN_RAYS, seed: int = 0) -> float:
    """The share of the light leaving ``weave``'s yarns that meets another yarn, as geometry alone
    has it: rays from points spread uniformly over the yarns' surface (one weave repeat of the
    default gonioreflectometer's tile), cosine-distributed about the smooth normal (a yarn's exit
    light under broad light), traced to their first hit.  The light between yarns scales the
    path-traced share of the validation weave by it (:func:`clothlight.garment.tables.lost_to_yarns`)."""
    if not (isinstance(rays, int) and rays > 0):
        raise ParameterError("rays", rays, "an integer > 0")
    plan = plan_sample(weave, DEFAULT_GONIO_INCIDENCE_RESOLUTION, DEFAULT_GONIO_EXIT_RESOLUTION,
                       DEFAULT_GONIO_PIXELS_PER_PATCH, 1)
    tracer = WovenTracer(plan, DEFAULT_GONIO_INCIDENCE_RESOLUTION, DEFAULT_GONIO_EXIT_RESOLUTION)
    # One weave repeat: the plan's patch (patch_repeats 1).
    offset = np.abs(tracer.face_centers[:, :2] - tracer.center[:2])
    faces = np.nonzero(np.all(offset < plan.patch_mm / 2.0, axis=1))[0]
    corners = tracer.vertices[tracer.faces[faces]]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    rng = np.random.default_rng(seed)
    face = faces[rng.choice(len(faces), rays, p=area / area.sum())]
    # Uniform over each triangle (square-root warp of the barycentrics), then cosine-weighted.
    root, along, radius, angle = np.sqrt(rng.random(rays)), rng.random(rays), np.sqrt(rng.random(rays)), \
        2.0 * np.pi * rng.random(rays)
    barycentric = np.stack([1.0 - root, root * (1.0 - along), root * along], axis=-1)
    points = np.einsum("sk,skc->sc", barycentric, tracer.vertices[tracer.faces[face]])
    normal = np.einsum("sk,skc->sc", barycentric, tracer.normals[tracer.faces[face]])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    first = np.cross(normal, helper)
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    second = np.cross(normal, first)
    directions = (radius * np.cos(angle))[:, None] * first + (radius * np.sin(angle))[:, None] * second \
        + np.sqrt(1.0 - radius**2)[:, None] * normal
    hit, *_ = tracer.first_hit(points + RAY_OFFSET_MM * directions, directions)
    other = (hit >= 0) & (tracer.face_yarn[np.maximum(hit, 0)] != tracer.face_yarn[face])
    return float(np.mean(other))
