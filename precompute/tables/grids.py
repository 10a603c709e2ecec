"""Equal-solid-angle direction grids shared by the transport tallies, the tables and the shader.

Directions are unit vectors in the local frame of a point on the yarn surface:
``x`` = tangent (the yarn axis), ``y`` = bitangent ``n × t``, ``z`` = outward
normal.  Both grids map a direction to a point of the unit square and split the
square into ``N × N`` equal cells, so every cell covers the same solid angle:

* :data:`HEMISPHERE` (``z ≥ 0``, exit directions): Shirley–Chiu concentric
  square→disk map followed by the equal-area lift ``z = 1 − r²``
  (Shirley & Chiu, "A Low Distortion Map Between Disk and Square", JGT 1997).
  Cell solid angle ``2π / N²``.  The paper's 144 cells are ``N = 12``.
* :data:`SPHERE` (all directions, incidence for the yarn BRDF, §5.3.2):
  Clarberg's equal-area octahedral map ("Fast Equal-Area Mapping of the
  (Hemi)Sphere using SIMD", JGT 2008).  Cell solid angle ``4π / N²``.

The square coordinates ``(s, t)`` run over ``[0, 1]``; cell ``(i, j)`` covers
``[i/N, (i+1)/N] × [j/N, (j+1)/N]`` and has flat index ``j * N + i``.  The OSL
header ``osl/clothlight.h`` implements the same maps; the tests hold both to
this module.

The scalar functions are numba-compiled so the transport kernels can bin exits
with them; the ``*_array`` wrappers are for NumPy callers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from precompute.errors import ParameterError

QUARTER_PI = 0.25 * math.pi


@numba.njit(cache=True, fastmath=False)
def concentric_square_to_disk(s: float, t: float) -> tuple[float, float]:
    a = 2.0 * s - 1.0
    b = 2.0 * t - 1.0
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0
    if abs(a) > abs(b):
        r = a
        phi = QUARTER_PI * (b / a)
    else:
        r = b
        phi = 2.0 * QUARTER_PI - QUARTER_PI * (a / b)
    return r * math.cos(phi), r * math.sin(phi)


@numba.njit(cache=True)
def concentric_disk_to_square(x: float, y: float) -> tuple[float, float]:
    r = math.sqrt(x * x + y * y)
    phi = math.atan2(y, x)
    if phi < -QUARTER_PI:
        phi += 2.0 * math.pi
    if phi < QUARTER_PI:
        a = r
        b = phi * a / QUARTER_PI
    elif phi < 3.0 * QUARTER_PI:
        b = r
        a = -(phi - 2.0 * QUARTER_PI) * b / QUARTER_PI
    elif phi < 5.0 * QUARTER_PI:
        a = -r
        b = (phi - 4.0 * QUARTER_PI) * a / QUARTER_PI
    else:
        b = -r
        a = -(phi - 6.0 * QUARTER_PI) * b / QUARTER_PI
    return 0.5 * (a + 1.0), 0.5 * (b + 1.0)


@numba.njit(cache=True)
def square_to_hemisphere(s: float, t: float) -> tuple[float, float, float]:
    """Equal-area map of the unit square onto the hemisphere ``z ≥ 0``."""
    dx, dy = concentric_square_to_disk(s, t)
    r2 = dx * dx + dy * dy
    scale = math.sqrt(max(0.0, 2.0 - r2))
    return dx * scale, dy * scale, 1.0 - r2


@numba.njit(cache=True)
def hemisphere_to_square(x: float, y: float, z: float) -> tuple[float, float]:
    """Inverse of :func:`square_to_hemisphere`; ``z`` is clamped to ``[0, 1]``."""
    z = min(1.0, max(0.0, z))
    r = math.sqrt(1.0 - z)
    planar = math.sqrt(x * x + y * y)
    if planar == 0.0:
        return 0.5, 0.5
    return concentric_disk_to_square(r * x / planar, r * y / planar)


@numba.njit(cache=True)
def square_to_sphere(s: float, t: float) -> tuple[float, float, float]:
    """Clarberg's equal-area octahedral map of the unit square onto the sphere."""
    u = 2.0 * s - 1.0
    v = 2.0 * t - 1.0
    up = abs(u)
    vp = abs(v)
    signed_distance = 1.0 - (up + vp)
    d = abs(signed_distance)
    r = 1.0 - d
    phi = QUARTER_PI * ((vp - up) / r + 1.0) if r != 0.0 else QUARTER_PI
    z = math.copysign(1.0 - r * r, signed_distance)
    cos_phi = math.copysign(math.cos(phi), u)
    sin_phi = math.copysign(math.sin(phi), v)
    scale = r * math.sqrt(max(0.0, 2.0 - r * r))
    return cos_phi * scale, sin_phi * scale, z


@numba.njit(cache=True)
def sphere_to_square(x: float, y: float, z: float) -> tuple[float, float]:
    """Inverse of :func:`square_to_sphere` for a unit vector."""
    ax = abs(x)
    ay = abs(y)
    az = min(1.0, abs(z))
    r = math.sqrt(1.0 - az)
    a = max(ax, ay)
    b = min(ax, ay)
    b = 0.0 if a == 0.0 else b / a
    phi = math.atan(b) * 2.0 / math.pi
    if ax < ay:
        phi = 1.0 - phi
    v = phi * r
    u = r - v
    if z < 0.0:
        u, v = v, u
        u = 1.0 - u
        v = 1.0 - v
    u = math.copysign(u, x)
    v = math.copysign(v, y)
    return 0.5 * (u + 1.0), 0.5 * (v + 1.0)


