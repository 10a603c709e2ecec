"""Validation outputs: JSON results, plots like the paper's graphs 1–6, colour swatches and a
compact Markdown report linking them.  No Blender needed.

Plots need matplotlib (Agg).  Blender's own Python has none: there the report says the plots were
skipped, and ``python -m clothlight.validation.report results.json`` redraws them later from the
JSON in any Python that has it.
"""

from __future__ import annotations

import json
import math
import pathlib
import struct
import sys
import zlib

try:
    import numpy as np

except KeyboardInterrupt:  # Ctrl-C while ``python -m clothlight.validation.report`` starts: code 130, no traceback
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None

CHANNELS = ("R", "G", "B")


def write_json(results: dict, path) -> pathlib.Path:
    """``results`` as standard JSON (NaN → null)."""
    from precompute import outputs
    path = pathlib.Path(path)
    standard = outputs.json_ready(results)
    path.write_text(json.dumps(standard, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def srgb_encode(linear) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values in [0, 1]."""
    linear = np.clip(np.asarray(linear, float), 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1.0 / 2.4) - 0.055)


def write_png(rgb8: np.ndarray, path) -> pathlib.Path:
    """Write an (H, W, 3) uint8 image, top row first, as an 8-bit RGB PNG."""
    height, width, _ = rgb8.shape
    raw = b"".join(b"\x00" + row.tobytes() for row in np.ascontiguousarray(rgb8, dtype=np.uint8))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    return path


def swatch_exposure(*images) -> float:
    """One exposure for swatches shown side by side: the brightest one's mean colour gets its
    largest channel at 0.5, so their relative brightness stays visible."""
    peak = max(float(np.asarray(image, float)[..., :3].mean(axis=(0, 1)).max()) for image in images)
    return 0.5 / peak if peak > 0.0 else 1.0


def write_swatch_png(pixels: np.ndarray, path, exposure: float) -> pathlib.Path:
    """A colour swatch (§6.1, Figures 9–10) from a render (H, W, 4) of linear RGB over black,
    multiplied by ``exposure`` and sRGB-encoded."""
    exposed = np.asarray(pixels, float)[..., :3] * exposure
    return write_png(np.round(255.0 * srgb_encode(exposed)).astype(np.uint8), path)


def plot_sweeps(results: dict, path, quantity: str = "brdf_rgb") -> pathlib.Path:
    """Cloth BRDF against signed view angle like the paper's graphs 1–6: one column per incidence,
    one row per channel, one line per material, the measurement dashed.  ``quantity`` is
    ``brdf_rgb`` (calibrated) or ``paper_normalised_rgb``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    incidences = results["settings"]["incidences_deg"]
    measured = (results.get("measurement") or {}).get("in_plane", {})
    fig, axes = plt.subplots(len(CHANNELS), len(incidences), figsize=(3.4 * len(incidences), 2.6 * len(CHANNELS)),
                             squeeze=False, sharex=True)
    for column, theta_i in enumerate(incidences):
        for row, channel in enumerate(CHANNELS):
            ax = axes[row, column]
            for kind, entry in results["materials"].items():
                points = [(v["theta_v_deg"], v[quantity][row]) for v in entry["views"]
                          if v["theta_i_deg"] == theta_i and v[quantity]]
                if points:
                    x, y = zip(*points)
                    ax.plot(x, y, marker="o", ms=3, lw=1.2, label=kind)
            curve = measured.get(f"{theta_i:g}", [])
            if curve:
                ax.plot([p[0] for p in curve], [p[1 + row] for p in curve], "k--", marker="s", ms=3, lw=1,
                        label="measurement")
            if theta_i > 0:
                ax.axvline(theta_i, color="0.6", lw=0.8, ls=":")
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
            if row == 0:
                ax.set_title(f"θi = {theta_i:g}°", fontsize=9)
            if column == 0:
                ax.set_ylabel(f"{channel}: BRDF (1/sr)", fontsize=8)
            if row == len(CHANNELS) - 1:
                ax.set_xlabel("θv (deg), negative: light's side", fontsize=8)
    axes[0, 0].legend(fontsize=7)
    title = "cloth BRDF, calibrated" if quantity == "brdf_rgb" else "cloth BRDF, the paper's normalisation"
    fig.suptitle(f"{title} (dotted: mirror direction)", fontsize=10)
    fig.tight_layout()
    path = pathlib.Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _plots(results: dict, out_dir: pathlib.Path) -> tuple[list[str], str | None]:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return [], ("matplotlib is not importable in this Python (Blender's has none): plots skipped; "
                    "redraw them with `python -m clothlight.validation.report results.json`")
    names = ["sweeps.png"]
    plot_sweeps(results, out_dir / "sweeps.png")
    if any(e.get("paper_normalisation_factor") for e in results["materials"].values()):
        plot_sweeps(results, out_dir / "sweeps_paper_normalised.png", "paper_normalised_rgb")
        names.append("sweeps_paper_normalised.png")
    return names, None


def _ratio_cell(value) -> str:
    if isinstance(value, list):
        return f"{value[0]:g}–{value[1]:g}"
    return "–" if value is None or not math.isfinite(value) else f"{value:.3g}"


def interreflection_section(light: dict | None) -> list[str]:
    """The report's lines on light between yarns (``results["interreflection"]``), or none."""
    if not light:
        return []
    lines = ["## Light between yarns", "",
             "The general-lighting yarn material path traced in a scene (`yarn_scene`: the rig's sun lamp, light "
             "bouncing between yarns) over the same material under direct light only (`yarn_general`), per view "
             "and channel: what inter-reflection adds (1 = nothing; the paper's model has none, §7).", "",
             "| channel | mean | min | max | max at θi, θv |", "| --- | --- | --- | --- | --- |"]
    for channel in ("R", "G", "B", "RGB"):
        c = light.get(channel)
        if c:
            at = c["max_at"]
            lines.append(f"| {channel if channel != 'RGB' else 'R + G + B'} | {c['mean']:.4g} | {c['min']:.4g} | "
                         f"{c['max']:.4g} | {at['theta_i_deg']:g}°, {at['theta_v_deg']:g}° |")
    swatches = light.get("swatches") or {}
    if swatches:
        lines += ["", "Swatches (normal view), mean radiance ratio (R, G, B) and what the scene adds, L/E (1/sr): "
                  + "; ".join(f"lit from the {side} " + ", ".join(_ratio_cell(x) for x in sw["ratio_rgb"])
                              + " (+" + ", ".join(f"{x:.3g}" for x in sw["added_rgb_per_irradiance"]) + ")"
                              for side, sw in swatches.items()) + "."]
    lines += ["", "| θi | θv | R | G | B |", "| --- | --- | --- | --- | --- |"]
    for v in light["views"]:
        lines.append(f"| {v['theta_i_deg']:g} | {v['theta_v_deg']:g} | "
                     + " | ".join("–" if x is None else f"{x:.4g}" for x in v["ratio_rgb"]) + " |")
    return lines + [""]


def azimuths_sentence(azimuths) -> list[str]:
    """The report's lines on the turns of the sample a sweep averaged (``results["sample_azimuths_deg"]``;
    none for a results.json written before sweeps recorded them)."""
    if not azimuths:
        return []
    angles = ", ".join(f"{a:g}°" for a in azimuths)
    if len(azimuths) == 1:
        return [f"The sample was measured at one turn: its warp at {angles} from the plane of incidence.", ""]
    return [f"The sample was averaged over its azimuth: every view and swatch is the mean of {len(azimuths)} renders "
            f"with the warp at {angles} from the plane of incidence (the sun and the cameras turned together about "
            "the sample's normal), as a measured isotropic BRDF averages the weave.", ""]


def markdown_report(results: dict, plots: list[str], plot_note: str | None) -> str:
    """The compact report: settings, plots, colour checks, metrics and the per-view table."""
    s = results["settings"]
    sample = s["sample"]
    lines = ["# ClothLight validation: virtual gonioreflectometer", "",
             f"Sample: {sample['name']}, {sample['size_mm'][0]:.3g} × {sample['size_mm'][1]:.3g} mm, "
             f"{sample['thickness_mm']:.3g} mm thick; every view frames the same central {s['patch_mm']:g} mm patch. "
             f"{s['resolution']}² pixels, {s['samples']} samples per pixel, seed {s['seed']}, "
             f"sun {s['sun_irradiance_w_per_m2']:g} W/m². Sweep time {results['seconds']['total']:.1f} s.", "",
             *azimuths_sentence(results.get("sample_azimuths_deg")),
             "Calibrated cloth BRDF f = Σ L_p a_p / (E cos θi · A cos θv) (1/sr): L_p pixel radiance, a_p pixel "
             "cross-section, E sun irradiance, A patch area (paper §4, step 5). θv < 0 is the light's side.", ""]
    lines += [f"![{name}]({name})" for name in plots] + ([f"*{plot_note}*"] if plot_note else []) + [""]

    lines += ["## Colour at normal illumination and view (paper Table 1)", "", "| | B/R | G/R |", "| --- | --- | --- |"]
    for kind, entry in results["materials"].items():
        t = entry["table1"] or {}
        lines.append(f"| {entry['label']} | {_ratio_cell(t.get('B/R'))} | {_ratio_cell(t.get('G/R'))} |")
    measurement = results.get("measurement")
    if measurement and measurement["table1"]:
        t = measurement["table1"]
        lines.append(f"| measurement (`{pathlib.Path(measurement['path']).name}`) | {_ratio_cell(t['B/R'])} | "
                     f"{_ratio_cell(t['G/R'])} |")
    for name, t in results["paper_table1"].items():
        lines.append(f"| paper: {name} | {_ratio_cell(t['B/R'])} | {_ratio_cell(t['G/R'])} |")
    lines.append("")

    swatched = {k: e["swatches"] for k, e in results["materials"].items() if e.get("swatches")}
    if swatched:
        lines += ["## Lit from the front and from behind (paper §6.1, Figures 9–10)", "",
                  "Both swatches of a material share one exposure (the brighter one's mean colour has its "
                  "largest channel at 0.5); L/E is the mean radiance over the irradiance, 1/sr.", "",
                  "| material | front | back | front L/E (R, G, B) | back L/E (R, G, B) |",
                  "| --- | --- | --- | --- | --- |"]
        for kind, sw in swatched.items():
            cells = [f"![{kind} {side}]({sw[side]['png']})" for side in ("front", "back")]
            levels = [", ".join(f"{c:.3g}" for c in sw[side]["mean_rgb_per_irradiance"]) for side in ("front", "back")]
            lines.append(f"| {kind} | {cells[0]} | {cells[1]} | {levels[0]} | {levels[1]} |")
        lines.append("")

    if measurement:
        lines += ["## Against the measurement", "",
                  f"`{measurement['path']}`: {measurement['direction_pairs']} direction pairs"
                  + (", spectral (converted to RGB)" if measurement["spectral"] else ", RGB") + ".", ""]
        if measurement.get("comments"):
            lines += ["> " + c for c in measurement["comments"]] + [""]
        lines += ["| material | values | channel | RMS (1/sr) | relative RMS | shape correlation |",
                  "| --- | --- | --- | --- | --- | --- |"]
        for kind, entry in results["materials"].items():
            metrics = entry.get("metrics")
            if not metrics:
                lines.append(f"| {kind} | – | – | no view in common with the measurement | | |")
                continue
            for quantity, label in (("brdf_rgb", "calibrated"), ("paper_normalised_rgb", "paper-normalised")):
                for channel in ("R", "RGB"):
                    m = (metrics.get(quantity) or {}).get(channel)
                    if m:
                        lines.append(f"| {kind} | {label} | {channel} | {m['rms']:.4g} "
                                     f"| {_ratio_cell(m['relative_rms'])} | {_ratio_cell(m['shape_correlation'])} |")
        factors = ", ".join(f"{k}: {e['paper_normalisation_factor']:.4g}" for k, e in results["materials"].items()
                            if e.get("paper_normalisation_factor"))
        lines += ["", "Paper normalisation coefficients (measured / model ΣRGB at θi = θv = 0): "
                  f"{factors or 'none'}.", ""]

    lines += interreflection_section(results.get("interreflection"))

    kinds = list(results["materials"])
    lines += ["## Cloth BRDF per view (1/sr, R G B)", "",
              "| θi | θv | " + " | ".join(kinds) + " |", "| --- | --- | " + " | ".join("---" for _ in kinds) + " |"]
    rows = zip(*(results["materials"][k]["views"] for k in kinds))
    for views in rows:
        cells = " | ".join(" ".join(f"{c:.4g}" for c in v["brdf_rgb"]) for v in views)
        lines.append(f"| {views[0]['theta_i_deg']:g} | {views[0]['theta_v_deg']:g} | {cells} |")
    lines += ["", "Data: `results.json`. Renders: `renders/`."]
    return "\n".join(lines) + "\n"


#: What a validation folder holds (a name ending in ``/`` is a folder): a new sweep may replace a
#: folder holding only these (precompute.tables.folder.check_output_folder).
VALIDATION_FOLDER_NAMES = ("results.json", "report.md", "sweeps.png", "sweeps_paper_normalised.png",
                           "renders/", "swatches/")


def write_report(results: dict, out_dir) -> dict:
    """Write plots, ``report.md`` and ``results.json`` into ``out_dir``; return their paths
    (relative to ``out_dir``), which are also stored in the JSON under ``files``."""
    out_dir = pathlib.Path(out_dir)
    plots, note = _plots(results, out_dir)
    files = {"json": "results.json", "report": "report.md", "plots": plots, "plot_note": note}
    (out_dir / "report.md").write_text(markdown_report(results, plots, note), encoding="utf-8")
    write_json({**results, "files": files}, out_dir / "results.json")
    return files


USAGE = "usage: python -m clothlight.validation.report RESULTS_JSON"


def main(argv=None) -> int:
    """``python -m clothlight.validation.report results.json``: redraw the plots and the report beside
    the results.  Exit codes as every ClothLight command (``precompute/exit_codes.py``)."""
    from precompute import exit_codes
    return exit_codes.run_cli(lambda: _main(sys.argv[1:] if argv is None else argv))


def _main(argv) -> int:
    from precompute import exit_codes
    from precompute import outputs
    from precompute.errors import ParameterError
    if list(argv) in (["-h"], ["--help"]):
        print(USAGE + "\n\n" + (main.__doc__ or "").split("\n\n")[0])
        return 0
    if len(argv) != 1:
        print(USAGE, file=sys.stderr)
        return exit_codes.BAD_INPUT
    path = pathlib.Path(argv[0])
    if not path.is_file():
        raise ParameterError("RESULTS_JSON", argv[0], "the results.json of a validation sweep (no such file)")
    outputs.check_writable_folder(
        path.parent, "RESULTS_JSON", what="a results.json in a folder this user can write (the plots go beside it)")
    try:
        results = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ParameterError("RESULTS_JSON", str(path), f"the results.json of a validation sweep ({error})") from None
    if not isinstance(results, dict) or not isinstance(results.get("materials"), dict):
        raise ParameterError("RESULTS_JSON", str(path), "the results.json of a validation sweep (no 'materials')")
    try:
        files = write_report(results, path.parent)
    except (KeyError, IndexError, TypeError, ValueError) as error:  # a results.json of another shape
        raise ParameterError("RESULTS_JSON", str(path), "the results.json of a validation sweep, as the sweep "
                                                        f"writes it ({type(error).__name__}: {error})") from None
    print(f"report: {path.parent / files['report']}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # between main's return and the exit
        sys.exit(130)
