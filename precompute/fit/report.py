"""What a fit writes: the fitted preset, ``fit.json``, ``report.md`` and three plots, as one folder.

``--out DIR`` receives, all at once (:func:`precompute.tables.folder.replace_folder`: written into a
staging folder beside it and swapped in at the end, so an interrupted or failed fit leaves no
partial folder):

``preset.toml``
    The fitted medium as a preset TOML (``python -m precompute bake --config DIR/preset.toml``):
    the input preset with the fitted values; relative data files that resolved next to the input
    preset are written as absolute paths (those of ``precompute/data`` stay relative).  The fitted
    specular term goes in a ``[fit]`` table (``specular_weight``, ``specular_slope``), which the
    medium's loader ignores.
``fit.json``
    Everything: parameters, bounds, metrics, baseline, every view's measured / model / baseline
    BRDF, and the whole history (:meth:`FitResult.to_dict`).
``report.md``
    The summary a person reads: parameters and where they ended, the relative RMS errors of the
    model and the baseline on fit and held-out views per channel, the figures.
``fit.png``, ``residuals.png``, ``history.png``
    Measured vs model vs baseline per incidence (plane of incidence and the held-out azimuths, one
    curve each), their residuals, and the objective of every evaluation coloured by its accuracy.
"""

from __future__ import annotations

import json
import math
import os
import pathlib
import re

import numpy as np

from precompute.optics import medium as medium_module
from precompute.outputs import json_ready
from precompute.tables.folder import check_output_folder, replace_folder
from precompute.optics.measured_sample import sample_azimuths_deg, sample_weave_name
from precompute.fit.objective import CHANNELS
from precompute.fit.optimise import FitResult
from precompute.optics.cook_torrance import FIT_TABLE

PRESET_FILE = "preset.toml"
JSON_FILE = "fit.json"
REPORT_FILE = "report.md"
PLOT_FILES = {"fit": "fit.png", "residuals": "residuals.png", "history": "history.png"}
#: Every file a fit folder holds.
FIT_FOLDER_FILES = (PRESET_FILE, JSON_FILE, REPORT_FILE, *PLOT_FILES.values())
_COLOURS = {"R": "#d62728", "G": "#2ca02c", "B": "#1f77b4"}
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


# ---- the output folder --------------------------------------------------------------------------


def check_fit_folder(out: str | os.PathLike, option: str = "--out") -> pathlib.Path:
    """``out`` (its real path) if a fit may write it: absent, or a folder holding only an earlier
    fit's files, in a writable place.  ParameterError naming ``option`` otherwise; called before any
    work."""
    return check_output_folder(out, FIT_FOLDER_FILES, option, job="fit")


def write_fit_folder(result: FitResult, out: str | os.PathLike, *, measured_name: str = "", option: str = "--out",
                     figures: bool = True) -> pathlib.Path:
    """Write every file of a fit (module docstring) into ``out`` as a whole; its real path.  Without
    ``figures`` (a Python without matplotlib, as Blender's) the folder holds no plots and the report
    says so."""
    check_fit_folder(out, option)

    def write(folder: pathlib.Path) -> None:
        (folder / PRESET_FILE).write_text(preset_toml(result, measured_name), encoding="utf-8")
        (folder / JSON_FILE).write_text(json.dumps(fit_summary(result, measured_name), indent=1, allow_nan=False),
                                        encoding="utf-8")
        if figures:
            write_plots(result, folder)
        (folder / REPORT_FILE).write_text(report_markdown(result, measured_name, figures=figures), encoding="utf-8")

    return replace_folder(out, write, FIT_FOLDER_FILES, option)


def fit_summary(result: FitResult, measured_name: str = "") -> dict:
    """``fit.json``'s content: :meth:`FitResult.to_dict` with the measurement named and NaN as null."""
    return json_ready({"measured": measured_name, "preset": result.config.get("name"), **result.to_dict()})