@numba.njit(cache=True)
def square_cell(s: float, t: float, n: int) -> int:
    """Flat index ``j * n + i`` of the cell holding square point ``(s, t)``."""
    i = min(n - 1, max(0, int(s * n)))
    j = min(n - 1, max(0, int(t * n)))
    return j * n + i


@numba.njit(cache=True)
def hemisphere_cell(x: float, y: float, z: float, n: int) -> int:
    s, t = hemisphere_to_square(x, y, z)
    return square_cell(s, t, n)


@numba.njit(cache=True)
def sphere_cell(x: float, y: float, z: float, n: int) -> int:
    s, t = sphere_to_square(x, y, z)
    return square_cell(s, t, n)


@numba.njit(cache=True)
def _square_to_hemisphere_array(s, t, out):
    for k in range(s.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = square_to_hemisphere(s[k], t[k])


@numba.njit(cache=True)
def _square_to_sphere_array(s, t, out):
    for k in range(s.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = square_to_sphere(s[k], t[k])


@numba.njit(cache=True)
def _hemisphere_to_square_array(d, out):
    for k in range(d.shape[0]):
        out[k, 0], out[k, 1] = hemisphere_to_square(d[k, 0], d[k, 1], d[k, 2])


@numba.njit(cache=True)
def _sphere_to_square_array(d, out):
    for k in range(d.shape[0]):
        out[k, 0], out[k, 1] = sphere_to_square(d[k, 0], d[k, 1], d[k, 2])


@dataclass(frozen=True)
class AngularGrid:
    """An ``N × N`` equal-solid-angle grid over the hemisphere or the sphere.

    Attributes
    ----------
    domain
        ``"hemisphere"`` (``z ≥ 0``) or ``"sphere"``.
    resolution
        ``N``, cells per side of the square; ``N²`` cells in all.
    """

    domain: str
    resolution: int

    def __post_init__(self):
        if self.domain not in ("hemisphere", "sphere"):
            raise ParameterError("angular_grid.domain", self.domain, "'hemisphere' or 'sphere'")
        if not isinstance(self.resolution, (int, np.integer)) or self.resolution < 2:
            raise ParameterError("angular_grid.resolution", self.resolution, "an integer ≥ 2")

    @property
    def n_cells(self) -> int:
        return self.resolution * self.resolution

    @property
    def cell_solid_angle(self) -> float:
        """Solid angle of every cell, sr."""
        total = 2.0 * math.pi if self.domain == "hemisphere" else 4.0 * math.pi
        return total / self.n_cells

    def square_to_direction(self, s, t) -> np.ndarray:
        """Directions (…, 3) for square coordinates ``s, t`` in ``[0, 1]``."""
        kernel = _square_to_hemisphere_array if self.domain == "hemisphere" else _square_to_sphere_array
        s, t = np.broadcast_arrays(np.asarray(s, float), np.asarray(t, float))
        out = np.empty(s.shape + (3,))
        kernel(s.reshape(-1), t.reshape(-1), out.reshape(-1, 3))
        return out

    def direction_to_square(self, directions) -> np.ndarray:
        """Square coordinates (…, 2) of unit directions (…, 3)."""
        kernel = _hemisphere_to_square_array if self.domain == "hemisphere" else _sphere_to_square_array
        d = np.ascontiguousarray(directions, dtype=float)
        out = np.empty(d.shape[:-1] + (2,))
        kernel(d.reshape(-1, 3), out.reshape(-1, 2))
        return out

    def cell_of(self, directions) -> np.ndarray:
        """Flat cell index of each unit direction (…, 3)."""
        st = self.direction_to_square(directions)
        n = self.resolution
        i = np.clip((st[..., 0] * n).astype(int), 0, n - 1)
        j = np.clip((st[..., 1] * n).astype(int), 0, n - 1)
        return j * n + i

    def cell_samples(self, subsamples: int) -> np.ndarray:
        """Directions (N², subsamples², 3) on a ``subsamples × subsamples`` lattice inside every cell
        of the equal-area square, flat cell order: uniform in solid angle over each cell."""
        if not isinstance(subsamples, (int, np.integer)) or subsamples < 1:
            raise ParameterError("subsamples", subsamples, "an integer ≥ 1")
        n = self.resolution
        offsets = (np.arange(subsamples) + 0.5) / subsamples
        cells = np.arange(n)
        s = (cells[None, :, None, None] + offsets[None, None, None, :]) / n  # [j, i, sub_t, sub_s]
        t = (cells[:, None, None, None] + offsets[None, None, :, None]) / n
        return self.square_to_direction(*np.broadcast_arrays(s, t)).reshape(n * n, subsamples * subsamples, 3)

    def cell_centers(self) -> np.ndarray:
        """Direction at the square-space center of every cell, shape (N², 3), flat order."""
        n = self.resolution
        centers = (np.arange(n) + 0.5) / n
        s, t = np.meshgrid(centers, centers)  # t varies along rows: flat index j*n+i
        return self.square_to_direction(s, t).reshape(-1, 3)


HEMISPHERE = "hemisphere"
SPHERE = "sphere"
