"""Validation outputs: JSON results, plots like the paper's graphs 1–6, and a Markdown report."""

from __future__ import annotations

import dataclasses
import json
import pathlib

import numpy as np


def write_json(path, results: dict) -> pathlib.Path:
    def plain(value):
        if dataclasses.is_dataclass(value):
            return dataclasses.asdict(value)
        if isinstance(value, np.ndarray):
            return value.tolist()
        raise TypeError(type(value).__name__)

    pathlib.Path(path).write_text(json.dumps(results, indent=2, default=plain))
    return pathlib.Path(path)


def plot_sweeps(path, curves: dict, incidences, measurement=None, quantity: str = "brdf_rgb") -> pathlib.Path:
    """Red-channel BRDF (``quantity``) vs signed view angle, one panel per incidence, one line per material."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = min(len(incidences), 2)
    rows = (len(incidences) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(5.5 * columns, 3.8 * rows), squeeze=False)
    for ax, theta_i in zip(axes.ravel(), incidences):
        for label, views in curves.items():
            points = [(v.theta_v_deg, getattr(v, quantity)[0]) for v in views
                      if v.theta_i_deg == theta_i and getattr(v, quantity)]
            if points:
                x, y = zip(*points)
                ax.plot(x, y, marker="o", ms=3, label=label)
        if measurement is not None:
            x, y = measurement.in_plane(theta_i)
            if len(x):
                ax.plot(x, y[:, 0], "k--", marker="s", ms=3, label="measurement")
        ax.set_title(f"θi = {theta_i:g}°")
        ax.set_xlabel("θv (deg); negative: the light's side")
        ax.set_ylabel("cloth BRDF, red (1/sr)" + (", paper-normalised" if quantity != "brdf_rgb" else ""))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    for ax in axes.ravel()[len(incidences):]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return pathlib.Path(path)


def write_markdown(path, results: dict, plot_name: str) -> pathlib.Path:
    lines = ["# ClothLight validation sweep", "",
             f"Sample: {results['sample']}", "",
             f"![in-plane sweeps]({plot_name})", "",
             "## Colour at normal incidence and view (paper Table 1)", "",
             "| material | B/R | G/R |", "| --- | --- | --- |"]
    for name, ratios in results["table1_ratios"].items():
        lines.append(f"| {name} | {ratios['B/R']:.4g} | {ratios['G/R']:.4g} |")
    lines += ["| real red cotton (paper) | 0.08 | 0.011 |", ""]
    if results.get("metrics"):
        lines += ["## Against the measurement", "", "![paper-normalised](sweeps_paper_normalised.png)", "",
                  "| material | RMS (1/sr) | relative RMS | relative RMS, paper-normalised | shape correlation |",
                  "| --- | --- | --- | --- | --- |"]
        for name, m in results["metrics"].items():
            lines.append(f"| {name} | {m['rms']:.4g} | {m['relative_rms']:.3g} | "
                         f"{m['paper_normalised_relative_rms']:.3g} | {m['shape_correlation']:.3f} |")
        lines.append("")
    lines += ["## Cloth BRDF, red channel (1/sr)", "", "| θi | θv | " + " | ".join(results["curves"]) + " |",
              "| --- | --- | " + " | ".join("---" for _ in results["curves"]) + " |"]
    first = next(iter(results["curves"].values()))
    for k, view in enumerate(first):
        values = " | ".join(f"{curve[k]['brdf_rgb'][0]:.4g}" for curve in results["curves"].values())
        lines.append(f"| {view['theta_i_deg']:g} | {view['theta_v_deg']:g} | {values} |")
    pathlib.Path(path).write_text("\n".join(lines) + "\n")
    return pathlib.Path(path)
