"""Scattering by the fibres of a yarn: absorbing dielectric fibres, the dye inside them (issue 43).

A spun yarn is a bundle of fibres in air (cotton: cellulose, n ≈ 1.53–1.59, 12–20 µm across, 40–60 %
of the yarn's volume).  Light meets fibre surfaces, each reflecting a few percent *undyed*, and is
absorbed by the dye only inside a fibre, so the dye is the fibre material's absorption index
``k(λ) = μ_a(λ) λ / 4π`` (:func:`fibre_index`: the dye's ``μ_a = ε w ρ_f`` of
:mod:`precompute.optics.dye`, plus the fibre's own grey absorption), not an absorption of the whole
yarn volume.

Per-fibre scattering, a first physical model, randomly oriented:

* **An equal volume-to-surface sphere as the fibre's proxy**.  A collection of independent spheres
  with the same volume-to-surface ratio as a non-spherical particle reproduces its extinction,
  absorption and, closely, its asymmetry parameter (Grenfell & Warren, "Representation of a
  nonspherical ice particle by a collection of independent spheres for scattering and absorption of
  radiation", J. Geophys. Res. 104 (D24), 31697 (1999); Neshyba, Grenfell & Warren, JGR 108 (D15),
  4448 (2003) for hexagonal columns).  For a long circular fibre of diameter ``d``, V/S = d/4, so the
  proxy's diameter is ``1.5 d`` (:func:`proxy_diameter_nm`), at the fibres' volume fraction: the
  extinction per volume is then the fibres' mean projected area per volume, ``φ/d`` (Cauchy: S/4V
  for any convex body), and the mean chord through the proxy, ``4V/S``, the fibre's.
* **Exact Mie theory of the absorbing proxy** (miepython, complex index), in the host.
* **The diffraction peak removed**.  For particles much larger than the wavelength, half the Mie
  extinction is Fraunhofer diffraction into a peak of width ~λ/d about the forward direction (the
  extinction paradox, van de Hulst 1957, §8.22).  In a densely packed medium the particles lie in
  each other's near field and that peak does not form: the diffraction is no scattering and is left
  out (Mishchenko, "Asymmetry parameters of the phase function for densely packed scattering grains",
  JQSRT 52, 95 (1994); the same in snow's geometric-optics model, Kokhanovsky & Zege, "Scattering
  optics of snow", Appl. Opt. 43, 1589 (2004)).  Here the Fraunhofer pattern of the proxy's
  projected disc, ``dC/dΩ = a² x²/4 · [2 J₁(x sin θ)/(x sin θ)]²`` over the forward hemisphere
  (integral π a² for x ≫ 1), is subtracted from the Mie differential cross-section
  (:func:`fraunhofer_differential_cross_section`), what would fall below 0 clipped, and what
  remains is the fibre's reflection and refraction: ``μ_s = N C_geo``, ``μ_a = N C_abs`` with C_abs
  the Mie absorption.  A ray meeting a fibre then interacts with it, as in geometric optics.
* **The phase function: external reflection exactly, the light through the fibre by its mean
  cosine** (:func:`fibre_phase`).  The light a large convex particle in random orientation reflects
  off its outside has the angular pattern of a sphere's, ``dC/dΩ = (a²/4) R((π − Θ)/2)``, R the
  unpolarised Fresnel reflectance (van de Hulst 1957, chapters 8 and 12): undyed, white, and exact for
  randomly oriented fibres.  What passes through the fibre is not a sphere's: a sphere focuses its
  once-reflected-inside light back toward the source (the glory and the rainbow of a ball lens), which
  a cylinder does only across its axis and an irregular fibre not at all (nonspherical particles have
  smooth phase functions without them: Macke, Mueller & Raschke, J. Atmos. Sci. 53, 2813 (1996);
  Mishchenko, Rossow, Macke & Lacis, JGR 101, 16973 (1996)).  That part is therefore a
  Henyey–Greenstein lobe whose mean cosine makes the whole phase function's g the proxy's Mie g
  (less diffraction), the quantity equal volume-to-surface spheres do reproduce (Grenfell & Warren).

Independent references (tests/test_fibre_optics.py): the reflection law against exact Mie theory of
an opaque sphere; the absorption against geometric optics, ``πa² (1 − R̄)``, as x grows.

Not yet here: the fibres' orientation along the yarn axis (a direction-dependent phase function:
the transport's kernel takes one phase function of cos Θ; docs/fitting.md, "A yarn of fibres").
"""

from __future__ import annotations

import math

import miepython
import numpy as np
from scipy.special import j1

