"""Plots of a baked yarn: what to look at before trusting a bake (matplotlib, Agg backend).

* :func:`plot_in_plane`: ρ vs θo in the plane of incidence for several θi,
  across and along the yarn (the paper's Figure 11), with ±1 standard error;
* :func:`plot_polar`: ρ over the exit hemisphere (θo radial, φo around, φo = 0
  along the yarn axis) for a few incidences;
* :func:`plot_albedo_spectra`: the yarn's hemispherical albedo ∫ρ cos θo dωo
  per wavelength for light from the front and from behind, beside the
  medium's single-scattering albedo μs/(μs + μa);
* :func:`plot_swatches`: the yarn's colour seen along its normal under white
  light from the front and from behind (the paper's Figures 9–10).

Table values are read back exactly as the shader interpolates them
(:func:`precompute.tables.layout.interpolate_rho`).  Directions are in the
yarn frame: x = yarn axis, y = n × t, z = outward normal.
"""

from __future__ import annotations

import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from precompute.tables.color import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, channel_ratios, clip_to_gamut, spectral_to_rgb
from precompute.tables.layout import brdf_atlas, interpolate_rho

#: Incidence angles of the in-plane curves, degrees (the paper's sweep: 0, 30, 45, 60).
INCIDENCE_DEG = (0, 30, 45, 60)
#: Rec.709 luminance weights of linear R, G, B.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
DPI = 110


def _in_plane(theta_deg, plane: str) -> np.ndarray:
    """Unit direction(s) at signed zenith ``theta_deg`` in the plane across (y–z) or along (x–z) the yarn."""
    theta = np.radians(np.asarray(theta_deg, float))
    zero = np.zeros_like(theta)
    x, y = (np.sin(theta), zero) if plane == "along" else (zero, np.sin(theta))
    return np.stack([x, y, np.cos(theta)], axis=-1)


def _direction(theta_deg: float, phi_deg: float) -> np.ndarray:
    theta, phi = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def _save(fig, path) -> pathlib.Path:
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return pathlib.Path(path)


def plot_in_plane(atlas, incidence_resolution: int, path, stderr_atlas=None) -> pathlib.Path:
    """Luminance of ρ vs θo in the plane of incidence, θi = 0, 30, 45, 60° (paper Figure 11).

    As in the paper's graphs, negative θo lie on the light's side of the
    normal and positive ones on the mirror side.  ``stderr_atlas`` (the
    ``brdf_stderr`` table) adds a ±1 standard-error band.
    """
    theta_out = np.arange(-85.0, 85.1, 2.5)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, plane in zip(axes, ("across", "along")):
        wo = _in_plane(theta_out, plane)
        for theta_in in INCIDENCE_DEG:
            wi = np.broadcast_to(_in_plane(-theta_in, plane), wo.shape)
            rho = interpolate_rho(atlas, incidence_resolution, wi, wo) @ LUMINANCE
            (line,) = ax.plot(theta_out, rho, label=f"θi = {theta_in}°")
            if stderr_atlas is not None:
                error = interpolate_rho(stderr_atlas, incidence_resolution, wi, wo) @ LUMINANCE
                ax.fill_between(theta_out, rho - error, rho + error, color=line.get_color(), alpha=0.2, lw=0)
        ax.set_title(f"plane of incidence {plane} the yarn axis")
        ax.set_xlabel("θo (deg); negative: the light's side of the normal")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("ρ luminance (1/sr) = L_o / E⊥")
    axes[0].legend()
    fig.tight_layout()
    return _save(fig, path)


