"""``python -m benchmarks [NAME ...]``: run the benchmark scripts (all, or those named) and print their figures.

Each ``benchmarks/bench_<name>.py`` is a plain script that prints what it
measured; none of them is a test, and none asserts a time.
"""

from __future__ import annotations

import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    scripts = sorted(HERE.glob("bench_*.py"))
    if argv:
        scripts = [s for s in scripts if s.stem.removeprefix("bench_") in argv]
    failures = 0
    for script in scripts:
        print(f"== {script.stem} ==", flush=True)
        failures += subprocess.run([sys.executable, str(script)], cwd=HERE.parent).returncode != 0
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
