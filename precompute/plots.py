"""Plots of a baked yarn: what people look at before trusting a bake.

* in-plane ρ vs θo for several θi, in the plane across the yarn and the plane along it (Figure 11);
* ρ over the exit hemisphere for a few incidences (equal-area "polar" maps);
* spectra of the yarn's hemispherical albedo for light from the front and from behind;
* colour swatches of the yarn lit by white light from the front and from behind (Figures 9–10).
"""

from __future__ import annotations

import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .color import clip_to_gamut, spectral_to_rgb  # noqa: E402
from .table_layout import interpolate_rho, rho_from_brdf_atlas  # noqa: E402

INCIDENCE_DEG = (0, 30, 45, 60)


def _plane_direction(theta_deg, plane: str) -> np.ndarray:
    t = math.radians(theta_deg)
    return np.array([math.sin(t), 0.0, math.cos(t)]) if plane == "along" else np.array([0.0, math.sin(t), math.cos(t)])


def plot_in_plane(atlas, incidence_resolution, path) -> pathlib.Path:
    """ρ (red channel and luminance-ish mean) vs θo in the planes across and along the yarn (paper Fig. 11)."""
    theta_out = np.arange(-85, 86, 5)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, plane in zip(axes, ("across", "along")):
        for theta_in in INCIDENCE_DEG:
            wi = _plane_direction(-theta_in, plane)  # light on the negative side
            wo = np.array([_plane_direction(t, plane) for t in theta_out])
            rho = interpolate_rho(atlas, incidence_resolution, np.broadcast_to(wi, wo.shape), wo)
            ax.plot(theta_out, rho[:, 0], label=f"θi = {theta_in}°")
        ax.set_title(f"plane {plane} the yarn axis")
        ax.set_xlabel("θo (deg); negative: the light's side")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("ρ red channel (1/sr) = L_o / E⊥")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return pathlib.Path(path)


def plot_exit_maps(atlas, incidence_resolution, path) -> pathlib.Path:
    """ρ (red) over the equal-area exit square for incidences along the normal, oblique and from behind."""
    rho = rho_from_brdf_atlas(atlas, incidence_resolution)
    from .grids import AngularGrid

    grid = AngularGrid("sphere", incidence_resolution)
    n_o = int(round(math.sqrt(rho.shape[1])))
    cases = {"normal (0, 0, 1)": [0, 0, 1], "45° across": [0, -0.707, 0.707], "45° along": [-0.707, 0, 0.707],
             "from behind (0, 0, −1)": [0, 0, -1]}
    fig, axes = plt.subplots(1, len(cases), figsize=(3.2 * len(cases), 3.2))
    for ax, (label, direction) in zip(axes, cases.items()):
        cell = grid.cell_of(np.array(direction, float) / np.linalg.norm(direction))
        image = rho[cell, :, 0].reshape(n_o, n_o)
        ax.imshow(image, origin="upper", extent=(0, 1, 1, 0), cmap="magma")
        ax.set_title(f"light {label}", fontsize=9)
        ax.set_xlabel("s (exit, equal-area)")
    axes[0].set_ylabel("t")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return pathlib.Path(path)


def plot_albedo_spectra(spectral: dict, incidence_resolution, path) -> pathlib.Path:
    from .grids import AngularGrid

    grid = AngularGrid("sphere", incidence_resolution)
    wl = spectral["wavelengths_nm"]
    albedo = spectral["hemispherical_albedo"]
    fig, ax = plt.subplots(figsize=(6, 4))
    for label, direction in (("light from the front (normal)", [0, 0, 1.0]), ("light from behind", [0, 0, -1.0])):
        ax.plot(wl, albedo[grid.cell_of(np.array(direction))], marker="o", ms=3, label=label)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("hemispherical albedo ∫ρ cosθo dωo")
    ax.set_yscale("log")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return pathlib.Path(path)


def plot_swatches(spectral: dict, incidence_resolution, path) -> pathlib.Path:
    """The yarn's colour under white light from the front and from behind (paper Figs. 9–10), each
    normalised to its own brightness so hue is comparable, with its relative brightness printed."""
    from .grids import AngularGrid

    grid = AngularGrid("sphere", incidence_resolution)
    wl = spectral["wavelengths_nm"]
    fig, axes = plt.subplots(1, 2, figsize=(6, 3))
    values = {}
    for label, direction in (("front", [0, 0, 1.0]), ("behind", [0, 0, -1.0])):
        rgb, _ = clip_to_gamut(spectral_to_rgb(spectral["hemispherical_albedo"][grid.cell_of(np.array(direction))], wl))
        values[label] = rgb
    brightest = max(v.max() for v in values.values()) or 1.0
    for ax, (label, rgb) in zip(axes, values.items()):
        shown = rgb / (rgb.max() or 1.0)
        display = np.where(shown <= 0.0031308, 12.92 * shown, 1.055 * np.power(shown, 1 / 2.4) - 0.055)
        ax.imshow(np.ones((10, 10, 3)) * display)
        ax.set_title(f"lit from {label}\nrelative brightness {rgb.max() / brightest:.3f}", fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return pathlib.Path(path)