from precompute.optics.dye import dye_absorption_coefficient
from precompute.optics.medium import Dye, Fibres
from precompute.optics.mie import (PHASE_TABLE_TOLERANCE, PhaseGridTooCoarse, SpeciesScattering,
                                   differential_scattering_cross_section)
from precompute.optics.phase import asymmetry_parameter, henyey_greenstein_phase, normalize_phase, phase_integral

#: The proxy sphere's diameter over the fibre's: equal volume-to-surface ratio (module docstring).
PROXY_DIAMETER_RATIO = 1.5
#: The mean cosine of the light through a fibre is held inside this (a Henyey–Greenstein lobe).
TRANSMITTED_G_LIMIT = 0.95


def proxy_diameter_nm(fibres: Fibres) -> float:
    """The diameter of the fibre's equal volume-to-surface sphere, nm (module docstring)."""
    return PROXY_DIAMETER_RATIO * fibres.diameter_um * 1000.0


def fibre_absorption_per_mm(fibres: Fibres, dye: Dye | None, wavelengths_nm: np.ndarray) -> np.ndarray:
    """(L,) absorption coefficient of the fibre material, 1/mm: its grey ``absorption_per_mm`` plus
    the dye's ``ε w ρ_f`` (:func:`precompute.optics.dye.dye_absorption_coefficient`)."""
    mu_a = np.full(len(wavelengths_nm), float(fibres.absorption_per_mm))
    if dye is not None:
        mu_a += dye_absorption_coefficient(dye, wavelengths_nm)
    return mu_a


def fibre_index(fibres: Fibres, dye: Dye | None, wavelengths_nm: np.ndarray) -> np.ndarray:
    """(L,) complex index ``n + ik`` of the (dyed) fibre material: ``k = μ_a λ / 4π`` (λ in vacuum)."""
    wavelengths_nm = np.asarray(wavelengths_nm, float)
    n = fibres.refractive_index.at(wavelengths_nm)
    k = fibre_absorption_per_mm(fibres, dye, wavelengths_nm) * wavelengths_nm * 1e-6 / (4.0 * math.pi)
    return n.real + 1j * (n.imag + k)


def fraunhofer_differential_cross_section(radius_nm: float, wavenumber: float, cos_theta: np.ndarray) -> np.ndarray:
    """``dC/dΩ`` (nm²/sr) of Fraunhofer diffraction by a disc of ``radius_nm`` for light of
    ``wavenumber`` (1/nm, in the host): ``a² x²/4 · [2 J₁(x sin θ)/(x sin θ)]²``, x = k a, on the
    forward hemisphere, 0 behind (its integral is π a² for x ≫ 1; van de Hulst 1957, chapter 8)."""
    x = wavenumber * radius_nm
    sin_theta = np.sqrt(np.clip(1.0 - cos_theta**2, 0.0, 1.0))
    u = x * sin_theta
    safe = np.where(u > 1e-8, u, 1.0)
    airy = np.where(u > 1e-8, 2.0 * j1(safe) / safe, 1.0)
    return np.where(cos_theta > 0.0, radius_nm**2 * x**2 / 4.0 * airy**2, 0.0)


