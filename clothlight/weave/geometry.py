"""Woven yarn geometry: crimped centrelines swept into closed, watertight tubes.

Coordinates are millimetres; the cloth lies in the x-y plane with its macroscopic normal +z.
Warp yarns run along x, weft yarns along y.  A yarn's centreline passes ``crimp`` above the
mid-plane where it goes over a crossing and as far below where it goes under, blended between
neighbouring crossings by a half cosine (zero slope at every crossing, so the path is smooth).
Every centreline is planar, so the frame (tangent; ``binormal`` in the cloth plane; ``normal``
up) is exact and has no twist: there is no seam where the sweep would otherwise rotate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .params import WeaveParameters


@dataclass(frozen=True)
class WovenMesh:
    """Triangle mesh of a woven sample with the per-vertex data the shaders need.

    vertices (V, 3) mm; faces (F, 3) vertex indices, outward-facing;
    uv (V, 2): u = arc length along the yarn axis, mm; v = position around the circumference, [0, 1);
    tangent (V, 3): unit yarn axis; cloth_normal (V, 3): the cloth's macroscopic normal (+z);
    yarn_id (V,), is_warp (V,) per vertex; yarn_faces: (start, stop) face range of every yarn.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    tangent: np.ndarray
    cloth_normal: np.ndarray
    yarn_id: np.ndarray
    is_warp: np.ndarray
    yarn_faces: tuple[tuple[int, int], ...]
    centerlines: tuple[np.ndarray, ...]

    def yarn_mesh(self, yarn: int):
        """One yarn as a trimesh.Trimesh (for checks and export)."""
        import trimesh

        start, stop = self.yarn_faces[yarn]
        faces = self.faces[start:stop]
        used = np.unique(faces)
        remap = np.full(len(self.vertices), -1)
        remap[used] = np.arange(len(used))
        return trimesh.Trimesh(self.vertices[used], remap[faces], process=False)

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


def _crossing_signs(params: WeaveParameters, warp: bool, index: int) -> np.ndarray:
    """+1 where yarn ``index`` passes over its crossings, −1 under, along its length."""
    matrix = params.interlacing
    rows, cols = matrix.shape
    if warp:
        over = np.array([matrix[i % rows, index % cols] for i in range(params.weft_count)])
    else:
        over = ~np.array([matrix[index % rows, j % cols] for j in range(params.warp_count)])
    return np.where(over, 1.0, -1.0)


def _centerline(signs: np.ndarray, spacing: float, amplitude: float, segments: int):
    """Axial coordinate, height and slope of a crimped centreline over ``len(signs)`` crossings."""
    count = len(signs)
    start = -count * spacing / 2.0
    s = np.linspace(start, -start, count * segments + 1)
    crossing = (s - start) / spacing - 0.5  # crossing k sits at crossing == k
    k = np.clip(np.floor(crossing).astype(int), 0, max(count - 2, 0))
    t = np.clip(crossing - k, 0.0, 1.0)
    if count == 1:
        return s, np.full_like(s, amplitude * signs[0]), np.zeros_like(s)
    a, b = signs[k], signs[k + 1]
    height = amplitude * (0.5 * (a + b) + 0.5 * (a - b) * np.cos(np.pi * t))
    slope = amplitude * 0.5 * (a - b) * (-np.pi / spacing) * np.sin(np.pi * t)
    slope = np.where((crossing < 0) | (crossing > count - 1), 0.0, slope)
    return s, height, slope


def _tube(center, tangent, binormal, semi_axes, around):
    """Vertices, outward faces (with end caps) and per-vertex v of an elliptical tube."""
    n = len(center)
    normal = np.cross(tangent, binormal)
    phi = 2.0 * np.pi * np.arange(around) / around
    width, thickness = semi_axes
    ring = (center[:, None, :] + width * np.cos(phi)[None, :, None] * binormal[:, None, :]
            + thickness * np.sin(phi)[None, :, None] * normal[:, None, :])
    vertices = np.vstack([ring.reshape(-1, 3), center[0], center[-1]])
    i, m = np.meshgrid(np.arange(n - 1), np.arange(around), indexing="ij")
    here, nxt = i * around + m, i * around + (m + 1) % around
    up, up_next = here + around, nxt + around
    side = np.concatenate([np.stack([here, nxt, up], -1).reshape(-1, 3),
                           np.stack([nxt, up_next, up], -1).reshape(-1, 3)])
    first, last = n * around, n * around + 1
    m = np.arange(around)
    start_cap = np.stack([np.full(around, first), (m + 1) % around, m], -1)
    end_cap = np.stack([np.full(around, last), (n - 1) * around + m, (n - 1) * around + (m + 1) % around], -1)
    v = np.concatenate([np.tile(phi / (2.0 * np.pi), n), [0.0, 0.0]])
    return vertices, np.vstack([side, start_cap, end_cap]), v


