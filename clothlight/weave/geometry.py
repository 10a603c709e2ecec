"""Woven yarn geometry: crimped centrelines swept into closed, watertight tubes, one per ply.

Layout (mm): the cloth lies in the x-y plane around the origin, its macroscopic normal is +z.
Warp ends run along +x; end ``j`` lies at y = (warp_count/2 − j − ½)·spacing, so seen from +z
with the warp pointing up the ends are numbered left to right.  Weft picks run along −y; pick
``i`` lies at x = (i + ½ − weft_count/2)·spacing, numbered from the bottom up.  A face-side
(+z) view therefore shows the drawdown as :mod:`.patterns` defines it.  An irregular sample
moves these places and the crossings' heights by its seeded jitters (:mod:`.layout`).

Each centreline is planar (see :mod:`.centerline`), so the sweep frame is exact and fixed: the
tangent T, a binormal B in the cloth plane that never changes (+y for warps, +x for wefts) and
the normal N = T × B, which tilts with the crimp but never rotates about the yarn axis.  A ring
vertex at angle φ sits at  centre + a·cos φ·B + b·sin φ·N  (semi-axes a, b: the ring's own where
the section relaxes between crossings, :mod:`.section`), so corresponding vertices of neighbouring
rings stay on the same side of the yarn: no twist, no seam.  A plied
yarn is one such tube per ply, its rings swept about the ply's helical centre in the same frame
(:mod:`.plies`); a single-ply yarn is the tube above.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .centerline import knot_height, ring_positions
from .irregularity import ply_radius_factors
from .layout import SampleLayout, sample_layout
from .params import WeaveParameters
from .plies import ply_rings
from .section import semi_axes_along


@dataclass(frozen=True, eq=False)
class WovenMesh:
    """Triangle mesh of a woven sample with the per-vertex data ClothLight's shaders read.

    Attributes
    ----------
    vertices
        (V, 3) float64, mm.
    faces
        (F, 3) vertex indices (int32; int64 past 2³¹ vertices), counter-clockwise seen from
        outside: normals point out.
    uv
        (V, 2) float64: u = arc length along the yarn's centreline from its start, mm (it grows
        along ``tangent``); v = angle around the cross-section / 2π in [0, 1): 0 on the +B side,
        0.25 on top (towards the cloth normal), 0.5 on the −B side, 0.75 underneath; around a
        ply of a plied yarn, from the ply's crest on (:func:`.plies.ply_rings`).  Cap centres
        carry v = 0.  Per face corner, with the seam closed, see :meth:`corner_uv`.
    tangent
        (V, 3) float64: unit axis of the vertex's tube at its ring: the yarn's centreline tangent,
        or, for a plied yarn, the ply's own helical axis (the cylinder the yarn shader sees).
    cloth_normal
        (V, 3) float64: the cloth's macroscopic normal, +z.
    yarn_id
        (V,) int32: warp ends 0 … warp_count − 1, then picks warp_count … warp_count + weft_count − 1.
    is_warp
        (V,) bool.
    ply_index
        (V,) int32: which ply of its yarn the vertex belongs to, 0 … ply_count − 1.
    yarn_faces
        (start, stop) face range of every yarn (all its plies), in yarn_id order.
    tube_faces
        (start, stop) face range of every closed tube: yarn by yarn, ply by ply within a yarn.
    centerlines
        Every yarn's centreline at its rings, (n, 3) mm, in yarn_id order.
    segments_around
        Vertices per ring.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    tangent: np.ndarray
    cloth_normal: np.ndarray
    yarn_id: np.ndarray
    is_warp: np.ndarray
    ply_index: np.ndarray
    yarn_faces: tuple[tuple[int, int], ...]
    tube_faces: tuple[tuple[int, int], ...]
    centerlines: tuple[np.ndarray, ...]
    segments_around: int

    def corner_uv(self) -> np.ndarray:
        """(F, 3, 2) UV per face corner; faces across the v seam get v = 1 instead of 0 where
        they close the ring, so v runs monotonically over every face (what a UV map needs)."""
        corners = self.uv[self.faces]
        v = corners[..., 1]
        last = (self.segments_around - 1) / self.segments_around
        v[(v == 0.0) & (v.max(axis=1, keepdims=True) >= last - 1e-12)] = 1.0
        return corners

    def edge_topology(self):
        """Edges (E, 2) of the whole mesh, each once, and the edge of every face corner (F, 3),
        corner k's edge joining it to corner k + 1: what Blender stores, without a search."""
        edges, corner_edges, templates = [], [], {}
        edge_offset = 0
        for start, stop in self.tube_faces:
            rings = (stop - start) // (2 * self.segments_around)
            if rings not in templates:
                templates[rings] = _tube_edges(rings, self.segments_around)
            tube_edges, tube_corners = templates[rings]
            edges.append(tube_edges + self.faces[start].min())   # a tube's first face starts at its first vertex
            corner_edges.append(tube_corners + edge_offset)
            edge_offset += len(tube_edges)
        index_type = self.faces.dtype
        return np.concatenate(edges).astype(index_type), np.concatenate(corner_edges).astype(index_type)

    def yarn_mesh(self, yarn: int):
        """One yarn as a ``trimesh.Trimesh`` (for checks and export)."""
        from .export import to_trimesh

        return to_trimesh(self, yarn)

    def to_trimesh(self):
        """The whole sample as one ``trimesh.Trimesh`` (vertices shared, nothing merged)."""
        from .export import to_trimesh

        return to_trimesh(self)


