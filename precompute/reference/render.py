"""The brute-force render: Mitsuba 3's volumetric path tracer on the same dielectric cylinder.

Scene (lengths in mm, Mitsuba's scene units): a circular cylinder of radius R along the x axis,
``length_radii`` · R long with black end caps (a path that reaches an end stops, as if it left an
infinite yarn there), looked at in its middle by an orthographic camera along −z whose image spans
b ∈ [−edge·R, edge·R] across the yarn; a smooth dielectric boundary (interior index n, exterior 1);
a homogeneous interior medium with μs, μa (1/mm, Mitsuba's ``sigma_t`` = μs + μa and ``albedo``)
and a ``tabphase`` phase function; lit by :class:`~.cap.CapLight` about the light direction.
Mitsuba's own ``volpath`` integrator, ``scalar_mono`` variant where the wheel has one, else
``scalar_rgb`` with a grey medium (the 3.9.1 wheel has no ``scalar_mono``; one wavelength per
render either way; the llvm variants need a newer libLLVM than some systems have).

The first-surface glint is removed by a Python BSDF wrapping Mitsuba's ``dielectric`` (registered
as :data:`GLINT_FREE_PLUGIN` by :func:`mitsuba`): seen from outside it always refracts, with weight
(1 − F) — the reflection from the outside, which on a convex cylinder is exactly the glint, is zero —
and from inside it is the plain dielectric (internal reflection and refraction out kept).

Conventions checked on Mitsuba 3.9.1 (tests/test_brute_force_reference.py): ``tabphase`` values
run over cos θ from −1 to +1 with cos θ = +1 forward scattering, the project's convention
(``precompute/optics/phase.py``); an ``envmap`` row k lies at θ = kπ/(H − 1) from the map's +y pole,
bilinear in between (:func:`check_cap_map`).
"""

from __future__ import annotations

import math
import os
import pathlib
import pickle
import subprocess
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from precompute.errors import ParameterError
from precompute.reference.cap import CapLight, cap_frame
from precompute.reference.geometry import bin_edges

#: Variants tried in order: one wavelength per render, no JIT (the llvm variants need a newer libLLVM).
VARIANTS = ("scalar_mono", "scalar_rgb")
#: Name under which the glint-free dielectric is registered with Mitsuba.
GLINT_FREE_PLUGIN = "clothlight_glint_free_dielectric"
#: Default image span across the yarn, as a fraction of R: rays at |b| = R graze the silhouette and
#: a float32 miss there would see the cap itself.
DEFAULT_EDGE = 0.999

_registered: set[str] = set()


def mitsuba():
    """Import Mitsuba 3, select the scalar variant (:data:`VARIANTS`) and register the glint-free BSDF.

    Returns the ``mitsuba`` module (a variant set before that is not one of :data:`VARIANTS` is
    replaced).  Raises ImportError when Mitsuba is not installed.
    """
    import mitsuba as mi

    if mi.variant() not in VARIANTS:
        available = mi.variants()
        for name in VARIANTS:
            if name in available:
                mi.set_variant(name)
                break
        else:
            raise ImportError(f"Mitsuba has none of the variants {VARIANTS} (it has {available})")
    if mi.variant() not in _registered:
        mi.register_bsdf(GLINT_FREE_PLUGIN, lambda props: _glint_free_class(mi)(props))
        _registered.add(mi.variant())
    return mi