def fresnel_reflectance(cos_i: np.ndarray, n: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance onto a dielectric of relative index ``n`` ≥ 1 at incidence
    cosine ``cos_i`` (Born & Wolf, chapter 1); 1 at grazing, 0 for ``n`` = 1."""
    c = np.clip(np.asarray(cos_i, float), 0.0, 1.0)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - c * c) / (n * n)))
    denominator_s, denominator_p = c + n * cos_t, n * c + cos_t
    safe_s, safe_p = np.where(denominator_s > 0, denominator_s, 1.0), np.where(denominator_p > 0, denominator_p, 1.0)
    r_s = np.where(denominator_s > 0, (c - n * cos_t) / safe_s, 1.0)
    r_p = np.where(denominator_p > 0, (n * c - cos_t) / safe_p, 1.0)
    return 0.5 * (r_s**2 + r_p**2)


def reflection_differential_cross_section(radius_nm: float, n: float, cos_theta: np.ndarray) -> np.ndarray:
    """``dC/dΩ = (a²/4) R((π − Θ)/2)`` (nm²/sr): the external reflection of a large sphere of
    ``radius_nm`` and relative index ``n``, and of any large convex particle of its surface in random
    orientation (van de Hulst 1957, chapters 8 and 12), at scattering angle Θ = arccos ``cos_theta``."""
    incidence = (np.pi - np.arccos(np.clip(cos_theta, -1.0, 1.0))) / 2.0
    return radius_nm**2 / 4.0 * fresnel_reflectance(np.cos(incidence), n)


def fibre_phase(cos_theta: np.ndarray, reflected: np.ndarray, c_geometric: float, g_geometric: float) -> np.ndarray:
    """The fibres' phase function (1/sr) on ``cos_theta`` (module docstring): their external
    reflection ``reflected`` (dC/dΩ, nm²/sr) exactly, and the rest of ``c_geometric`` (nm²) in a
    Henyey–Greenstein lobe whose mean cosine makes the whole one's ``g_geometric``."""
    c_reflected = float(phase_integral(cos_theta, reflected))
    c_through = max(c_geometric - c_reflected, 0.0)
    if c_through <= 0.0:
        return normalize_phase(cos_theta, reflected)
    g_reflected = float(asymmetry_parameter(cos_theta, reflected / c_reflected)) if c_reflected > 0 else 0.0
    g_through = (g_geometric * (c_through + c_reflected) - g_reflected * c_reflected) / c_through
    g_through = float(np.clip(g_through, -TRANSMITTED_G_LIMIT, TRANSMITTED_G_LIMIT))
    return normalize_phase(cos_theta, reflected + c_through * henyey_greenstein_phase(cos_theta, g_through))


def fibre_scattering(fibres: Fibres, dye: Dye | None, wavelengths_nm: np.ndarray, host_index: np.ndarray,
                     cos_theta: np.ndarray) -> SpeciesScattering:
    """μs, μa (1/mm) and phase function of the fibres in a host of real index ``host_index`` (L,),
    on the caller's ``cos_theta`` grid (module docstring: the equal volume-to-surface proxy's Mie
    scattering with its diffraction peak removed).  Raises :class:`precompute.optics.mie.PhaseGridTooCoarse`
    when the grid's integral of the Mie cross-section misses it by more than
    :data:`precompute.optics.mie.PHASE_TABLE_TOLERANCE`, as for any particle (an automatic grid is
    then refined).  What is left after the diffraction is taken out is ``Q_sca − 1`` only as x → ∞:
    at finite x the edge terms of the extinction (``Q_ext − 2 ∝ x^(−2/3)``, van de Hulst 1957,
    chapter 17) stay in it."""
    wavelengths_nm = np.asarray(wavelengths_nm, float)
    diameter = proxy_diameter_nm(fibres)
    radius = diameter / 2.0
    area = math.pi * radius**2
    density_per_nm3 = fibres.volume_fraction / (math.pi * diameter**3 / 6.0)
    index = fibre_index(fibres, dye, wavelengths_nm)
    count = len(wavelengths_nm)
    mu_s, mu_a = np.zeros(count), np.zeros(count)
    phase = np.full((count, len(cos_theta)), 1.0 / (4.0 * math.pi))
    for i, (wavelength, n_host, n_fibre) in enumerate(zip(wavelengths_nm, host_index, index)):
        m = complex(n_fibre.real, -n_fibre.imag)  # miepython writes an absorbing index n − ik
        qext, qsca, _, _ = miepython.efficiencies(m, diameter, wavelength, n_env=n_host)
        wavenumber = 2.0 * math.pi * n_host / wavelength
        mie = differential_scattering_cross_section(m / n_host, wavenumber * radius, wavenumber, cos_theta)
        miss = abs(float(phase_integral(cos_theta, mie)) / (qsca * area) - 1.0)
        if miss > PHASE_TABLE_TOLERANCE:
            raise PhaseGridTooCoarse(len(cos_theta), f"a finer cos θ grid (or \"auto\"): the fibres' Mie "
                                     f"cross-section at {wavelength:g} nm is missed by {miss:.1e}", miss)
        geometric = np.clip(mie - fraunhofer_differential_cross_section(radius, wavenumber, cos_theta), 0.0, None)
        c_geometric = float(phase_integral(cos_theta, geometric))
        mu_s[i] = density_per_nm3 * c_geometric * 1e6
        mu_a[i] = density_per_nm3 * max(qext - qsca, 0.0) * area * 1e6
        if c_geometric > 0.0:
            g_geometric = float(asymmetry_parameter(cos_theta, geometric / c_geometric))
            reflected = reflection_differential_cross_section(radius, n_fibre.real / n_host, cos_theta)
            phase[i] = fibre_phase(cos_theta, reflected, c_geometric, g_geometric)
    return SpeciesScattering(mu_s=mu_s, mu_a=mu_a, phase=phase, number_density_per_um3=density_per_nm3 * 1e9)


__all__ = ["PROXY_DIAMETER_RATIO", "TRANSMITTED_G_LIMIT", "fibre_absorption_per_mm", "fibre_index", "fibre_phase",
           "fibre_scattering", "fraunhofer_differential_cross_section", "fresnel_reflectance", "proxy_diameter_nm",
           "reflection_differential_cross_section"]
