"""``python -m precompute <command>``: the precomputation command line.

Exit codes: 0 success, 2 bad input (the message names the parameter), 1 any
other failure.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .errors import ParameterError

# Each module in precompute/cli defines add_parser(subparsers), whose parser sets
# ``func(args) -> int``.  Listed by name so a missing optional command fails loudly.
COMMAND_MODULES = ("optics", "slab", "bake", "plot")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m precompute", description=__doc__)
    subparsers = parser.add_subparsers(dest="command", required=True)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"precompute.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"precompute.cli.{name}":
                raise
            continue
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ParameterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - the CLI's last line of defence, exit code 1
        print(f"error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