def _tube_faces(rings: int, around: int) -> np.ndarray:
    """Outward faces of one tube of ``rings`` rings: sides, then the start and end caps, whose
    centres are vertices rings·around and rings·around + 1."""
    i, m = np.meshgrid(np.arange(rings - 1), np.arange(around), indexing="ij")
    here, nxt = i * around + m, i * around + (m + 1) % around
    side = np.concatenate([np.stack([here, nxt, here + around], -1).reshape(-1, 3),
                           np.stack([nxt, nxt + around, here + around], -1).reshape(-1, 3)])
    m = np.arange(around)
    start = np.stack([np.full(around, rings * around), (m + 1) % around, m], -1)
    last = (rings - 1) * around
    end = np.stack([np.full(around, rings * around + 1), last + m, last + (m + 1) % around], -1)
    return np.concatenate([side, start, end])


def _tube_edges(rings: int, around: int):
    """Edges (E, 2) of one tube laid out as :func:`_tube_faces`, and the edge of every face
    corner (F, 3): corner k's edge joins it to corner k + 1 (Blender's ``corner_edge``)."""
    m = np.arange(around)
    ring = np.arange(rings)[:, None] * around + m                     # ring edge (i, k): k → k+1
    ring_edges = np.stack([ring, ring - m + (m + 1) % around], -1).reshape(-1, 2)
    lower = ring[:-1]
    along_edges = np.stack([lower, lower + around], -1).reshape(-1, 2)  # (i, k) → (i+1, k)
    diagonal_edges = np.stack([lower - m + (m + 1) % around, lower + around], -1).reshape(-1, 2)
    spokes = np.concatenate([np.stack([np.full(around, rings * around), m], -1),
                             np.stack([np.full(around, rings * around + 1), (rings - 1) * around + m], -1)])
    edges = np.concatenate([ring_edges, along_edges, diagonal_edges, spokes])
    n_ring, n_along = rings * around, (rings - 1) * around
    i, k = np.meshgrid(np.arange(rings - 1), m, indexing="ij")
    ring_id = lambda i, k: i * around + k % around                   # noqa: E731
    along_id = lambda i, k: n_ring + i * around + k % around         # noqa: E731
    diagonal_id = n_ring + n_along + i * around + k
    first = np.stack([ring_id(i, k), diagonal_id, along_id(i, k)], -1).reshape(-1, 3)
    second = np.stack([along_id(i, k + 1), ring_id(i + 1, k), diagonal_id], -1).reshape(-1, 3)
    spoke = n_ring + 2 * n_along
    start = np.stack([spoke + (m + 1) % around, ring_id(0, m), spoke + m], -1)
    end = np.stack([spoke + around + m, ring_id(rings - 1, m), spoke + around + (m + 1) % around], -1)
    return edges, np.concatenate([first, second, start, end])


