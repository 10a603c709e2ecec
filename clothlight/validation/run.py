"""One code path for a validation sweep: the operator, ``python -m clothlight.validate`` and a real
Blender (``blender -b -P scripts/validate_blender.py -- …``) all call :func:`run_validation`."""

from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Callable

import bpy

from mathutils import Vector

from ..materials import SUN_MODE, build_baseline_material, build_yarn_material, sync_sun
from ..measurement_render import render_to_array
from ..yarn_tables import yarn_tables_from_bake
from .measure import run_sweep
from .measured_data import read_measurement, relative_rms_error, rms_error, shape_correlation
from .report import plot_sweeps, write_json, write_markdown
from .rig import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG, RigSettings, aim, build_rig, set_view


def run_validation(out_dir, *, tables_dir=None, settings: RigSettings = RigSettings(),
                   incidences=DEFAULT_INCIDENCES_DEG, views=DEFAULT_VIEWS_DEG, measurement_csv=None,
                   mode: str = SUN_MODE, progress: Callable[[float], None] | None = None,
                   cancel: Callable[[], bool] | None = None) -> dict:
    """Sweep the yarn material (if ``tables_dir`` is a bake) and the paper's baseline; write
    ``results.json``, ``sweeps.png`` and ``report.md`` into ``out_dir``; return the results."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    scene = bpy.context.scene
    sample, sun, camera = build_rig(settings, scene)
    materials = {"baseline (Lambert 0.6/π red + Cook–Torrance m = 0.8)": build_baseline_material(mode=mode)}
    if tables_dir is not None:
        materials = {"ClothLight yarn BRDF": build_yarn_material(yarn_tables_from_bake(tables_dir), mode=mode), **materials}
    curves = {}
    for index, (label, material) in enumerate(materials.items()):
        def share(done, index=index):
            if progress is not None:
                progress((index + done) / len(materials))

        curves[label] = run_sweep(scene, sample, sun, camera, material, settings, incidences, views,
                                  out_dir / "renders", share, cancel)
    measurement = read_measurement(measurement_csv) if measurement_csv else None
    results = {
        "sample": f"{settings.weave.warp_count}×{settings.weave.weft_count} yarns, spacing {settings.weave.spacing_mm} mm, "
                  f"patch {settings.patch_mm} mm, {settings.resolution}² px, {settings.samples} spp",
        "units": {"brdf_rgb": "1/sr (cloth BRDF, calibrated)", "rgb_sum": "sum of linear RGB over cloth pixels",
                  "angles": "degrees; negative θv on the light's side"},
        "settings": dataclasses.asdict(settings) | {"weave": {"spacing_mm": settings.weave.spacing_mm}},
        "curves": {label: [dataclasses.asdict(v) for v in views_] for label, views_ in curves.items()},
        "table1_ratios": {},
        "metrics": {},
    }
    for label, views_ in curves.items():
        normal = next((v for v in views_ if v.theta_i_deg == 0 and v.theta_v_deg == 0), None)
        if normal is not None and normal.brdf_rgb[0] > 0:
            r, g, b = normal.brdf_rgb
            results["table1_ratios"][label] = {"B/R": b / r, "G/R": g / r}
    if measurement is not None:
        _paper_normalise(curves, measurement)
        for label, views_ in curves.items():
            model, measured, normalised = [], [], []
            for theta_i in incidences:
                x, y = measurement.in_plane(theta_i)
                for v in views_:
                    if v.theta_i_deg == theta_i and len(x) and abs(x - v.theta_v_deg).min() < 0.5:
                        measured.append(y[abs(x - v.theta_v_deg).argmin()][:3])
                        model.append(v.brdf_rgb)
                        normalised.append(v.paper_normalised_rgb)
            if model:
                results["metrics"][label] = {"rms": rms_error(model, measured),
                                             "relative_rms": relative_rms_error(model, measured),
                                             "shape_correlation": shape_correlation(model, measured),
                                             "paper_normalised_relative_rms": relative_rms_error(normalised, measured)}
        results["curves"] = {label: [dataclasses.asdict(v) for v in views_] for label, views_ in curves.items()}
        plot_sweeps(out_dir / "sweeps_paper_normalised.png", curves, incidences, measurement, "paper_normalised_rgb")
    if tables_dir is not None:
        material = materials["ClothLight yarn BRDF"]
        results["front_back_rgb"] = render_front_back(scene, sample, sun, camera, material, settings,
                                                      out_dir / "swatches_front_back.png")
    plot_sweeps(out_dir / "sweeps.png", curves, incidences, measurement)
    write_json(out_dir / "results.json", results)
    write_markdown(out_dir / "report.md", results, "sweeps.png")
    return results


def _paper_normalise(curves, measurement) -> None:
    """The paper's §4 step 5: scale each material's curves by the one factor that makes its
    normal-incidence, normal-view red value equal the measured one."""
    x, y = measurement.in_plane(0.0)
    if not len(x) or abs(x).min() > 0.5:
        return
    target = y[abs(x).argmin()][0]
    for views_ in curves.values():
        normal = next((v for v in views_ if v.theta_i_deg == 0 and v.theta_v_deg == 0), None)
        if normal is None or normal.brdf_rgb[0] <= 0:
            continue
        factor = target / normal.brdf_rgb[0]
        for v in views_:
            v.paper_normalised_rgb = [factor * c for c in v.brdf_rgb]


def render_front_back(scene, sample, sun, camera, material, settings: RigSettings, path) -> dict:
    """The sample seen from the front under a white sun in front of it and behind it (paper
    Figures 9–10); writes both renders side by side as a PNG and returns their mean RGB."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    sample.data.materials.clear()
    sample.data.materials.append(material)
    set_view(camera, settings, 0.0)
    images, means = {}, {}
    for label, direction in (("front", Vector((0.0, 0.0, 1.0))), ("behind", Vector((0.0, 0.0, -1.0)))):
        aim(sun, direction)
        scene.view_layers[0].update()
        sync_sun(material, sun)
        pixels = render_to_array(scene, pathlib.Path(path).with_name(f"swatch_{label}.exr"))
        images[label] = pixels[..., :3]
        means[label] = pixels[..., :3].mean(axis=(0, 1)).tolist()
    brightest = max(float(np.max(m)) for m in means.values()) or 1.0
    fig, axes = plt.subplots(1, 2, figsize=(6, 3.2))
    for ax, (label, image) in zip(axes, images.items()):
        shown = np.clip(image / max(float(np.percentile(image, 99)), 1e-12), 0, 1)
        ax.imshow(np.where(shown <= 0.0031308, 12.92 * shown, 1.055 * shown ** (1 / 2.4) - 0.055))
        ax.set_title(f"sun {label}; relative brightness {max(means[label]) / brightest:.2f}", fontsize=8)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return means
