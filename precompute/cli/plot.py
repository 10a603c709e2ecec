"""``python -m precompute plot``: PNG plots of a baked yarn (see precompute/plots.py)."""

from __future__ import annotations

import json
import pathlib

import numpy as np

from .. import plots
from ..tables import read_table


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("plot", help="PNG plots of baked yarn tables")
    parser.add_argument("table", type=pathlib.Path, help="a bake folder, or its brdf.exr")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="folder for the PNG files")
    parser.set_defaults(func=run)


def run(args) -> int:
    folder = args.table if args.table.is_dir() else args.table.parent
    atlas, metadata = read_table(folder / "brdf.exr")
    resolution = int(metadata["incidence_resolution"])
    spectral = dict(np.load(folder / "spectral.npz"))
    args.out.mkdir(parents=True, exist_ok=True)
    written = [
        plots.plot_in_plane(atlas, resolution, args.out / "rho_in_plane.png"),
        plots.plot_exit_maps(atlas, resolution, args.out / "rho_exit_maps.png"),
        plots.plot_albedo_spectra(spectral, resolution, args.out / "albedo_spectra.png"),
        plots.plot_swatches(spectral, resolution, args.out / "swatches_front_back.png"),
    ]
    print(json.dumps([str(p) for p in written]))
    return 0
