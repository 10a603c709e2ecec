"""Geometry of the brute-force reference: the scene frame, the width bins, the yarn frames, and the
exact unscattered (ballistic) paths and first-surface glint of a smooth dielectric cylinder.

Scene (world) frame, lengths in mm: the yarn axis is +x, the orthographic camera looks along −z
(so the view direction ω_o, toward the camera, is +z everywhere), and the image's horizontal axis
is +y.  A camera ray at impact parameter ``b`` (mm, −R < b < R) meets the yarn at
``p = (x, b, √(R² − b²))``.  The yarn frame there follows :mod:`precompute.tables.grids`:
x = tangent (the axis), y = n × t, z = outward normal.

Everything here is NumPy only (no Mitsuba): it is the table side of the comparison and the
closed-form answers the tests hold the renderer to.
"""

from __future__ import annotations

import math

import numpy as np

from precompute.errors import ParameterError

#: Unit vectors of the scene frame: yarn axis, image horizontal (across the yarn), toward the camera.
AXIS = np.array([1.0, 0.0, 0.0])
ACROSS = np.array([0.0, 1.0, 0.0])
VIEW = np.array([0.0, 0.0, 1.0])


def light_direction(azimuth_deg: float, elevation_deg: float = 0.0) -> np.ndarray:
    """Unit vector toward the light in the scene frame (3,).

    ``azimuth_deg``: angle from the view direction, turning toward +y, in the plane perpendicular
    to the axis (0 = light at the camera, 180 = straight behind the yarn); ``elevation_deg``:
    angle out of that plane toward the +x axis.
    """
    az, el = math.radians(float(azimuth_deg)), math.radians(float(elevation_deg))
    return math.cos(el) * (math.cos(az) * VIEW + math.sin(az) * ACROSS) + math.sin(el) * AXIS


def bin_edges(bins: int, edge: float = 1.0) -> np.ndarray:
    """Edges (bins + 1,) of equal bins of the impact parameter b/R across [−edge, edge] (dimensionless)."""
    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
        raise ParameterError("bins", bins, "an integer ≥ 1")
    if not 0.0 < edge <= 1.0:
        raise ParameterError("edge", edge, "(0, 1]")
    return np.linspace(-edge, edge, int(bins) + 1)


def bin_positions(edges: np.ndarray, per_bin: int) -> np.ndarray:
    """Midpoint-rule positions b/R (bins, per_bin) inside each bin (uniform in b, as the image is)."""
    edges = np.asarray(edges, float)
    frac = (np.arange(per_bin) + 0.5) / per_bin
    return edges[:-1, None] + (edges[1:] - edges[:-1])[:, None] * frac[None, :]


def yarn_frames(b_over_r: np.ndarray) -> np.ndarray:
    """Yarn frames (…, 3, 3) at the visible points of impact parameter b/R: rows x, y, z in the scene frame.

    x = axis (tangent), z = outward normal (0, b/R, √(1 − (b/R)²)), y = z × x.
    """
    b = np.asarray(b_over_r, float)
    nz = np.sqrt(np.clip(1.0 - b * b, 0.0, 1.0))
    frames = np.zeros(b.shape + (3, 3))
    frames[..., 0, 0] = 1.0
    frames[..., 1, 1] = nz
    frames[..., 1, 2] = -b
    frames[..., 2, 1] = b
    frames[..., 2, 2] = nz
    return frames