def plot_polar(atlas, incidence_resolution: int, path) -> pathlib.Path:
    """Luminance of ρ over the exit hemisphere for light along the normal, at 45° and 60°, and from behind."""
    cases = {
        "normal": _direction(0, 0),
        "45° across": _direction(45, 90),
        "45° along": _direction(45, 0),
        "60° across": _direction(60, 90),
        "from behind": _direction(180, 0),
    }
    theta_edges = np.linspace(0.0, 90.0, 19)
    phi_edges = np.linspace(0.0, 360.0, 49)
    theta_mid = 0.5 * (theta_edges[1:] + theta_edges[:-1])
    phi_mid = 0.5 * (phi_edges[1:] + phi_edges[:-1])
    wo = np.array([[_direction(t, p) for p in phi_mid] for t in theta_mid])
    fig, axes = plt.subplots(1, len(cases), figsize=(3.3 * len(cases), 3.6), subplot_kw={"projection": "polar"})
    for ax, (label, wi) in zip(axes, cases.items()):
        rho = interpolate_rho(atlas, incidence_resolution, np.broadcast_to(wi, wo.shape), wo) @ LUMINANCE
        mesh = ax.pcolormesh(np.radians(phi_edges), theta_edges, rho, cmap="magma", shading="flat")
        ax.set_title(f"light {label}", fontsize=9)
        ax.set_yticks([30, 60, 90])
        ax.set_yticklabels(["30°", "60°", "90°"], fontsize=7)
        ax.set_xticks(np.radians([0, 90, 180, 270]))
        ax.set_xticklabels(["+x (axis)", "+y", "−x", "−y"], fontsize=7)
        fig.colorbar(mesh, ax=ax, shrink=0.7, pad=0.12).ax.tick_params(labelsize=7)
    fig.suptitle("ρ luminance (1/sr) over the exit directions; radius θo, angle φo from the yarn axis", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _at_incidence(per_cell: np.ndarray, incidence_resolution: int, wi) -> np.ndarray:
    """Values per incidence cell (N_i², C) at direction ``wi``, bilinear between cell centres as the shader does."""
    # Constant 2 × 2 tiles (the smallest exit grid): the exit interpolation returns the cell's value.
    image = brdf_atlas(np.repeat(np.asarray(per_cell, float)[:, None, :], 4, axis=1))
    return interpolate_rho(image, incidence_resolution, np.asarray(wi, float), np.array([0.0, 0.0, 1.0]))


def plot_albedo_spectra(spectral: dict, incidence_resolution: int, path) -> pathlib.Path:
    """Hemispherical albedo spectra of the yarn (light from the front, at 60°, from behind) and the medium's
    single-scattering albedo.  ``spectral``: the arrays of a bake's spectral.npz."""
    wavelengths = spectral["wavelengths_nm"]
    albedo = spectral["hemispherical_albedo"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, wi in (("front (normal)", _direction(0, 0)), ("60° across", _direction(60, 90)),
                      ("from behind", _direction(180, 0))):
        spectrum = _at_incidence(albedo, incidence_resolution, wi)
        left.plot(wavelengths, spectrum, marker="o", ms=3, label=f"light {label}")
    left.set_yscale("log")
    left.set_xlabel("wavelength (nm)")
    left.set_ylabel("yarn albedo ∫ρ cos θo dωo")
    left.set_title("hemispherical albedo at a point of the yarn")
    left.grid(alpha=0.3, which="both")
    left.legend()
    mu_s, mu_a = spectral["mu_s"], spectral["mu_a"]
    right.plot(wavelengths, mu_s / (mu_s + mu_a), marker="o", ms=3, color="k")
    right.set_xlabel("wavelength (nm)")
    right.set_ylabel("μs / (μs + μa)")
    right.set_title("single-scattering albedo of the medium")
    right.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, path)


def _display(rgb: np.ndarray) -> np.ndarray:
    """sRGB-encoded display values of linear Rec.709 RGB, clipped to [0, 1]."""
    rgb = np.clip(rgb, 0.0, 1.0)
    return np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1 / 2.4) - 0.055)


def plot_swatches(spectral: dict, incidence_resolution: int, path,
                  illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER) -> pathlib.Path:
    """The yarn seen along its normal under white light from the front and from behind (paper Figures 9–10).

    Top row: one exposure for both (the brightest channel of the two at
    display white) — the relative brightness.  Bottom row: each at its own
    exposure — the hue.  White is the bake's illuminant.
    """
    wavelengths = spectral["wavelengths_nm"]
    rho = spectral["rho"]
    n_o = int(round(math.sqrt(rho.shape[1])))
    atlas = brdf_atlas(rho)
    normal = np.array([0.0, 0.0, 1.0])
    colours = {}
    for label, wi in (("front", normal), ("behind", -normal)):
        spectrum = interpolate_rho(atlas, incidence_resolution, wi, normal)
        colours[label] = clip_to_gamut(spectral_to_rgb(spectrum, wavelengths, illuminant, observer))[0]
    exposure = 1.0 / max(max(rgb.max() for rgb in colours.values()), 1e-30)
    fig, axes = plt.subplots(2, 2, figsize=(6.4, 6.4))
    for column, (label, rgb) in enumerate(colours.items()):
        ratios = channel_ratios(rgb)
        for row, scale in enumerate((exposure, 1.0 / max(rgb.max(), 1e-30))):
            axes[row, column].imshow(np.ones((8, 8, 3)) * _display(rgb * scale))
            axes[row, column].set_xticks([])
            axes[row, column].set_yticks([])
        axes[0, column].set_title(f"white light from {label}\nρ(normal view) = {rgb.max():.3g}/sr (max channel)",
                                  fontsize=9)
        axes[1, column].set_xlabel(f"B/R = {ratios['B/R']:.3g}, G/R = {ratios['G/R']:.3g}", fontsize=9)
    axes[0, 0].set_ylabel("same exposure", fontsize=9)
    axes[1, 0].set_ylabel("each at its own exposure", fontsize=9)
    fig.suptitle(f"scattered light of the yarn seen along its normal ({illuminant} white; exit grid {n_o}×{n_o})",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, path)
