"""Tabulated phase functions: normalisation, asymmetry, sampling tables, Henyey–Greenstein.

A phase function ``p(μ)``, ``μ = cos θ``, is in 1/sr and normalised over the
sphere: ``2π ∫_{-1}^{1} p(μ) dμ = 1``.  Tables live on an increasing grid of
``μ`` over [−1, 1] and are taken linear in μ between grid points; integrals use
the trapezoidal rule on that grid, so a table, its ``g`` and its sampling table
agree with each other exactly.  Two grids (:data:`PHASE_GRID_KINDS`):

* ``"uniform-cos"``: uniform in μ (:func:`cos_theta_grid`), what the
  transport's tables use (docs/transport.md);
* ``"uniform-angle"``: uniform in the scattering angle θ
  (:func:`angle_cos_theta_grid`), dense in μ near both μ = ±1.  Mie phase
  functions of large spheres have a diffraction peak of angular width ~1/x
  and ripples of angular period ~π/x (size parameter x; van de Hulst, *Light
  Scattering by Small Particles*, 1957, §§ 8.3, 12.3), so a grid uniform in θ
  needs ``M ∝ x`` samples where a grid uniform in μ needs ``M ∝ x²``.  Its
  tables go to the transport through :func:`resample_uniform_cos`.
"""

from __future__ import annotations

import numpy as np

from precompute.errors import ParameterError

#: Samples of the default cos θ grid.  For Mie particles with size parameter
#: x ≲ 15 in the host the trapezoidal integral of the phase table is within
#: 1e-3 of the Mie cross-section and g within 2e-4 of the Mie g.
DEFAULT_PHASE_SAMPLES = 2001
#: Entries of the inverse-CDF sampling table.
DEFAULT_ICDF_SIZE = 4096
#: The kinds of cos θ grid (see the module docstring).
PHASE_GRID_KINDS = ("uniform-cos", "uniform-angle")


def cos_theta_grid(n_samples: int = DEFAULT_PHASE_SAMPLES) -> np.ndarray:
    """Uniform grid of ``n_samples`` values of cos θ over [−1, 1]."""
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 3:
        raise ParameterError("phase_samples", n_samples, "an integer ≥ 3")
    return np.linspace(-1.0, 1.0, int(n_samples))


def angle_cos_theta_grid(n_samples: int) -> np.ndarray:
    """``n_samples`` values of cos θ over [−1, 1], increasing, at θ uniform over [0, π]."""
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 3:
        raise ParameterError("phase_samples", n_samples, "an integer ≥ 3")
    grid = np.cos(np.linspace(np.pi, 0.0, int(n_samples)))
    grid[0], grid[-1] = -1.0, 1.0
    return grid


def phase_grid(kind: str, n_samples: int) -> np.ndarray:
    """The cos θ grid of a kind in :data:`PHASE_GRID_KINDS` with ``n_samples`` values."""
    if kind == "uniform-cos":
        return cos_theta_grid(n_samples)
    if kind == "uniform-angle":
        return angle_cos_theta_grid(n_samples)
    raise ParameterError("phase grid kind", kind, f"one of {PHASE_GRID_KINDS}")


#: The default grid, shared by every table that does not choose its own.
DEFAULT_COS_THETA = cos_theta_grid()


