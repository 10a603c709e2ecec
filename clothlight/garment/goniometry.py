"""Where the cloth gonioreflectometer looks and how its pixels become a cloth BSDF (paper §7).

No Blender (NumPy, and the patch weights in numba: :mod:`.patch_lattice`).  The yarn-scale rig
(:mod:`clothlight.validation`) measures in the plane of incidence; a garment material needs the
cloth's whole BSDF: incidence over the sphere, views over both sides, azimuths included.  This
module lays that measurement out.

Frames.  The cloth lies in the x-y plane with its macroscopic normal +z and its warp along +x
(:mod:`clothlight.weave.geometry`).  The *front* frame is the world frame; the *back* frame is
the cloth seen from below, (x, −y, −z): a half-turn about the warp, so it stays right-handed and
the warp stays +x.  Each side's table is indexed like a yarn table (docs/table-spec.md), in
that side's frame: incidence over the sphere, exit over the side's hemisphere.

Many incidences per render.  A sun-mode ClothLight material emits ρ(ω_i, ω_o)·E for the sun
direction on its socket and traces its own shadow rays, so the sun can differ from face to face:
the sample is cut into a G × G grid of square *regions*, each lit from one incidence cell's
centre (a face attribute), and one orthographic camera per exit cell sees them all.  A region's
*patch* at its centre is a whole number of weave repeats, so its mean over any translate is
the cloth's mean; the band around it (the *guard*) holds the yarn surface that the patch's
pixels see when the view is tilted (within h·tan θ_v of the mid-plane point), lit by the same
sun.  Shadow rays only ask whether yarns block them, not what the blockers' sun is, so they may
cross region borders freely.

Calibration (the in-plane rig's, :mod:`clothlight.validation.measure`, generalised).  A pixel's
value is the mean radiance L_p over its square (Cycles' box filter of one pixel); the patch's
radiant intensity toward the camera is Σ_p w_p L_p s², with w_p the fraction of pixel p whose
rays cross the mid-plane inside the patch and s the pixel side.  A patch of area A with BSDF f
under a sun of irradiance E gives I = f E |cos θ_i| A |cos θ_v|, so the table's quantity, the
ρ of the yarn tables (L = ρ E, ρ = f |cos θ_i|), is

    ρ(ω_i, ω_o) = Σ_p w_p L_p s² / (E A |cos θ_v|) = Σ_p w_p L_p / (E Σ_p w_p)      [1/sr],

the second form because Σ_p w_p s² is the patch's projected area A |cos θ_v|: the weighted mean
radiance over the patch, which leaves the lattice's counting error at the patch's edges only to
second order.

Directions are unit 3-vectors; lengths are millimetres.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np


from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid

from ..weave import WeaveParameters, build_woven_mesh
from .patch_lattice import lattice_patch_counts

SIDES = ("front", "back")
#: Rotation taking a side's frame to the world: front = identity, back = half-turn about x.
SIDE_TO_WORLD = {"front": np.diag([1.0, 1.0, 1.0]), "back": np.diag([1.0, -1.0, -1.0])}
#: Sub-pixel lattice (per pixel side) on which the patch weights are counted.
WEIGHT_SUBSAMPLES = 4
#: How far from a surface the gonioreflectometer's rays start, mm (the shaders' ``ShadowMinDistance``,
#: the trace's offset).  The regions at the grid's edge lie 18–24 mm from the origin, where a float32
#: step is 2·10⁻⁶ mm: with the shaders' default 10⁻⁵ a shadow ray met the triangle next to its start
#: and the rendered response lost up to 5 % of the lit samples there (docs/garment.md).
RAY_OFFSET_MM = 1e-4


def side_to_world(directions, side: str) -> np.ndarray:
    """Directions (…, 3) given in ``side``'s frame, in the world (cloth) frame; its own inverse."""
    if side not in SIDES:
        raise ParameterError("side", side, f"one of {SIDES}")
    return np.asarray(directions, float) @ SIDE_TO_WORLD[side].T


def incidence_directions(incidence_resolution: int, side: str) -> np.ndarray:
    """World directions toward the sun (N_i², 3) at the centres of the side's incidence cells.

    An odd N_i keeps every centre off the cloth plane (the octahedral square's diagonal
    |u| + |v| = 1 falls between centres), where the sun would graze the slab forever."""
    return side_to_world(AngularGrid("sphere", incidence_resolution).cell_centers(), side)