# ---- the preset ---------------------------------------------------------------------------------


def fitted_preset_config(result: FitResult, measured_name: str = "") -> dict:
    """The fitted preset's content: the fit's config with a new name and description, relative data
    files made to resolve from anywhere, and the ``[fit]`` table (the specular term)."""
    config = json.loads(json.dumps(result.config))  # a deep, plain copy
    name = str(config.get("name", "custom"))
    config["name"] = name if name.endswith("_fit") else f"{name}_fit"
    values = ", ".join(f"{p.name} = {result.parameters[p.name]:.4g}" for p in result.free)
    config["description"] = (f"{name} fitted to {measured_name or 'a measurement'} by python -m clothlight.fit "
                             f"({values})")
    absolute_data_files(config, result.base_dir)
    config[FIT_TABLE] = {key: float(value) for key, value in result.specular.items()}
    return config


def absolute_data_files(config: dict, base_dir: pathlib.Path) -> None:
    """Point ``config``'s data files (``csv``, ``spectrum_csv``) that sit beside its TOML in ``base_dir``
    at their absolute paths, so that the preset reads the same written anywhere; shipped ones stay named."""
    def absolute(value: str) -> str:
        beside = pathlib.Path(base_dir) / value
        shipped = medium_module.DATA_DIR / value
        if not pathlib.Path(value).is_absolute() and beside.is_file() and beside.resolve() != shipped.resolve():
            return str(beside.resolve())
        return value

    def visit(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("csv", "spectrum_csv") and isinstance(value, str):
                    node[key] = absolute(value)
                elif key == "spectrum_csv" and isinstance(value, list):  # a shade recipe's dyes
                    node[key] = [absolute(item) if isinstance(item, str) else item for item in value]
                else:
                    visit(value)
        elif isinstance(node, list):
            for item in node:
                visit(item)

    visit(config)


def preset_toml(result: FitResult, measured_name: str = "") -> str:
    """The fitted preset as TOML text (module docstring), with a header saying how it was made."""
    config = fitted_preset_config(result, measured_name)
    lines = [f"# Fitted by `python -m clothlight.fit` to {measured_name or 'a measurement'} (seed {result.seed}).",
             f"# Objective (relative RMS on the plane of incidence): {result.objective:.4g}; "
             f"held-out views: {_show(result.metrics['model']['held_out_views']['relative_rms'])}.",
             "# Free parameters: " + ", ".join(f"{p.name} = {result.parameters[p.name]:.6g}"
                                               + (f" {p.unit}" if p.unit else "") for p in result.free)]
    lines += [f"# Note: {hit}" for hit in result.bound_hits]
    return "\n".join(lines) + "\n\n" + to_toml(config)


def to_toml(config: dict) -> str:
    """A preset's content as TOML: top-level values first, then tables (``[name]``), arrays of tables
    (``[[name]]``); tables within those as inline tables.  Reads back equal with :mod:`tomllib`."""
    out = []
    scalars = {k: v for k, v in config.items() if not _is_table(v) and not _is_table_array(v)}
    out += [f"{_key(k)} = {_toml_value(v)}" for k, v in scalars.items()]
    for key, value in config.items():
        if _is_table(value):
            out += ["", f"[{_key(key)}]"] + [f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()]
        elif _is_table_array(value):
            for table in value:
                out += ["", f"[[{_key(key)}]]"] + [f"{_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(out).lstrip("\n") + "\n"


def _is_table(value) -> bool:
    return isinstance(value, dict)


def _is_table_array(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _key(key: str) -> str:
    return key if _BARE_KEY.match(str(key)) else json.dumps(str(key), ensure_ascii=False)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


# ---- the report ---------------------------------------------------------------------------------


def _show(value) -> str:
    return "–" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.3g}"


def report_markdown(result: FitResult, measured_name: str = "", figures: bool = True) -> str:
    """``report.md`` (module docstring); without ``figures``, a line in place of the figures."""
    model, base = result.metrics["model"], result.metrics["baseline"]
    held_count = int(result.views.held_out.sum())
    lines = [f"# Medium fit: {result.config.get('name', 'custom')} to {measured_name or 'a measurement'}", "",
             f"{int(result.views.fit.sum())} fit views (plane of incidence), {held_count} held-out views "
             "(every other azimuth, never seen by the optimiser).  Objective: per-channel relative RMS error on "
             "the fit views, combined as their RMS over R, G, B"
             + (" plus the colour-ratio penalty" if result.target_ratios else "")
             + (" plus the band penalty" if result.bands else "") + " (docs/fitting.md).", "",
             f"- objective of the fitted medium (final evaluation at relative error {result.schedule.final:g}): "
             f"**{result.objective:.4g}** (estimate during the search: {result.estimate:.4g})",
             f"- {result.forward_evaluations} forward evaluations in {result.generations} generations, "
             f"{result.seconds:.1f} s; stopped by {result.stop_reason}",
             f"- seed {result.seed}; accuracy schedule {result.schedule.loose:g} → {result.schedule.tight:g} "
             f"(final {result.schedule.final:g})",
             f"- sample weave (the cloth the forward model renders, `[sample]`): {sample_weave_name(result.config)}, "
             f"averaged over the warp at {', '.join(f'{a:g}°' for a in sample_azimuths_deg(result.config))} "
             "from the plane of incidence"]
    if result.swatches:
        limit = result.swatches["max_back_front"]
        lines.append(f"- §6.1 swatches at normal view: lit from behind / from the front, luminance "
                     f"**{result.swatches['back_front_luminance']:.3g}**"
                     + (f" (asked: at most {limit:g})" if limit is not None else " (not constrained)"))
    if result.bands:
        low, high = result.bands["band"]
        lines.append(f"- held within {low:g}–{high:g}, model / measured (`--hold-bands`): "
                     + ", ".join(f"{key} **{ratio:.3g}**" for key, ratio in result.bands["ratios"].items())
                     + f"; band penalty {result.bands['penalty']:.3g}")
    lines.append("")
    if result.bound_hits:
        lines += ["## Bounds", ""] + [f"- **{hit}**" for hit in result.bound_hits] + [""]
    lines += ["## Parameters", "", "| parameter | fitted | start | range | unit | sets |", "|---|---|---|---|---|---|"]
    for p in result.free:
        side = p.at_bound(result.parameters[p.name])
        flag = f" (at the {side} bound)" if side else ""
        lines.append(f"| {p.name} | {result.parameters[p.name]:.4g}{flag} | {result.initial[p.name]:.4g} | "
                     f"{p.low:g}–{p.high:g} ({'log' if p.log else 'linear'}) | {p.unit or '–'} | `{p.path}` |")
    lines += ["", "Specular term given to the forward model: "
              + ", ".join(f"{k} = {v:.4g}" for k, v in result.specular.items()) + ".", ""]
    lines += ["## Errors", "",
              "Relative RMS error (RMS of model − measured over the RMS of the measured, per channel).", "",
              "| | views | R | G | B | RGB |", "|---|---|---|---|---|---|"]
    for label, terms in (("fitted medium", model), ("fitted baseline", base)):
        for views, key in (("fit", "fit_views"), ("held out", "held_out_views")):
            t = terms[key]
            lines.append(f"| {label} | {views} | {_show(t['R'])} | {_show(t['G'])} | {_show(t['B'])} | "
                         f"{_show(t['relative_rms'])} |")
    b = result.baseline
    lines += ["", f"Baseline (Lambert + Cook–Torrance about the cloth normal, fitted to the same views): albedo "
              f"R {b.albedo[0]:.3g}, G {b.albedo[1]:.3g}, B {b.albedo[2]:.3g}; weight {b.weight:.3g}, "
              f"rms slope m {b.slope:.3g}.", ""]
    if result.target_ratios:
        lines += ["## Colour targets (θi = 0, θo ≤ 10°)", "", "| ratio | target | fitted medium | baseline |",
                  "|---|---|---|---|"]
        for key, target in result.target_ratios.items():
            lines.append(f"| {key} | {target:g} | {_show(model['target_ratios'][key]['achieved'])} | "
                         f"{_show(base['target_ratios'][key]['achieved'])} |")
        lines.append("")
    bake = f"To bake the fitted medium at full accuracy: `python -m precompute bake --config {PRESET_FILE}`."
    if not figures:
        lines += ["## Figures", "",
                  "Not drawn: matplotlib is not installed in the Python that ran the fit (Blender's). `fit.json` "
                  "holds every view's measured, model and baseline BRDF.", "", bake, ""]
        return "\n".join(lines)
    lines += ["## Figures", "",
              "![measured, fitted medium and fitted baseline per incidence](fit.png)", "",
              "`fit.png`: per incidence θi (rows), the plane of incidence (left: signed view angle, negative on "
              "the light's side) and the held-out azimuths (right: the perpendicular plane ○ and, where measured, "
              "45° △ and 135° ▽ from the plane of incidence); markers measured, solid the fitted medium, dashed "
              "the fitted baseline, per channel.", "",
              "![residuals](residuals.png)", "",
              "`residuals.png`: (model − measured) over the channel's RMS on the fit views.", "",
              "![objective per evaluation](history.png)", "",
              "`history.png`: the objective of every forward evaluation, coloured by the relative error asked of "
              "the forward model; the line is the best so far.", "",
              bake, ""]
    return "\n".join(lines)


# ---- plots --------------------------------------------------------------------------------------


#: Markers of the held-out views by their azimuth from the plane of incidence, |Δφ| in degrees.
_AZIMUTH_MARKERS = {45: "^", 90: "o", 135: "v"}


def _azimuth_groups(views, select: np.ndarray) -> list[tuple[np.ndarray, str]]:
    """The views ``select`` grouped by |Δφ| (the plane of incidence is one group), each with its
    marker: the held-out column draws one curve per azimuth."""
    a = views.angles_deg[select]
    folded = np.abs(((a[:, 3] - a[:, 1]) % 360.0 + 180.0) % 360.0 - 180.0)
    folded = np.where(views.fit[select], 0.0, np.round(folded))
    return [(select[folded == value], _AZIMUTH_MARKERS.get(int(value), "o")) for value in np.unique(folded)]


def write_plots(result: FitResult, folder: pathlib.Path) -> dict[str, pathlib.Path]:
    """``fit.png``, ``residuals.png`` and ``history.png`` in ``folder``; their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = pathlib.Path(folder)
    paths = {name: folder / file for name, file in PLOT_FILES.items()}
    views, measured = result.views, np.asarray(result.measurement.rgb, float)
    incidences = views.incidences
    scale = np.sqrt(np.mean(measured[views.fit] ** 2, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    positive = measured[measured > 0]
    floor = float(positive.min()) / 3 if positive.size else 1e-4

    for name in ("fit", "residuals"):
        figure, axes = plt.subplots(len(incidences), 2, figsize=(11, 2.8 * len(incidences)), squeeze=False,
                                    sharex="col")
        for row, theta_i in enumerate(incidences):
            at = views.at_incidence(theta_i)
            for column, (mask, title, xlabel) in enumerate((
                    (views.fit, "plane of incidence (fit)", "signed view angle θv, °"),
                    (views.held_out, "other azimuths (held out; Δφ by marker)", "view zenith θo, °"))):
                ax = axes[row, column]
                select = np.flatnonzero(at & mask)
                for group, marker in _azimuth_groups(views, select):
                    group = group[np.argsort(views.signed_view_deg[group], kind="stable")]
                    x = views.signed_view_deg[group]
                    for c, channel in enumerate(CHANNELS):
                        colour = _COLOURS[channel]
                        if name == "fit":
                            ax.plot(x, np.maximum(measured[group, c], floor), marker, color=colour, ms=3.5,
                                    label=f"measured {channel}")
                            ax.plot(x, np.maximum(result.model_rgb[group, c], floor), "-", color=colour,
                                    label=f"medium {channel}")
                            ax.plot(x, np.maximum(result.baseline_rgb[group, c], floor), "--", color=colour,
                                    alpha=0.7, label=f"baseline {channel}")
                        else:
                            ax.plot(x, (result.model_rgb[group, c] - measured[group, c]) / scale[c], "-" + marker,
                                    ms=3, color=colour, label=f"medium {channel}")
                            ax.plot(x, (result.baseline_rgb[group, c] - measured[group, c]) / scale[c], "--",
                                    color=colour, alpha=0.7, label=f"baseline {channel}")
                if name == "fit" and len(select):
                    ax.set_yscale("log")
                if name == "residuals":
                    ax.axhline(0.0, color="0.5", lw=0.8)
                ax.set_title(f"θi = {theta_i:g}°, {title}", fontsize=9)
                if row == len(incidences) - 1:
                    ax.set_xlabel(xlabel)
                ax.set_ylabel("BRDF, 1/sr" if name == "fit" else "residual / channel RMS")
                ax.grid(alpha=0.3)
                if not len(select):
                    ax.text(0.5, 0.5, "no views", transform=ax.transAxes, ha="center", va="center", color="0.5")
        handles, labels = axes[0, 0].get_legend_handles_labels()
        if handles:
            figure.legend(handles, labels, loc="upper center", ncol=3, fontsize=8, frameon=False)
        # Margins set, not measured: tight_layout sizes every log-scale tick label and took seconds.
        height = figure.get_figheight()
        figure.subplots_adjust(left=0.08, right=0.98, wspace=0.22, hspace=0.5,
                               bottom=0.55 / height, top=1.0 - 0.8 / height)
        figure.savefig(paths[name], dpi=110)
        plt.close(figure)

    figure, ax = plt.subplots(figsize=(8, 4.2))
    history = result.history
    forward = [e for e in history if e.kind != "refused"]
    refused = [e for e in history if e.kind == "refused"]
    if forward:
        points = ax.scatter([e.index for e in forward], [e.objective for e in forward],
                            c=[e.relative_error for e in forward], cmap="viridis", s=18,
                            marker="o", edgecolors="none")
        figure.colorbar(points, ax=ax, label="relative error asked of the forward model")
        finals = [e for e in forward if e.kind == "final"]
        ax.scatter([e.index for e in finals], [e.objective for e in finals], marker="*", s=140, facecolors="none",
                   edgecolors="k", label="final (accurate) evaluations: the winner's and the start's")
        best, running = math.inf, []
        for e in forward:
            best = min(best, e.objective)
            running.append(best)
        ax.step([e.index for e in forward], running, where="post", color="k", lw=0.9, label="best so far")
    if refused:
        ax.scatter([e.index for e in refused], [e.objective for e in refused], marker="x", color="0.6",
                   label="refused by the medium (penalty)")
    ax.set_yscale("log")
    ax.set_xlabel("evaluation")
    ax.set_ylabel("objective")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    figure.subplots_adjust(left=0.13, right=0.95, bottom=0.12, top=0.96)
    figure.savefig(paths["history"], dpi=110)
    plt.close(figure)
    return paths


__all__ = ["FIT_FOLDER_FILES", "JSON_FILE", "PLOT_FILES", "PRESET_FILE", "REPORT_FILE",
           "check_fit_folder", "fit_summary", "fitted_preset_config", "preset_toml", "report_markdown", "to_toml",
           "write_fit_folder", "write_plots"]