def to_local(frames: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Scene-frame directions (…, 3) in the yarn frames (…, 3, 3) (broadcast): (…, 3)."""
    return np.einsum("...ij,...j->...i", frames, directions)


def to_world(frames: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_local`."""
    return np.einsum("...ji,...j->...i", frames, local)


def fresnel_unpolarized(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance for incidence cosine ``cos_i`` ≥ 0 from index 1 into relative
    index ``eta`` (= n_transmitted / n_incident); 1 under total internal reflection."""
    cos_i = np.clip(np.asarray(cos_i, float), 0.0, 1.0)
    sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, 1.0))
    rs = (cos_i - eta * cos_t) / np.maximum(cos_i + eta * cos_t, 1e-300)
    rp = (eta * cos_i - cos_t) / np.maximum(eta * cos_i + cos_t, 1e-300)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def _refract(d: np.ndarray, normal: np.ndarray, eta: float) -> np.ndarray:
    """Refract unit ``d`` through a surface of unit ``normal`` facing against ``d``; ``eta`` = n_from / n_to."""
    cos_i = -np.sum(d * normal, axis=-1, keepdims=True)
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, 1.0))
    return eta * d + (eta * cos_i - cos_t) * normal


def unscattered_paths(wo: np.ndarray, index: float, orders: int = 4):
    """The unscattered light paths through a smooth dielectric cylinder that leave toward ``wo``.

    The contract of ``precompute.optics.ballistic.unscattered_paths``, computed here independently (by
    tracing the exit ray backward, which the reciprocity of refraction and Fresnel makes exact),
    with the Fresnel factor of every hit evaluated on its own:

    Parameters
    ----------
    wo : (…, 3) exit directions (z > 0) in the yarn frame of the exit point.
    index : the cylinder's refractive index (exterior 1).
    orders : K, the number of paths per direction: k = 0 … K−1 internal reflections.

    Returns
    -------
    wi : (…, K, 3) unit direction toward the light of path k, in the same yarn frame.
    fresnel_factor : (…, K) T_in · R^k · T_out (unpolarised Fresnel, dimensionless).
    chord_over_radius : (…, K) the path length inside the yarn divided by its radius R.

    The radiance factor of path k at extinction μt (1/mm) is
    ``fresnel_factor · exp(−μt · R · chord_over_radius)``.
    """
    wo = np.asarray(wo, float)
    if isinstance(orders, bool) or not isinstance(orders, (int, np.integer)) or orders < 1:
        raise ParameterError("orders", orders, "an integer ≥ 1")
    if not index > 0:
        raise ParameterError("index", index, "> 0")
    shape = wo.shape[:-1]
    cos_o = np.clip(wo[..., 2], 0.0, 1.0)
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), wo.shape)
    # In units of R, the cross-section is y² + (z + 1)² = 1; the exit point is the origin.
    d = _refract(-wo, normal, 1.0 / index)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    p = np.zeros(wo.shape)
    carried = 1.0 - fresnel_unpolarized(cos_o, index)
    chord = np.zeros(shape)
    wi = np.zeros(shape + (orders, 3))
    factor = np.zeros(shape + (orders,))
    length = np.zeros(shape + (orders,))
    for k in range(orders):
        # next wall hit from inside: |(p_y, p_z + 1) + s (d_y, d_z)| = 1, the positive root
        qy, qz = p[..., 1], p[..., 2] + 1.0
        a = d[..., 1] ** 2 + d[..., 2] ** 2
        half_b = qy * d[..., 1] + qz * d[..., 2]
        c = qy * qy + qz * qz - 1.0
        s = (-half_b + np.sqrt(np.maximum(half_b * half_b - a * c, 0.0))) / np.maximum(a, 1e-300)
        p = p + s[..., None] * d
        chord = chord + s
        m = np.zeros(wo.shape)
        m[..., 1], m[..., 2] = p[..., 1], p[..., 2] + 1.0
        m /= np.linalg.norm(m, axis=-1, keepdims=True)
        cos_in = np.clip(np.sum(d * m, axis=-1), 0.0, 1.0)
        sin_out2 = index * index * (1.0 - cos_in * cos_in)
        # Fresnel at the inside: the same as from outside at the refracted angle (reciprocity)
        cos_out = np.sqrt(np.clip(1.0 - sin_out2, 0.0, 1.0))
        r = np.where(sin_out2 >= 1.0, 1.0, fresnel_unpolarized(cos_out, index))
        exit_dir = _refract(d, -m, index)
        exit_dir /= np.linalg.norm(exit_dir, axis=-1, keepdims=True)
        wi[..., k, :] = exit_dir
        factor[..., k] = carried * (1.0 - r)
        length[..., k] = chord
        carried = carried * r
        d = d - 2.0 * np.sum(d * m, axis=-1, keepdims=True) * m
    return wi, factor, length


def glint_paths(wo: np.ndarray, index: float):
    """The first-surface (exterior) reflection toward ``wo`` (…, 3, yarn frame): the direction toward
    the light whose mirror image it is (…, 3) and the Fresnel reflectance (…,).  The tables exclude
    it (the shader's Cook–Torrance term covers it); a plain dielectric render includes it."""
    wo = np.asarray(wo, float)
    wi = wo * np.array([-1.0, -1.0, 1.0])
    return wi, fresnel_unpolarized(wo[..., 2], index)