def exit_directions(exit_resolution: int, side: str) -> np.ndarray:
    """World directions toward the camera (N_o², 3) at the centres of the side's exit cells."""
    return side_to_world(AngularGrid("hemisphere", exit_resolution).cell_centers(), side)


def max_tilt(directions) -> float:
    """tan of the largest zenith angle (from ±z) among ``directions``: how far a ray crossing a
    slab travels sideways per unit of thickness."""
    d = np.asarray(directions, float).reshape(-1, 3)
    cos = np.abs(d[:, 2])
    if cos.min() <= 0.0:
        raise ParameterError("directions", "a direction in the cloth plane", "directions off the cloth plane")
    return float(np.max(np.sqrt(1.0 - cos**2) / cos))


@dataclass(frozen=True)
class RegionLayout:
    """G × G square regions of pitch ``pitch_mm`` centred on ``center`` (x, y, mid-plane z), each
    with a centred square patch of side ``patch_mm``.  Region k = row·G + column, row 0 at −y."""

    grid: int
    pitch_mm: float
    patch_mm: float
    center: tuple[float, float, float]

    @property
    def half_extent_mm(self) -> float:
        return self.grid * self.pitch_mm / 2.0

    def region_centers(self) -> np.ndarray:
        """(G², 2) x, y of every region's centre, mm."""
        offsets = (np.arange(self.grid) + 0.5) * self.pitch_mm - self.half_extent_mm
        x, y = np.meshgrid(offsets + self.center[0], offsets + self.center[1])
        return np.stack([x.ravel(), y.ravel()], axis=-1)

    def region_of(self, xy) -> np.ndarray:
        """Region index of points (…, 2), or −1 outside the grid."""
        xy = np.asarray(xy, float)
        local = (xy - np.asarray(self.center[:2])) + self.half_extent_mm
        cell = np.floor(local / self.pitch_mm).astype(int)
        inside = np.all((cell >= 0) & (cell < self.grid), axis=-1)
        return np.where(inside, cell[..., 1] * self.grid + cell[..., 0], -1)

    def patch_of(self, xy) -> np.ndarray:
        """Index of the patch containing each point (…, 2), or −1 when in no patch."""
        # In pitches from the grid's corner, per axis: the region's cell and where in it.
        local = (np.asarray(xy, float) - np.asarray(self.center[:2])) / self.pitch_mm + self.grid / 2.0
        cell = np.floor(local)
        in_patch = np.abs(local - cell - 0.5) <= self.patch_mm / (2.0 * self.pitch_mm)
        inside = in_patch & (cell >= 0) & (cell < self.grid)
        return np.where(inside[..., 0] & inside[..., 1], cell[..., 1] * self.grid + cell[..., 0], -1).astype(int)


def plan_regions(count: int, patch_mm: float, half_thickness_mm: float, view_tilt: float,
                 margin_mm: float, center=(0.0, 0.0, 0.0)) -> RegionLayout:
    """The smallest square grid of at least ``count`` regions whose guards hold what the patch's
    pixels see: a guard of h·tan θ_v,max + ``margin_mm`` around every patch."""
    for name, value in (("patch_mm", patch_mm), ("half_thickness_mm", half_thickness_mm),
                        ("margin_mm", margin_mm), ("view_tilt", view_tilt)):
        if not (math.isfinite(value) and value >= 0.0) or (name == "patch_mm" and value == 0.0):
            raise ParameterError(name, value, "a finite value ≥ 0 (patch: > 0)")
    grid = math.ceil(math.sqrt(count))
    pitch = patch_mm + 2.0 * (half_thickness_mm * view_tilt + margin_mm)
    return RegionLayout(grid, pitch, patch_mm, tuple(float(c) for c in center))


def required_sample_half_size_mm(layout: RegionLayout, half_thickness_mm: float, view_tilt: float,
                                 light_tilt: float, edge_band_mm: float) -> float:
    """How far the sample must reach from the layout's centre so that neither a view ray through
    a patch nor a shadow ray from what it sees meets the sample's edge, mm (as
    :func:`clothlight.validation.framing.required_half_extent_mm`, in every azimuth)."""
    h = half_thickness_mm
    return layout.half_extent_mm + h * view_tilt + 2.0 * h * light_tilt + edge_band_mm