def build_woven_mesh(params: WeaveParameters = WeaveParameters()) -> WovenMesh:
    """Sweep every warp and weft yarn of ``params`` into one mesh (see the module docstring)."""
    spacing, amplitude = params.spacing_mm, params.crimp_amplitude
    pieces = []
    offset = 0
    yarn_faces = []
    centerlines = []
    yarns = [(True, j) for j in range(params.warp_count)] + [(False, i) for i in range(params.weft_count)]
    for yarn_id, (warp, index) in enumerate(yarns):
        signs = _crossing_signs(params, warp, index)
        s, height, slope = _centerline(signs, spacing, amplitude, params.segments_per_crossing)
        across = (index + 0.5) * spacing - (params.warp_count if warp else params.weft_count) * spacing / 2.0
        if warp:
            center = np.stack([s, np.full_like(s, across), height], -1)
            tangent = np.stack([np.ones_like(s), np.zeros_like(s), slope], -1)
            binormal = np.tile([0.0, 1.0, 0.0], (len(s), 1))
        else:
            center = np.stack([np.full_like(s, across), s, height], -1)
            tangent = np.stack([np.zeros_like(s), np.ones_like(s), slope], -1)
            binormal = np.tile([-1.0, 0.0, 0.0], (len(s), 1))
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        vertices, faces, v = _tube(center, tangent, binormal, params.semi_axes_mm, params.segments_around)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(center, axis=0), axis=1))])
        u = np.concatenate([np.repeat(arc, params.segments_around), [arc[0], arc[-1]]])
        vertex_tangent = np.vstack([np.repeat(tangent, params.segments_around, axis=0), tangent[0], tangent[-1]])
        pieces.append((vertices, faces + offset, np.stack([u, v], -1), vertex_tangent, yarn_id, warp))
        start = sum(len(p[1]) for p in pieces[:-1])
        yarn_faces.append((start, start + len(faces)))
        centerlines.append(center)
        offset += len(vertices)
    vertices = np.vstack([p[0] for p in pieces])
    counts = [len(p[0]) for p in pieces]
    return WovenMesh(
        vertices=vertices,
        faces=np.vstack([p[1] for p in pieces]).astype(np.int64),
        uv=np.vstack([p[2] for p in pieces]),
        tangent=np.vstack([p[3] for p in pieces]),
        cloth_normal=np.tile([0.0, 0.0, 1.0], (len(vertices), 1)),
        yarn_id=np.repeat([p[4] for p in pieces], counts).astype(np.int32),
        is_warp=np.repeat([p[5] for p in pieces], counts).astype(bool),
        yarn_faces=tuple(yarn_faces),
        centerlines=tuple(centerlines),
    )


def minimum_clearance(mesh: WovenMesh, params: WeaveParameters) -> float:
    """Smallest distance between the centrelines of crossing yarns minus the sum of their
    half-thicknesses, mm: negative means the tubes intersect (exact for round yarns,
    conservative for elliptical ones, whose larger semi-axis is used)."""
    radius = max(params.semi_axes_mm)
    warps = mesh.centerlines[: params.warp_count]
    wefts = mesh.centerlines[params.warp_count:]
    worst = math.inf
    for warp in warps:
        for weft in wefts:
            # only the neighbourhood of their crossing can come close
            near_warp = warp[np.abs(warp[:, 0] - weft[0, 0]) < 1.5 * params.spacing_mm]
            near_weft = weft[np.abs(weft[:, 1] - warp[0, 1]) < 1.5 * params.spacing_mm]
            d = np.linalg.norm(near_warp[:, None, :] - near_weft[None, :, :], axis=-1).min()
            worst = min(worst, d - 2.0 * radius)
    return worst