def _glint_free_class(mi):
    class GlintFreeDielectric(mi.BSDF):
        """``dielectric`` (child ``nested``, relative index ``eta``) without reflection from the outside."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.nested = props["nested"]
            self.eta = float(props["eta"])
            self.m_flags = self.nested.m_flags
            self.m_components = list(self.nested.m_components)

        def sample(self, ctx, si, sample1, sample2, active=True):
            cos_i = float(si.wi[2])
            if cos_i <= 0.0:  # inside: the plain dielectric
                return self.nested.sample(ctx, si, sample1, sample2, active)
            reflectance = float(mi.fresnel(mi.Float(cos_i), mi.Float(self.eta))[0])
            # the dielectric refracts when sample1 > F: choose that branch always and weight it by 1 − F
            forced = reflectance + (1.0 - reflectance) * min(max(float(sample1), 1e-6), 1.0 - 1e-6)
            bs, weight = self.nested.sample(ctx, si, forced, sample2, active)
            if float(bs.wo[2]) >= 0.0:
                return bs, weight * 0.0
            return bs, weight * (1.0 - reflectance)

        def eval(self, ctx, si, wo, active=True):
            return self.nested.eval(ctx, si, wo, active) * 0.0  # delta lobes: never evaluated

        def pdf(self, ctx, si, wo, active=True):
            return 0.0

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.nested.eval(ctx, si, wo, active) * 0.0, 0.0

        def to_string(self):
            return f"GlintFreeDielectric[eta={self.eta}]"

    return GlintFreeDielectric


@dataclass(frozen=True)
class ReferenceMedium:
    """The yarn the reference renders, at one wavelength.

    Attributes
    ----------
    radius_mm : R, mm
    index : real refractive index of the host (the boundary); exterior 1
    mu_s, mu_a : scattering and absorption coefficients, 1/mm
    phase : (M,) phase function on the uniform grid of M ≥ 2 values of cos θ over [−1, 1], cos θ = +1
        forward (``precompute.optics.phase`` convention), 1/sr, any normalisation (Mitsuba normalises the
        piecewise-linear function, as the project's transport does); None: isotropic
    """

    radius_mm: float
    index: float
    mu_s: float
    mu_a: float
    phase: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        for name in ("radius_mm", "index"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ParameterError(name, getattr(self, name), "> 0")
        for name in ("mu_s", "mu_a"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ParameterError(name, getattr(self, name), "≥ 0 (1/mm)")
        if self.mu_t <= 0:
            raise ParameterError("mu_s + mu_a", self.mu_t, "> 0 (1/mm)")
        if self.phase is not None:
            phase = np.asarray(self.phase, float)
            if phase.ndim != 1 or len(phase) < 2 or not np.all(np.isfinite(phase)) or np.any(phase < 0) or \
                    phase.sum() <= 0:
                raise ParameterError("phase", phase.shape, "(M ≥ 2,) finite values ≥ 0, not all 0")
            object.__setattr__(self, "phase", phase)

    @property
    def mu_t(self) -> float:
        """μs + μa, 1/mm."""
        return self.mu_s + self.mu_a


@dataclass(frozen=True, eq=False)
class ReferenceResult:
    """Radiance per bin across the yarn divided by E⊥, from independent renders (seeds).

    Attributes
    ----------
    bin_edges : (B + 1,) b/R of the bin edges (image columns ordered by increasing y)
    rho : (B,) L_o / E⊥, 1/sr, the mean over seeds of each bin's mean over its pixels
    rho_stderr : (B,) its standard error (spread of the seeds / √seeds), 1/sr
    per_seed : (K, B) each seed's bins, 1/sr
    light : (3,) unit vector toward the cap centre, scene frame
    e_perp : E⊥ per unit cap radiance, sr
    glint : whether the first-surface reflection was kept
    """

    bin_edges: np.ndarray
    rho: np.ndarray
    rho_stderr: np.ndarray
    per_seed: np.ndarray
    light: np.ndarray
    e_perp: float
    glint: bool
    spp: int
    variant: str
    seconds: float

    @property
    def width_mean(self) -> float:
        """Mean of ρ over the bins (the yarn width), 1/sr."""
        return float(self.rho.mean())

    @property
    def width_mean_stderr(self) -> float:
        """Standard error of :attr:`width_mean` from the spread of the seeds' width means, 1/sr."""
        means = self.per_seed.mean(axis=1)
        return float(means.std(ddof=1) / math.sqrt(len(means)))

    @property
    def rel_stderr(self) -> np.ndarray:
        """(B,) relative standard error of each bin (inf where ρ = 0)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.rho > 0, self.rho_stderr / self.rho, np.inf)


def _phase_values(medium: ReferenceMedium) -> dict:
    if medium.phase is None:
        return {"type": "isotropic"}
    return {"type": "tabphase", "values": ", ".join(f"{v:.9g}" for v in medium.phase)}


def scene_dict(medium: ReferenceMedium, light, *, cap: CapLight = CapLight(), bins: int = 16,
               pixels_per_bin: int = 4, rows: int = 4, edge: float = DEFAULT_EDGE, length_radii: float = 200.0,
               glint: bool = False, spp: int = 64, max_depth: int = 100_000, rr_depth: int = 64) -> dict:
    """The Mitsuba scene description (a dict for ``mitsuba.load_dict``); see the module docstring.

    ``light``: unit vector toward the cap centre (scene frame, :func:`~.geometry.light_direction`).
    The film is ``bins · pixels_per_bin`` × ``rows`` pixels with a box filter (each pixel the mean
    radiance over its area), ``spp`` samples per pixel.
    """
    mi = mitsuba()
    radius = float(medium.radius_mm)
    width, height = int(bins) * int(pixels_per_bin), int(rows)
    transform = mi.ScalarTransform4f
    half = edge * radius
    frame = cap_frame(light)
    rotation = np.eye(4)
    # map-local +y (the pole) → light; local x, z → the cap frame's e1, e2
    rotation[:3, 0], rotation[:3, 1], rotation[:3, 2] = frame[0], frame[2], -frame[1]
    dielectric = {"type": "dielectric", "int_ior": float(medium.index), "ext_ior": 1.0}
    bsdf = dielectric if glint else {"type": GLINT_FREE_PLUGIN, "eta": float(medium.index), "nested": dielectric}
    length = float(length_radii) * radius
    black = {"type": "diffuse", "reflectance": 0.0}
    end_caps = {
        f"end_{side}": {
            "type": "disk",
            "to_world": transform().translate([sign * length / 2, 0.0, 0.0])
            @ transform().rotate([0.0, 1.0, 0.0], sign * 90.0) @ transform().scale([1.001 * radius] * 3),
            "bsdf": black,
        }
        for side, sign in (("low", -1.0), ("high", 1.0))
    }
    return {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": int(max_depth), "rr_depth": int(rr_depth)},
        "sensor": {
            "type": "orthographic",
            "near_clip": 0.5 * radius,
            "far_clip": 100.0 * radius,
            "to_world": transform().look_at(origin=[0.0, 0.0, 3.0 * radius], target=[0.0, 0.0, 0.0],
                                            up=[1.0, 0.0, 0.0]) @ transform().scale([half, half, 1.0]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                     "pixel_format": "luminance" if mi.variant().endswith("mono") else "rgb"},
            "sampler": {"type": "independent", "sample_count": int(spp)},
        },
        "yarn": {
            "type": "cylinder",
            "p0": [-length / 2, 0.0, 0.0],
            "p1": [length / 2, 0.0, 0.0],
            "radius": radius,
            "bsdf": bsdf,
            "interior": {
                "type": "homogeneous",
                "sigma_t": float(medium.mu_t),
                "albedo": float(medium.mu_s / medium.mu_t),
                "sample_emitters": False,  # shadow rays cannot cross the delta boundary: a waste
                "phase": _phase_values(medium),
            },
        },
        **end_caps,
        "light": {"type": "envmap", "bitmap": mi.Bitmap(cap.map_image()),
                  "to_world": transform(rotation.tolist())},
    }


def check_cap_map(emitter, cap: CapLight, light, tolerance: float = 2e-3) -> float:
    """The largest difference between the loaded ``envmap``'s radiance and ``cap.radiance`` over
    directions at many angles from ``light``; raises RuntimeError beyond ``tolerance``."""
    mi = mitsuba()
    frame = cap_frame(light)
    degrees = [0.0, 1.0, 0.5 * math.degrees(cap.flat_angle), math.degrees(cap.flat_angle) - 0.01,
               math.degrees(0.5 * (cap.flat_angle + cap.outer_angle)), math.degrees(cap.outer_angle) + 0.01,
               2.0 * math.degrees(cap.outer_angle), 45.0, 90.0, 135.0, 180.0]
    worst = 0.0
    for theta in np.radians(degrees):
        for phi in np.linspace(0.0, 2.0 * math.pi, 7, endpoint=False):
            d = math.sin(theta) * (math.cos(phi) * frame[0] + math.sin(phi) * frame[1]) + math.cos(theta) * frame[2]
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*(-d))
            value = float(np.asarray(emitter.eval(si)).reshape(-1)[0])
            worst = max(worst, abs(value - float(cap.radiance(theta))))
    if worst > tolerance:
        raise RuntimeError(f"Mitsuba's envmap does not hold the cap profile this code assumes "
                           f"(largest difference {worst:.3g}); see precompute/reference/cap.py")
    return worst


def _column_positions(sensor, width: int, radius: float) -> np.ndarray:
    """b/R of each film column's centre, from Mitsuba's own camera rays."""
    mi = mitsuba()
    b = np.empty(width)
    for c in range(width):
        ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((c + 0.5) / width, 0.5), mi.Point2f(0.5, 0.5))
        b[c] = float(ray.o[1]) / radius
    return b


def _film_order(sensor, width: int, radius: float, edge: float) -> slice:
    """The column order that puts the film's columns by increasing y (checked on Mitsuba's own rays)."""
    columns = _column_positions(sensor, width, radius)
    expected = edge * (2.0 * (np.arange(width) + 0.5) / width - 1.0)
    if np.allclose(columns, expected[::-1], atol=1e-5):
        return slice(None, None, -1)
    if np.allclose(columns, expected, atol=1e-5):
        return slice(None)
    raise RuntimeError(f"unexpected film mapping: column b/R {columns[:3]} … {columns[-3:]}")


def _render_seeds(medium: ReferenceMedium, light: np.ndarray, seeds: list[int], options: dict,
                  threads: int) -> np.ndarray:
    """Each seed's bin means of radiance per unit cap radiance (len(seeds), bins); runs in a worker."""
    import drjit as dr

    mi = mitsuba()
    cap, bins, ppb, rows = options["cap"], options["bins"], options["pixels_per_bin"], options["rows"]
    scene = mi.load_dict(scene_dict(medium, light, **options))
    check_cap_map(scene.emitters()[0], cap, light)
    order = _film_order(scene.sensors()[0], bins * ppb, medium.radius_mm, options["edge"])
    out = np.empty((len(seeds), bins))
    previous = dr.thread_count()
    dr.set_thread_count(threads)
    try:
        for k, seed in enumerate(seeds):
            image = np.asarray(mi.render(scene, seed=int(seed), spp=int(options["spp"])), dtype=float)
            out[k] = image[..., 0][:, order].reshape(rows, bins, ppb).mean(axis=(0, 2))
    finally:
        dr.set_thread_count(previous)
    return out