def woven_bounds(vertices) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half extents (3,) of a woven mesh's vertices as a Blender mesh holds them (float32), mm."""
    stored = np.asarray(vertices, np.float32)
    low, high = stored.min(axis=0).astype(float), stored.max(axis=0).astype(float)
    return (low + high) / 2.0, (high - low) / 2.0


@dataclass(frozen=True)
class SamplePlan:
    """The woven sample a gonioreflectometer sweep needs: ``weave`` with its yarn counts set, the
    regions' ``layout`` (centred at the origin: a scene centres it on its sample), the weave's half
    thickness, the patch side and how far the sample must reach from its centre, mm."""

    weave: WeaveParameters
    layout: RegionLayout
    half_thickness_mm: float
    patch_mm: float
    half_size_mm: float


def plan_sample(weave: WeaveParameters, incidence_resolution: int, exit_resolution: int, pixels_per_patch: int,
                patch_repeats: int) -> SamplePlan:
    """Regions for every incidence cell, guards for every view, and a sample that reaches past
    every view and shadow ray from them (:func:`plan_regions`, :func:`required_sample_half_size_mm`),
    for ``pixels_per_patch`` pixels across a patch's side at the most grazing view (the guards'
    margin is two of them)."""
    probe = build_woven_mesh(dataclasses.replace(weave, warp_count=4, weft_count=4))
    half_thickness = float(woven_bounds(probe.vertices)[1][2])
    spacing = float(weave.spacing_mm)
    repeat = max(weave.interlacing.shape) * spacing
    view_tilt = max(max_tilt(exit_directions(exit_resolution, side)) for side in SIDES)
    light_tilt = max(max_tilt(incidence_directions(incidence_resolution, side)) for side in SIDES)
    patch_mm = patch_repeats * repeat
    least_cos = min(abs(d[2]) for side in SIDES for d in exit_directions(exit_resolution, side))
    pixel_mm = patch_mm * least_cos / pixels_per_patch
    layout = plan_regions(incidence_resolution**2, patch_mm, half_thickness, view_tilt, margin_mm=2.0 * pixel_mm)
    half_size = required_sample_half_size_mm(layout, half_thickness, view_tilt, light_tilt, edge_band_mm=spacing)
    # Whole repeats keep the sample symmetric about its centre, where the layout is centred.
    yarns = int(math.ceil(2.0 * half_size / repeat)) * int(round(repeat / spacing))
    return SamplePlan(dataclasses.replace(weave, warp_count=yarns, weft_count=yarns), layout, half_thickness,
                      patch_mm, half_size)


@dataclass(frozen=True)
class OrthographicView:
    """An orthographic camera looking at ``center`` from ``toward_camera``: its image axes
    (``right``, ``up``, both unit and perpendicular to the view), pixel width ``pixel_mm`` (along
    ``right``) and height ``pixel_mm · aspect`` (along ``up``), and image size ``width`` × ``height``
    pixels.  ``up`` is the world +z projected onto the image plane (+y when looking along z), so
    the cloth's foreshortening runs along it."""

    toward_camera: tuple[float, float, float]
    center: tuple[float, float, float]
    right: tuple[float, float, float]
    up: tuple[float, float, float]
    pixel_mm: float
    width: int
    height: int
    aspect: float = 1.0

    @property
    def ortho_scale(self) -> float:
        """Blender's orthographic scale: the image's larger side, mm."""
        return max(self.pixel_mm * self.width, self.pixel_mm * self.aspect * self.height)

    @property
    def pixel_aspect(self) -> tuple[float, float]:
        """Blender's (pixel_aspect_x, pixel_aspect_y), each ≥ 1, of this view's pixels."""
        return (1.0 / self.aspect, 1.0) if self.aspect < 1.0 else (1.0, self.aspect)

    def camera_matrix(self, distance: float) -> np.ndarray:
        """The camera object's 4 × 4 world matrix at ``distance`` from the centre (Blender cameras
        look along local −z with local +y up)."""
        w = np.asarray(self.toward_camera)
        matrix = np.eye(4)
        matrix[:3, 0], matrix[:3, 1], matrix[:3, 2] = self.right, self.up, w
        matrix[:3, 3] = np.asarray(self.center) + distance * w
        return matrix

    def midplane_axes(self) -> tuple[np.ndarray, np.ndarray]:
        """The image axes ``right`` and ``up`` slid along the view onto the mid-plane: (2,) each, the
        x, y a unit step along them moves the point where a ray crosses the plane z = centre z."""
        w, r, u = (np.asarray(v, float) for v in (self.toward_camera, self.right, self.up))
        return r[:2] - r[2] / w[2] * w[:2], u[:2] - u[2] / w[2] * w[:2]

    def midplane_points(self, columns, rows) -> np.ndarray:
        """Where the rays through image points (``columns``, ``rows``: pixel units from the
        top-left corner, so pixel (i, j) has its centre at (i + ½, j + ½)) cross the plane z =
        centre z: (…, 2) x, y, mm."""
        c = np.asarray(self.center, float)
        a = (np.asarray(columns, float) - self.width / 2.0) * self.pixel_mm
        b = (self.height / 2.0 - np.asarray(rows, float)) * self.pixel_mm * self.aspect
        # The point c + a r + b u of the image plane slid along the view direction back to the
        # mid-plane: an affine map of (a, b), taken per coordinate so that a row of columns and a
        # column of rows broadcast to the image without (…, 3) temporaries.
        right, up = self.midplane_axes()
        x, y = (c[i] + a * right[i] + b * up[i] for i in range(2))
        return np.stack(np.broadcast_arrays(x, y), axis=-1)


