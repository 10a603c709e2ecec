"""``python -m precompute <command>``: the precomputation command line.

Exit codes (precompute/exit_codes.py, the same for every ClothLight command): 0 done, 2 bad input
(the message names the parameter or file and what is allowed), 130 interrupted, 1 an internal
error (one line; CLOTHLIGHT_TRACEBACK=1 shows the traceback).
"""

from __future__ import annotations

try:  # a Ctrl-C before the handler below is in place still exits with 130, without a traceback
    import sys

    from precompute.exit_codes import INTERRUPTED, run_cli
except KeyboardInterrupt:
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None

#: The commands; each module of precompute/cli defines add_parser(subparsers), whose parser sets
#: ``func(args) -> int``.  The medium fit renders with Blender, so its command is the add-on's:
#: ``python -m clothlight.fit``.
COMMANDS = ("optics", "slab", "bake", "plot")


def _command_module(name: str):
    """The module of command ``name``, imported when asked for: start-up time (the slab command
    imports neither numba nor NumPy, and a bake need not import the plots)."""
    if name == "optics":
        from precompute.cli import optics as module
    elif name == "slab":
        from precompute.cli import slab as module
    elif name == "bake":
        from precompute.cli import bake as module
    elif name == "plot":
        from precompute.cli import plot as module
    else:
        raise ValueError(f"no command {name!r}")
    return module


def build_parser(argv: list[str] | None = None):
    """The parser; with ``argv`` naming a command, only that command's module is imported, else all
    of them (the help lists every command)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m precompute", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    subparsers = parser.add_subparsers(dest="command", required=True)
    requested = next((arg for arg in argv or () if not arg.startswith("-")), None)
    for name in (requested,) if requested in COMMANDS else COMMANDS:
        _command_module(name).add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run a command; its exit code.  The command modules (numba, scipy) are imported in here, so a
    Ctrl-C during those imports ends as one at any other moment: code 130, one line."""

    arguments = sys.argv[1:] if argv is None else list(argv)

    def command() -> int:
        from precompute.cli.arguments import parse_arguments

        args = parse_arguments(build_parser(arguments), arguments)
        return args.func(args)

    return run_cli(command)


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # between main's return and the exit
        sys.exit(INTERRUPTED)
