"""How long one UV unit of a garment mesh is on the cloth: the weave's scale on a garment.

The garment material tiles the cloth bake's weave detail texture (one weave repeat of the measured
sample) ``repeats`` times per UV unit.  The right number is the cloth's length along u over the
repeat's, both in millimetres: what a UV unit spans on the mesh is the length of ∂P/∂u, P the
point on the surface, which on a triangle with corners P₀, P₁, P₂ at UV coordinates Q₀, Q₁, Q₂ is
constant,

    [∂P/∂u  ∂P/∂v] = [P₁ − P₀  P₂ − P₀] · [Q₁ − Q₀  Q₂ − Q₀]⁻¹,

and the mesh's value is its mean over the surface (each triangle weighted by its area on the
mesh).  No Blender here: the operator passes the evaluated mesh's triangles in millimetres.
"""

from __future__ import annotations

import numpy as np

#: A triangle whose UV area is below this (UV units²) is collapsed in the UV map and left out.
DEGENERATE_UV_AREA = 1e-12


def millimetres_per_uv(corners_mm, corner_uvs) -> tuple[float, float]:
    """Mean length on the surface, in mm, of one UV unit along u and along v.

    Parameters
    ----------
    corners_mm
        (n, 3, 3): each triangle's corners in mm.
    corner_uvs
        (n, 3, 2): the same corners' UV coordinates.

    Raises ValueError when no triangle has a UV area (an unwrapped map is needed).
    """
    corners = np.asarray(corners_mm, dtype=np.float64)
    uvs = np.asarray(corner_uvs, dtype=np.float64)
    if corners.ndim != 3 or corners.shape[1:] != (3, 3) or uvs.shape != corners.shape[:2] + (2,):
        raise ValueError(f"expected (n, 3, 3) corners and (n, 3, 2) UVs, not {corners.shape} and {uvs.shape}")
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]], axis=-1)  # (n, 3, 2)
    uv_edges = np.stack([uvs[:, 1] - uvs[:, 0], uvs[:, 2] - uvs[:, 0]], axis=-1)  # (n, 2, 2)
    uv_area = 0.5 * np.abs(np.linalg.det(uv_edges))
    kept = uv_area > DEGENERATE_UV_AREA
    if not np.any(kept):
        raise ValueError("the UV map has no area: unwrap the mesh (u along the warp)")
    jacobian = edges[kept] @ np.linalg.inv(uv_edges[kept])  # columns ∂P/∂u, ∂P/∂v in mm per UV unit
    area = 0.5 * np.linalg.norm(np.cross(edges[kept, :, 0], edges[kept, :, 1]), axis=-1)
    if area.sum() <= 0.0:
        raise ValueError("the mesh has no area")
    per_u, per_v = (np.linalg.norm(jacobian[:, :, axis], axis=-1) for axis in (0, 1))
    return float(np.average(per_u, weights=area)), float(np.average(per_v, weights=area))


def weave_repeats_per_uv(corners_mm, corner_uvs, repeat_mm: float) -> float:
    """Weave repeats per UV unit along u (the warp) for a weave repeat of ``repeat_mm`` mm."""
    if not repeat_mm > 0.0:
        raise ValueError(f"repeat_mm must be > 0 mm, not {repeat_mm!r}")
    return millimetres_per_uv(corners_mm, corner_uvs)[0] / repeat_mm