def view_of(toward_camera, layout: RegionLayout, pixels_per_patch: int, *,
            pixels_square_on_cloth: bool = False) -> OrthographicView:
    """The camera that sees every region of ``layout`` from ``toward_camera`` with at least
    ``pixels_per_patch`` pixels across each patch's foreshortened side: square pixels, so that a
    grazing view has 1/cos θ_v times as many across the other side.  With ``pixels_square_on_cloth``
    the pixels are foreshortened as the cloth is (height = width · cos θ_v along ``up``): each one
    sees a square of side patch / ``pixels_per_patch`` on the cloth's mid-plane, the same in every
    view."""
    w = np.asarray(toward_camera, float)
    w = w / np.linalg.norm(w)
    if abs(w[2]) < 1e-6:
        raise ParameterError("toward_camera", tuple(w), "a view off the cloth plane")
    up = np.array([0.0, 0.0, 1.0]) - w[2] * w
    up = np.array([0.0, 1.0, 0.0]) if np.linalg.norm(up) < 1e-6 else up / np.linalg.norm(up)
    right = np.cross(up, w)
    height_mm = layout.patch_mm * abs(w[2]) / pixels_per_patch
    pixel, aspect = (layout.patch_mm / pixels_per_patch, abs(w[2])) if pixels_square_on_cloth else (height_mm, 1.0)
    half = layout.half_extent_mm
    corners = np.array([[sx * half, sy * half, 0.0] for sx in (-1, 1) for sy in (-1, 1)])
    width = 2.0 * np.max(np.abs(corners @ right)) / pixel
    height = 2.0 * np.max(np.abs(corners @ up)) / height_mm
    return OrthographicView(tuple(w), layout.center, tuple(right), tuple(up), float(pixel),
                            int(math.ceil(width)) + 2, int(math.ceil(height)) + 2, float(aspect))