def _start_worker(arguments) -> subprocess.Popen:
    """Run :func:`_render_seeds` in a fresh interpreter (``python -m precompute.reference.render``)."""
    root = str(pathlib.Path(__file__).resolve().parents[2])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    process = subprocess.Popen([sys.executable, "-m", "precompute.reference.render"], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=root)
    process.stdin.write(pickle.dumps(arguments))
    process.stdin.close()
    return process


def _finish_worker(process: subprocess.Popen) -> np.ndarray:
    output = process.stdout.read()
    errors = process.stderr.read().decode(errors="replace")
    if process.wait() != 0:
        raise RuntimeError(f"a reference render worker failed:\n{errors}")
    return pickle.loads(output)


def render_reference(medium: ReferenceMedium, light, *, cap: CapLight = CapLight(), bins: int = 16,
                     spp: int = 64, seeds: int = 8, pixels_per_bin: int = 4, rows: int = 4,
                     edge: float = DEFAULT_EDGE, length_radii: float = 200.0, glint: bool = False,
                     rr_depth: int = 64, first_seed: int = 0, workers: int | None = None,
                     target_rel_stderr: float | None = None, target_on: str = "width",
                     max_seconds: float | None = None, max_seeds: int = 4096) -> ReferenceResult:
    """Render the yarn ``seeds`` times independently and return ρ = L_o / E⊥ per width bin (1/sr).

    ``light``: unit vector toward the cap centre in the scene frame (yarn axis x, camera +z);
    ``glint``: keep the first-surface reflection (a plain ``dielectric``; the tables exclude it).
    The bins split b/R ∈ [−edge, edge] into ``bins`` equal parts, ordered by increasing y; each
    render has ``spp`` samples in each of ``bins · pixels_per_bin × rows`` pixels.
    ``workers``: processes rendering the seeds, one thread each (default: one per CPU, at most
    ``seeds``).  The glint-free BSDF is Python, called under the interpreter lock for every
    boundary hit, so threads of one process would wait on each other; processes do not.

    With ``target_rel_stderr``, further rounds of seeds follow until the relative standard error of
    the width mean (``target_on="width"``) or the median over the bins of each bin's
    (``target_on="bins"``) is at most that, the next round would end after ``max_seconds`` (wall
    time of this call), or ``max_seeds`` are rendered.  The error falls as 1/√seeds.
    """
    if isinstance(seeds, bool) or not isinstance(seeds, (int, np.integer)) or seeds < 2:
        raise ParameterError("seeds", seeds, "an integer ≥ 2 (the error comes from their spread)")
    if target_rel_stderr is not None and not 0 < target_rel_stderr < 1:
        raise ParameterError("target_rel_stderr", target_rel_stderr, "(0, 1)")
    if target_on not in ("width", "bins"):
        raise ParameterError("target_on", target_on, "'width' or 'bins'")
    light = np.asarray(light, float)
    light = light / np.linalg.norm(light)
    workers = min(int(seeds), os.cpu_count() or 1) if workers is None else int(workers)
    if workers < 1:
        raise ParameterError("workers", workers, "≥ 1")
    options = dict(cap=cap, bins=int(bins), pixels_per_bin=int(pixels_per_bin), rows=int(rows), edge=float(edge),
                   length_radii=float(length_radii), glint=bool(glint), spp=int(spp), rr_depth=int(rr_depth))
    start = time.perf_counter()
    rounds, done, count = [], 0, int(seeds)
    while count > 0:
        round_start = time.perf_counter()
        round_seeds = [int(first_seed) + done + k for k in range(count)]
        if workers == 1:
            rounds.append(_render_seeds(medium, light, round_seeds, options, 1))
        else:
            part = np.empty((count, bins))
            jobs = [(w, _start_worker((medium, light, round_seeds[w::workers], options, 1)))
                    for w in range(min(workers, count))]
            for w, job in jobs:
                part[w::workers] = _finish_worker(job)
            rounds.append(part)
        done += count
        if target_rel_stderr is None:
            break
        samples = np.concatenate(rounds)
        if target_on == "width":
            samples = samples.mean(axis=1, keepdims=True)
        means = samples.mean(axis=0)
        if not np.any(means > 0):
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            relative = float(np.median(np.where(means > 0, samples.std(axis=0, ddof=1) / means, np.inf)))
        relative /= math.sqrt(done)
        if relative <= target_rel_stderr:
            break
        wanted = math.ceil(done * min((relative / target_rel_stderr) ** 2, 1e6)) - done
        if max_seconds is not None:
            per_seed_seconds = (time.perf_counter() - round_start) / count
            left = max_seconds - (time.perf_counter() - start)
            wanted = min(wanted, int(left / per_seed_seconds))
        count = min(wanted, max_seeds - done)
        if count < 2:
            break
    e_perp = cap.e_perp
    per_seed = np.concatenate(rounds) / e_perp
    rho = per_seed.mean(axis=0)
    stderr = per_seed.std(axis=0, ddof=1) / math.sqrt(len(per_seed))
    return ReferenceResult(bin_edges(bins, edge), rho, stderr, per_seed, light, e_perp, bool(glint), int(spp),
                           mitsuba().variant(), time.perf_counter() - start)


if __name__ == "__main__":  # a worker of render_reference: pickled arguments in, pickled bins out
    sys.stdout.buffer.write(pickle.dumps(_render_seeds(*pickle.loads(sys.stdin.buffer.read()))))
