"""How far from the surface the cloth gonioreflectometer's shadow rays must start (issue 44): the lit
share of every region in the rendered response's lookups, with the shader's ``ShadowMinDistance`` at
its default 10⁻⁵ mm and at ``goniometry.RAY_OFFSET_MM`` (10⁻⁴ mm), over the traced response's.

    python benchmarks/bench_shadow_offset.py [--yarn PRESET_OR_BAKE] [--views 12]

The default gonioreflectometer's front exit cells 0, k, 2k, … (``--views`` of them), 21² samples a
patch. The regions at the grid's edge lie 18–24 mm from the origin, where float32 rounding can let a
shadow ray that starts too close meet the triangle next to its start; the traced response starts
its rays ``RAY_OFFSET_MM`` out near the origin (docs/garment.md, "Traced without Blender").  Prints
the corner regions' ratios and the medians at the grid's edge and inside it.  About two minutes.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from subject_medium import SUBJECT_PRESET


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--yarn", default=SUBJECT_PRESET, help="a preset's name or a yarn bake folder")
    parser.add_argument("--views", type=int, default=12, help="front exit cells rendered (default 12)")
    args = parser.parse_args()

    import bpy  # noqa: F401  (Blender as a module)
    import numpy as np

    from clothlight.blender.garment.bake import RESPONSE_SAMPLES_PER_SIDE
    from clothlight.blender.garment.measure import GoniometerSettings, _GoniometerScene, _sample_weave
    from clothlight.blender.materials import shader_node
    from clothlight.blender.scene_files import open_empty_file
    from clothlight.garment.goniometry import RAY_OFFSET_MM, plan_sample
    from clothlight.garment.traced_response import WovenTracer, trace_view
    from clothlight.yarn_tables import yarn_tables_from_bake
    from precompute.bake import bake

    folder = pathlib.Path(args.yarn) if pathlib.Path(args.yarn).is_dir() else bake(args.yarn).folder
    settings = GoniometerSettings()
    n_i, n_o = settings.incidence_resolution, settings.exit_resolution
    cells = list(range(0, n_o * n_o, max(1, n_o * n_o // args.views)))[: args.views]
    regions = n_i * n_i

    def lit_share(views) -> np.ndarray:
        return sum(np.bincount(v.patch, v.weight, regions) for v in views) / sum(v.counted for v in views)

    open_empty_file()
    scene = _GoniometerScene(yarn_tables_from_bake(folder), settings, RESPONSE_SAMPLES_PER_SIDE)
    rendered = {}
    try:
        with tempfile.TemporaryDirectory(prefix="clothlight-bench-shadow-") as renders:
            for offset in (1e-5, RAY_OFFSET_MM):
                shader_node(scene._material).inputs["ShadowMinDistance"].default_value = offset
                rendered[offset] = lit_share([scene.render_lookups("front", cell, pathlib.Path(renders)
                                                                   / f"{offset:g}_{cell}.exr") for cell in cells])
    finally:
        scene.close()
    plan = plan_sample(_sample_weave(settings), n_i, n_o, settings.pixels_per_patch, settings.patch_repeats)
    tracer = WovenTracer(plan, n_i, n_o)
    traced = lit_share([trace_view(tracer, "front", cell, n_o, RESPONSE_SAMPLES_PER_SIDE, cell) for cell in cells])
    row, column = np.divmod(np.arange(regions), n_i)
    edge = (row == 0) | (row == n_i - 1) | (column == 0) | (column == n_i - 1)
    corners = [0, n_i - 1, regions - n_i, regions - 1]
    print(f"{len(cells)} front views, {RESPONSE_SAMPLES_PER_SIDE}² samples a patch; lit share, rendered / traced:")
    for offset, share in rendered.items():
        ratio = share / np.where(traced > 0.0, traced, np.nan)
        print(f"ShadowMinDistance {offset:g} mm: corner regions {' '.join(f'{r:.3f}' for r in ratio[corners])}, "
              f"median at the grid's edge {np.nanmedian(ratio[edge]):.3f}, inside it {np.nanmedian(ratio[~edge]):.3f}")


if __name__ == "__main__":
    main()
