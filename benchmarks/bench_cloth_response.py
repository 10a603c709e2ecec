"""The cloth response against the full sweep (issue 19): time and agreement, side by side in one run.

A validation sweep of the yarn material (the default 14 views × 4 incidences at 128² px) against
the cloth response of the same views (rendered once at 128² px × supersampling² camera samples per
pixel) applied to the same tables: the response's one-off render time, the time to apply it to a
table (first call: building the layout's map; then per medium), and the per-view deviation.  Both
are Monte-Carlo estimates of the same sums; the defaults (64 spp, 8² samples per pixel) keep the
noise of each well below 1 % per view (the default sweep's 16 spp and 4²: 0.6 % RMS, 2.2 % at worst).

    python benchmarks/bench_cloth_response.py [--tables BAKE] [--samples 64] [--supersampling 8]

Default tables: the shipped red-cotton bake in example_blends/tables.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _read(path):
    import OpenEXR

    with OpenEXR.File(str(path)) as exr:
        return np.array(next(iter(exr.parts[0].channels.values())).pixels)[..., :3]


def main() -> None:
    import bpy

    from clothlight.validation.response import TableLayout
    from clothlight.blender.validation.response_render import measure_response
    from clothlight.blender.validation.rig import RigSettings
    from clothlight.blender.validation.run import run_validation
    from clothlight.yarn_tables import yarn_tables_from_bake
    from precompute.optics import ballistic

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tables", type=pathlib.Path, default=ROOT / "example_blends" / "tables" / "paper_2008")
    parser.add_argument("--samples", type=int, default=64, help="the sweep's samples per pixel")
    parser.add_argument("--supersampling", type=int, default=8, help="the response's samples per pixel per axis")
    args = parser.parse_args()
    tables = yarn_tables_from_bake(args.tables)
    settings = RigSettings(samples=args.samples)
    out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-response-"))
    print(f"{os.cpu_count()} CPU cores; tables: {args.tables}; sweep {settings.resolution}² px × {args.samples} spp, "
          f"response × {args.supersampling}² samples per pixel")
    bpy.ops.wm.read_homefile(use_empty=True)

    start = time.perf_counter()
    results = run_validation(None, out / "sweep", materials=("yarn",), tables_dir=args.tables, settings=settings,
                             swatches=False)
    sweep_seconds = time.perf_counter() - start
    sweep = {(v["theta_i_deg"], v["theta_v_deg"]): np.array(v["brdf_rgb"])
             for v in results["materials"]["yarn"]["views"]}

    views = [(theta_i, theta_v, 0.0, 0.0) for theta_i in settings.incidences_deg for theta_v in settings.views_deg]
    start = time.perf_counter()
    response = measure_response(tables, views, resolution=settings.resolution,
                                supersampling=args.supersampling)
    render_seconds = time.perf_counter() - start

    atlas, attenuation = _read(tables.brdf_path), _read(tables.unscattered_path)
    layout = TableLayout(tables.incidence_resolution, tables.exit_resolution, tables.unscattered_samples,
                         tables.host_index, ballistic.SUN_MODE_SPREAD_RAD)
    timings = []
    for _ in range(6):
        start = time.perf_counter()
        model = response.cloth_brdf(atlas, attenuation, layout, specular_weight=1.0, specular_slope=0.8)
        timings.append(time.perf_counter() - start)
    ratio = np.array([model[k] / sweep[view[:2]] for k, view in enumerate(views)])
    worst = np.unravel_index(np.argmax(np.abs(ratio - 1.0)), ratio.shape)
    print(f"full sweep: {len(views)} views in {sweep_seconds:.1f} s")
    print(f"response: rendered once in {render_seconds:.1f} s; applied to a table in {timings[0]:.2f} s (first call, "
          f"building the map), then {1e3 * np.median(timings[1:]):.2f} ms: "
          f"{sweep_seconds / np.median(timings[1:]):.0f}× faster than a sweep per medium")
    print(f"response / sweep per view: largest deviation {ratio[worst] - 1.0:+.2%} "
          f"(θi {views[worst[0]][0]:g}°, θv {views[worst[0]][1]:g}°, channel {'RGB'[worst[1]]}); "
          f"RMS {np.sqrt(np.mean((ratio - 1.0) ** 2)):.2%}")


if __name__ == "__main__":
    main()
