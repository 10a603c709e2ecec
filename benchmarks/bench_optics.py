"""Medium optics: time of ``medium_optics`` for every shipped preset, with and without Percus–Yevick.

Every bake calls ``medium_optics`` once, so it should stay well under a second
for the default preset.  Prints seconds per call (best of 3) and the number of
Mie evaluations behind it.

    python benchmarks/bench_optics.py
"""

from __future__ import annotations

import dataclasses
import pathlib
import sys
import time

# Run as a plain script (``python benchmarks/bench_optics.py``): the repository root holds the package.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from precompute.optics.medium import load_preset, preset_names
from precompute.optics.mie import size_distribution
from precompute.optics.coefficients import medium_optics


def best_of(count: int, function) -> float:
    times = []
    for _ in range(count):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    print(f"{'preset':<22} {'model':<14} {'λ':>3} {'Mie calls':>9} {'M':>6} {'seconds':>8}")
    for name in preset_names():
        params = load_preset(name)
        calls = len(params.wavelengths.values) * sum(len(size_distribution(s)[0]) for s in params.particles)
        for model in ("none", "percus-yevick"):
            variant = dataclasses.replace(params, dependent_scattering=model)
            seconds = best_of(3, lambda: medium_optics(variant))
            samples = medium_optics(variant).phase_samples  # the chosen count when phase_samples is "auto"
            print(
                f"{name:<22} {model:<14} {len(params.wavelengths.values):>3} {calls:>9} "
                f"{samples:>6} {seconds:8.3f}"
            )


if __name__ == "__main__":
    main()