def _trapezoid(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.sum(0.5 * (y[..., 1:] + y[..., :-1]) * np.diff(x), axis=-1)


def phase_integral(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """``2π ∫ p dμ`` over the sphere (…,); 1 for a normalised phase function."""
    return 2.0 * np.pi * _trapezoid(np.asarray(phase, float), np.asarray(cos_theta, float))


def normalize_phase(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """``phase`` (…, M) scaled so that ``2π ∫ p dμ = 1``."""
    total = phase_integral(cos_theta, phase)
    if np.any(total <= 0) or not np.all(np.isfinite(total)):
        raise ParameterError("phase", "non-positive or non-finite integral", "a positive, finite phase function")
    return np.asarray(phase, float) / total[..., None]


def asymmetry_parameter(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Mean cosine ``g = 2π ∫ μ p(μ) dμ`` (…,) of a normalised phase function."""
    cos_theta = np.asarray(cos_theta, float)
    return 2.0 * np.pi * _trapezoid(cos_theta * np.asarray(phase, float), cos_theta)


def henyey_greenstein_phase(cos_theta, g) -> np.ndarray:
    """Henyey–Greenstein phase function, 1/sr: ``(1 − g²) / (4π (1 + g² − 2gμ)^{3/2})``.

    ``g`` in (−1, 1), a scalar or an array of shape (…,); the result has shape
    ``cos_theta.shape`` or (…, ``len(cos_theta)``).
    """
    cos_theta = np.asarray(cos_theta, float)
    g = np.asarray(g, float)
    if not np.all(np.isfinite(g)) or np.any(np.abs(g) >= 1.0):
        raise ParameterError("g", g.tolist(), "(-1, 1)")
    g_ = g[..., None] if g.ndim else g
    return (1.0 - g_**2) / (4.0 * np.pi * (1.0 + g_**2 - 2.0 * g_ * cos_theta) ** 1.5)


def phase_inverse_cdf(cos_theta: np.ndarray, phase: np.ndarray, n_samples: int = DEFAULT_ICDF_SIZE) -> np.ndarray:
    """Inverse cumulative distribution of μ = cos θ for each phase function (…, M) → (…, n_samples).

    Entry ``k`` is the μ at cumulative probability ``u_k = k / (n_samples − 1)``;
    a sampler interpolates linearly in ``u`` (:func:`sample_inverse_cdf`).  The
    CDF is the trapezoidal integral of the table, so the drawn μ follow the
    table to the resolution of ``cos_theta`` and of ``u``.
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 2:
        raise ParameterError("n_samples", n_samples, "an integer ≥ 2")
    cos_theta = np.asarray(cos_theta, float)
    phase = np.asarray(phase, float)
    if cos_theta.ndim != 1 or phase.shape[-1] != cos_theta.size or np.any(np.diff(cos_theta) <= 0):
        raise ParameterError(
            "cos_theta", cos_theta.shape, f"strictly increasing, one value per phase sample ({phase.shape[-1]})"
        )
    if not np.all(np.isfinite(phase)) or np.any(phase < 0):
        raise ParameterError("phase", "negative or non-finite values", "finite values ≥ 0")
    flat = phase.reshape(-1, phase.shape[-1])
    u = np.linspace(0.0, 1.0, n_samples)
    out = np.empty((flat.shape[0], n_samples))
    for row, p in enumerate(flat):
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(cos_theta))])
        if cdf[-1] <= 0:
            raise ParameterError("phase", "an all-zero row", "a phase function with a positive integral")
        cdf /= cdf[-1]
        # Where p = 0 the CDF is flat and its inverse ambiguous: keep the first μ of each flat run.
        keep = np.concatenate([[True], np.diff(cdf) > 0])
        out[row] = np.interp(u, cdf[keep], cos_theta[keep])
    return out.reshape(phase.shape[:-1] + (n_samples,))


def _cumulative(cos_theta: np.ndarray, phase: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``∫_{-1}^{at} p dμ`` (…, len(at)) of the piecewise-linear ``phase`` (…, M) on ``cos_theta``, exactly."""
    width = np.diff(cos_theta)
    segment = 0.5 * (phase[..., 1:] + phase[..., :-1]) * width
    start = np.concatenate([np.zeros(phase.shape[:-1] + (1,)), np.cumsum(segment, axis=-1)], axis=-1)
    j = np.clip(np.searchsorted(cos_theta, at, side="right") - 1, 0, len(cos_theta) - 2)
    t = np.clip(at - cos_theta[j], 0.0, width[j])
    p0, p1 = phase[..., j], phase[..., j + 1]
    return start[..., j] + p0 * t + (p1 - p0) * t * t / (2.0 * width[j])


def resample_uniform_cos(cos_theta: np.ndarray, phase: np.ndarray, n_samples: int) -> np.ndarray:
    """``phase`` (…, M) on any increasing ``cos_theta`` grid → (…, n_samples) on :func:`cos_theta_grid`.

    Conserves probability per grid cell: the value at node ``μ_j`` (spacing h) is
    the mean of the piecewise-linear table over ``[μ_j − h/2, μ_j + h/2]`` (over
    the half cell at the ends), so the trapezoidal integral of the result equals
    the table's exactly and a forward peak narrower than h keeps its
    probability (a linear interpolation would keep its height instead).  The
    mean cosine changes by O(h²) where the table is smooth and by less than h/2
    times the probability of a peak the new grid does not resolve.  A table
    already on the uniform grid of ``n_samples`` values is returned unchanged.
    """
    cos_theta = np.asarray(cos_theta, float)
    phase = np.asarray(phase, float)
    target = cos_theta_grid(n_samples)
    if cos_theta.shape == target.shape and np.allclose(cos_theta, target, rtol=0.0, atol=1e-12):
        return phase
    if cos_theta.ndim != 1 or phase.shape[-1] != cos_theta.size or np.any(np.diff(cos_theta) <= 0) or \
            cos_theta[0] != -1.0 or cos_theta[-1] != 1.0:
        raise ParameterError("cos_theta", cos_theta.shape, "strictly increasing from −1 to 1, one value per sample")
    h = target[1] - target[0]
    edges = np.concatenate([[-1.0], np.clip(target[:-1] + h / 2.0, -1.0, 1.0), [1.0]])
    cells = np.diff(_cumulative(cos_theta, phase, edges), axis=-1)
    return cells / np.diff(edges)


def sample_inverse_cdf(icdf: np.ndarray, u) -> np.ndarray:
    """μ drawn from one inverse-CDF table (K,) for uniform numbers ``u`` in [0, 1]."""
    position = np.asarray(u, float) * (len(icdf) - 1)
    k = np.minimum(position.astype(int), len(icdf) - 2)
    frac = position - k
    return icdf[k] * (1.0 - frac) + icdf[k + 1] * frac