def patch_weights(view: OrthographicView, layout: RegionLayout,
                  subsamples: int = WEIGHT_SUBSAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """Which patch each pixel sees and how much of it: (index, weight), both (height, width);
    index −1 where no patch is seen, weight the fraction of the pixel whose rays cross the
    mid-plane inside that patch, counted on a ``subsamples`` × ``subsamples`` lattice.

    Guards wider than a pixel keep any pixel from reaching two patches; ParameterError if not."""
    return patch_weights_at(view, layout, np.arange(view.height)[:, None], np.arange(view.width)[None, :],
                            subsamples)


def patch_weights_at(view: OrthographicView, layout: RegionLayout, rows, columns,
                     subsamples: int = WEIGHT_SUBSAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """:func:`patch_weights` of the pixels (``rows``, ``columns``), broadcast together: the same
    values, pixel by pixel, as the whole image's."""
    rows, columns = np.broadcast_arrays(np.asarray(rows), np.asarray(columns))
    right, up = view.midplane_axes()
    index, hits, two_patches = lattice_patch_counts(
        columns.ravel().astype(np.int64), rows.ravel().astype(np.int64), int(subsamples), view.width / 2.0,
        view.height / 2.0, float(view.pixel_mm), float(view.pixel_mm * view.aspect),
        np.asarray(view.center[:2], float), right, up, np.asarray(layout.center[:2], float), float(layout.pitch_mm),
        int(layout.grid), layout.patch_mm / (2.0 * layout.pitch_mm))
    if two_patches:
        raise ParameterError("layout", f"guard {layout.pitch_mm - layout.patch_mm:.3g} mm",
                             f"guards wider than a pixel ({view.pixel_mm:.3g} mm)")
    return index.reshape(rows.shape), (hits / subsamples**2).reshape(rows.shape)


def patch_pixels(view: OrthographicView, layout: RegionLayout) -> tuple[np.ndarray, np.ndarray]:
    """(rows, columns) of the pixels that see some patch of ``layout`` (and a few around them that
    do not): the patches' bounding boxes in the image, each pixel once, in row-major order."""
    # Image coordinates (column, row) of a mid-plane point, inverting the affine map of
    # OrthographicView.midplane_points.
    c = np.asarray(view.center, float)
    right, up = view.midplane_axes()
    to_image = np.linalg.inv(np.column_stack([right * view.pixel_mm, -up * view.pixel_mm * view.aspect]))
    half = layout.patch_mm / 2.0
    corners = layout.region_centers()[:, None, :] + half * np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]])
    image = (corners - c[:2]) @ to_image.T + np.array([view.width, view.height]) / 2.0
    low = np.clip(np.floor(image.min(axis=1)).astype(int) - 1, 0, None)
    high = np.minimum(np.ceil(image.max(axis=1)).astype(int) + 1, [view.width, view.height])
    flat = np.unique(np.concatenate([
        (np.arange(r0, r1)[:, None] * view.width + np.arange(c0, c1)[None, :]).ravel()
        for (c0, r0), (c1, r1) in zip(low, high)]))
    return flat // view.width, flat % view.width


def patch_rho(pixels: np.ndarray, index: np.ndarray, weight: np.ndarray, view: OrthographicView,
              layout: RegionLayout, sun_irradiance: float) -> tuple[np.ndarray, np.ndarray]:
    """ρ (G², C) of every patch from a render's linear ``pixels`` (H, W, C + alpha) and the
    :func:`patch_weights` of its view (module docstring), 1/sr; and every patch's coverage, the
    fraction of it hidden by yarn along the view (the mean film alpha over its projection)."""
    pixels = np.asarray(pixels, float)
    seen = index >= 0
    patches = index[seen]
    w = weight[seen]
    n = layout.grid**2
    # Σ_p w_p s² is the patch's projected area A |cos θ_v| up to the lattice's counting error at
    # its edges: dividing by the counted area instead leaves only second-order edge errors.
    counted = np.bincount(patches, w, n)
    if np.any(counted <= 0.0):
        raise ParameterError("view", view.toward_camera, "a view that sees every patch")
    rho = np.stack([np.bincount(patches, w * pixels[..., c][seen], n) for c in range(pixels.shape[-1] - 1)],
                   axis=-1) / counted[:, None] / sun_irradiance
    coverage = np.bincount(patches, w * pixels[..., -1][seen], n) / counted
    return rho, coverage


#: How the cloth BSDF is measured: read off the weave's cloth response (:mod:`.response`, the
#: default) or rendered with the yarn itself (``measure_cloth``, the response's check).
MEASUREMENT_METHODS = ("response", "render")


@dataclass
class ClothMeasurement:
    """What the cloth gonioreflectometer measures of a yarn on a weave (rendered, ``measure_cloth``, or
    from its response, :mod:`.response`): ρ per side (N_i², N_o², 3) in that side's frame, 1/sr, and
    the part of it that is the yarns' specular term (§5.2, about the cloth normal; (N_i², N_o²),
    grey); the specular visibility per side (N_i², N_o²), the fraction of the patch's projection
    where that term shines (yarn facing the sun, lit, seen); the coverage per side and exit cell
    (N_o²,), the fraction of the cloth hidden by yarn along that view; the yarn material's specular
    parameters (``weight``, ``slope`` m, ``ior``); the scene's patch side, sample size and half
    thickness, mm; and the seconds its renders took."""

    rho: dict
    specular: dict
    specular_visibility: dict
    specular_parameters: dict
    coverage: dict
    patch_mm: float
    sample_size_mm: tuple[float, float]
    half_thickness_mm: float
    render_seconds: float