def _family(params: WeaveParameters, layout: SampleLayout, warp: bool):
    """The tubes of all warps or all wefts: vertices (Y, P, n·around + 2, 3) of every ply of
    every yarn, centrelines (Y, n, 3), ply axes (Y, P, n, 3) and arc lengths (Y, n)."""
    knots = layout.weft_x if warp else layout.weft_knots
    heights = layout.warp_heights if warp else layout.weft_heights
    across = layout.warp_y if warp else layout.weft_x
    yarns = len(heights)
    s = ring_positions(knots, params.spacing_mm, params.segments_per_crossing)
    z, dz = knot_height(knots, heights, s)
    shape = z.shape
    if warp:
        center = np.stack([np.broadcast_to(s, shape), np.broadcast_to(across[:, None], shape), z], -1)
        tangent = np.stack([np.ones(shape), np.zeros(shape), dz], -1)
        binormal = np.array([0.0, 1.0, 0.0])
    else:
        center = np.stack([np.broadcast_to(across[:, None], shape), np.broadcast_to(-s, shape), z], -1)
        tangent = np.stack([np.zeros(shape), -np.ones(shape), dz], -1)
        binormal = np.array([1.0, 0.0, 0.0])
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    normal = np.cross(tangent, binormal)
    arc = np.concatenate([np.zeros((yarns, 1)),
                          np.cumsum(np.linalg.norm(np.diff(center, axis=1), axis=-1), axis=1)], axis=1)
    factors = ply_radius_factors(params.seed, params.warp_count, params.weft_count, params.ply_count,
                                 params.ply_radius_jitter)[0 if warp else 1]
    # a ply's radius blends between its crossings as the centreline's height does
    radius = knot_height(knots, factors, s)[0]
    section = semi_axes_along(knots, s, params.cross_section_mm, params.section_relaxation)
    rings, centres = ply_rings(center, binormal, normal, arc, section, params.ply_count,
                               params.twist_angle_deg, radius, params.segments_around)
    if params.ply_count == 1:
        axis = np.broadcast_to(tangent[:, None], centres.shape)
    else:
        axis = np.gradient(centres, axis=2)
        axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    plies = params.ply_count
    vertices = np.concatenate([rings.reshape(yarns, plies, -1, 3), centres[:, :, :1], centres[:, :, -1:]], axis=2)
    return vertices, center, axis, arc


def build_woven_mesh(params: WeaveParameters = WeaveParameters()) -> WovenMesh:
    """Sweep every ply of every warp and weft yarn of ``params`` into one mesh (layout: module
    docstring; plies: :mod:`.plies`; irregularity: :mod:`.irregularity`)."""
    around, plies = params.segments_around, params.ply_count
    layout = sample_layout(params)
    parts = [_family(params, layout, warp) for warp in (True, False)]
    per_tube = [part[0].shape[2] for part in parts]
    total = sum(part[0].shape[0] * plies * count for part, count in zip(parts, per_tube))
    index_type = np.int32 if total < 2**31 else np.int64
    vertices, faces, uv, tangent, ply_index, tube_faces, centerlines = [], [], [], [], [], [], []
    offset = face_offset = 0
    for (vertex, center, axis, arc), count in zip(parts, per_tube):
        yarns, rings = center.shape[:2]
        tubes = yarns * plies
        template = _tube_faces(rings, around).astype(index_type)
        starts = offset + count * np.arange(tubes, dtype=index_type)
        faces.append((template[None] + starts[:, None, None]).reshape(-1, 3))
        tube_faces += [(face_offset + n * len(template), face_offset + (n + 1) * len(template)) for n in range(tubes)]
        vertices.append(vertex.reshape(-1, 3))
        u = np.concatenate([np.repeat(arc, around, axis=1), arc[:, :1], arc[:, -1:]], axis=1)
        u = np.broadcast_to(u[:, None], (yarns, plies, count))
        v = np.concatenate([np.tile(np.arange(around) / around, rings), [0.0, 0.0]])
        uv.append(np.stack([u, np.broadcast_to(v, u.shape)], -1).reshape(-1, 2))
        ring_tangent = np.repeat(axis, around, axis=2)
        tangent.append(np.concatenate([ring_tangent, axis[:, :, :1], axis[:, :, -1:]], axis=2).reshape(-1, 3))
        ply = np.arange(plies, dtype=np.int32)[None, :, None]
        ply_index.append(np.broadcast_to(ply, (yarns, plies, count)).ravel())
        centerlines += list(center)
        offset += tubes * count
        face_offset += tubes * len(template)
    vertex_count = offset
    yarn_sizes = [part[0].shape[0] for part in parts]
    per_yarn = [plies * count for count in per_tube]
    return WovenMesh(
        vertices=np.concatenate(vertices),
        faces=np.concatenate(faces),
        uv=np.concatenate(uv),
        tangent=np.concatenate(tangent),
        cloth_normal=np.broadcast_to(np.array([0.0, 0.0, 1.0]), (vertex_count, 3)).copy(),
        yarn_id=np.repeat(np.arange(sum(yarn_sizes), dtype=np.int32),
                          np.repeat(per_yarn, yarn_sizes)),
        is_warp=np.repeat([True, False], [yarn_sizes[0] * per_yarn[0], yarn_sizes[1] * per_yarn[1]]),
        ply_index=np.concatenate(ply_index),
        yarn_faces=tuple((tube_faces[n * plies][0], tube_faces[n * plies + plies - 1][1])
                         for n in range(sum(yarn_sizes))),
        tube_faces=tuple(tube_faces),
        centerlines=tuple(centerlines),
        segments_around=around,
    )
