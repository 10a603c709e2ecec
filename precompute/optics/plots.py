"""A one-page PNG of a medium's optics, to look at before trusting a bake.

Panels: μs and μa (1/mm, log scale), single-scattering albedo and asymmetry g
against wavelength, and the phase function against scattering angle at a few
wavelengths.  A second :class:`~precompute.optics.coefficients.MediumOptics` (e.g. the same
medium with the Percus–Yevick correction) can be drawn dashed for comparison.
Uses matplotlib's Agg canvas directly, so no display and no global backend
switch are involved.
"""

from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from precompute.errors import ParameterError
from precompute.optics.coefficients import MediumOptics

#: Wavelengths (nm) whose phase functions are drawn when the grid contains them; otherwise the nearest.
PHASE_WAVELENGTHS_NM = (400.0, 550.0, 700.0)


def _phase_rows(optics: MediumOptics, wavelengths_nm) -> list[int]:
    rows = []
    for wavelength in wavelengths_nm:
        row = int(np.argmin(np.abs(optics.wavelengths_nm - wavelength)))
        if row not in rows:
            rows.append(row)
    return rows


def plot_medium_optics(
    optics: MediumOptics,
    path: str | pathlib.Path,
    *,
    title: str = "",
    comparison: MediumOptics | None = None,
    comparison_label: str = "",
    phase_wavelengths_nm=PHASE_WAVELENGTHS_NM,
) -> pathlib.Path:
    """Write the optics of ``optics`` (and, dashed, of ``comparison``) as a PNG at ``path``; return the path."""
    path = pathlib.Path(path)
    if path.suffix.lower() != ".png":
        raise ParameterError("plot", str(path), "a file name ending in .png")
    if not path.parent.is_dir():
        raise ParameterError("plot", str(path), "a path in an existing folder")
    main_label = "independent" if optics.dependent_scattering == "none" else optics.dependent_scattering
    figure = Figure(figsize=(12, 7.5), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(2, 3)
    wl = optics.wavelengths_nm
    series = [(optics, "-", main_label)]
    if comparison is not None:
        series.append((comparison, "--", comparison_label))
    for data, style, label in series:
        axes[0, 0].semilogy(data.wavelengths_nm, data.mu_s, style, color="C0", label=f"μs {label}")
        axes[0, 0].semilogy(data.wavelengths_nm, np.maximum(data.mu_a, 1e-6), style, color="C3", label=f"μa {label}")
        axes[0, 1].plot(data.wavelengths_nm, data.albedo, style, color="C2", label=label)
        axes[0, 2].plot(data.wavelengths_nm, data.g, style, color="C1", label=label)
    axes[0, 0].set(xlabel="wavelength (nm)", ylabel="coefficient (1/mm)", title="scattering μs, absorption μa")
    axes[0, 1].set(xlabel="wavelength (nm)", ylabel="albedo μs/μt", title="single-scattering albedo", ylim=(0, 1.02))
    axes[0, 2].set(xlabel="wavelength (nm)", ylabel="g = ⟨cos θ⟩", title="asymmetry parameter")
    for axis in axes[0]:
        if len(wl) > 1:
            axis.set_xlim(wl[0], wl[-1])
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    theta_deg = np.degrees(np.arccos(np.clip(optics.cos_theta, -1.0, 1.0)))
    rows = _phase_rows(optics, phase_wavelengths_nm)
    for colour, row in enumerate(rows):
        label = f"{wl[row]:g} nm"
        axes[1, 0].semilogy(theta_deg, optics.phase[row], color=f"C{colour}", label=f"{label} {main_label}")
        axes[1, 1].plot(optics.cos_theta, optics.phase[row] * 4.0 * np.pi, color=f"C{colour}", label=label)
        if comparison is not None:
            theta_c = np.degrees(np.arccos(np.clip(comparison.cos_theta, -1.0, 1.0)))
            axes[1, 0].semilogy(
                theta_c, comparison.phase[row], "--", color=f"C{colour}", label=f"{label} {comparison_label}"
            )
    axes[1, 0].set(xlabel="scattering angle θ (deg)", ylabel="p(θ) (1/sr)", title="phase function", xlim=(0, 180))
    axes[1, 1].set(xlabel="cos θ", ylabel="4π p(cos θ)", title=f"phase function ({main_label}), linear", xlim=(-1, 1))
    for axis in axes[1, :2]:
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    axes[1, 2].axis("off")
    summary = [
        f"{wl[row]:g} nm: μs {optics.mu_s[row]:.3g}/mm, μa {optics.mu_a[row]:.3g}/mm,\n"
        f"        albedo {optics.albedo[row]:.3f}, g {optics.g[row]:.3f}"
        for row in rows
    ]
    summary.append(f"boundary index {optics.boundary_index:.4f}")
    axes[1, 2].text(
        0.0,
        1.0,
        "\n".join(summary),
        va="top",
        ha="left",
        fontsize=9,
        family="monospace",
        transform=axes[1, 2].transAxes,
    )
    figure.suptitle(title or "medium optics")
    figure.savefig(path, dpi=110)
    return path
