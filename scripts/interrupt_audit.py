"""Ctrl-C at chosen moments of every command: exit code, seconds from the signal to the exit, and
what the interrupted run left in its output place (issue 47: "SIGINT at any moment of any command
exits 130 within a few seconds and writes nothing").

    python scripts/interrupt_audit.py                  # every command, SIGINT at 0.5, 2, 6 and 15 s
    python scripts/interrupt_audit.py --moments 1 4 --commands bake fit

A run that ends before its moment is listed as "ended first" (its exit code is then the command's
own).  The commands are small versions of real work, each on a fresh folder; the output place must
hold nothing after an interrupt (no output folder, no staging ``.partial`` folder beside it).
"""

from __future__ import annotations

import argparse
import pathlib
import signal
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
TABLES = REPO / "example_blends" / "tables" / "paper_2008"
MEASURED = REPO / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"

#: name → argv after ``python -m``; ``{out}`` is the output place, ``{cache}`` a cache folder of its own.
COMMANDS = {
    "bake": ["precompute", "bake", "--preset", "paper_2008", "--paths", "4000", "--scheduler", "none",
             "--cache-dir", "{cache}", "--out", "{out}"],
    "optics": ["precompute", "optics", "--preset", "voided_red_cotton", "--plot", "{out}.png"],
    "slab": ["precompute", "slab", "--albedo", "0.9", "--g", "0.5", "--tau", "4", "--paths", "20000000",
             "--threads", "1"],
    "plot": ["precompute", "plot", "--out", "{out}", str(TABLES)],
    "validate": ["clothlight.validate", "--out", "{out}", "--material", "baseline", "--resolution", "32",
                 "--samples", "4", "--scheduler", "none"],
    "garment": ["clothlight.garment", "bake", "--tables", str(TABLES), "--out", "{out}", "--cache-dir", "{cache}",
                "--incidence-resolution", "3", "--exit-resolution", "2", "--pixels-per-patch", "8", "--samples", "2",
                "--scheduler", "none"],
    "fit": ["clothlight.fit", "--measured", str(MEASURED), "--preset", "paper_2008", "--free", "dye_weight_percent",
            "--budget-evaluations", "8", "--scheduler", "none", "--cache-dir", "{cache}", "--out", "{out}"],
    "match_colour": ["clothlight.fit.match_colour", "--target", "#8c1c24", "--preset", "voided_red_cotton",
                     "--cache-dir", "{cache}", "--out", "{out}.toml"],
}


def interrupt_at(name: str, moment_s: float, *, grace_s: float = 60.0) -> dict:
    """Run command ``name`` on a fresh folder, send SIGINT ``moment_s`` seconds after its start, and
    report what happened."""
    with tempfile.TemporaryDirectory(prefix=f"clothlight-interrupt-{name}-") as folder:
        root = pathlib.Path(folder)
        out = root / "out"
        argv = [arg.format(out=out, cache=root / "cache") for arg in COMMANDS[name]]
        child = subprocess.Popen([sys.executable, "-m", *argv], cwd=REPO, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                 preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        try:
            child.wait(timeout=moment_s)
            ended_first = True
        except subprocess.TimeoutExpired:
            ended_first = False
            child.send_signal(signal.SIGINT)
        sent = time.perf_counter()
        try:
            code = child.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            child.kill()
            code = child.wait()
        seconds = time.perf_counter() - sent
        stderr = child.stderr.read().decode(errors="replace")
        left = sorted(p.name for p in root.iterdir() if p.name != "cache")
        return {"command": name, "moment_s": moment_s, "ended_first": ended_first, "exit": code,
                "seconds_to_exit": None if ended_first else seconds, "left": left,
                "traceback": "Traceback" in stderr, "last_line": (stderr.strip().splitlines() or [""])[-1][:80]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commands", nargs="+", choices=sorted(COMMANDS), default=list(COMMANDS))
    parser.add_argument("--moments", nargs="+", type=float, default=[0.5, 2.0, 6.0, 15.0],
                        help="seconds after the start at which SIGINT is sent")
    args = parser.parse_args(argv)
    print("| command | SIGINT at | exit | s to exit | left in the output place | last line of stderr |")
    print("| --- | --- | --- | --- | --- | --- |")
    failures = 0
    for name in args.commands:
        for moment in args.moments:
            r = interrupt_at(name, moment)
            if r["ended_first"]:
                print(f"| {name} | {moment:g} s | {r['exit']} (ended first) | | {', '.join(r['left']) or '–'} | |")
                continue
            # Killed by the signal itself (-2): Python restores SIGINT's default while it finalises,
            # so a Ctrl-C in the last moments of an exit ends the process as the signal does; a shell
            # reports that as 130 too.
            code = "130 (signal)" if r["exit"] == -signal.SIGINT else r["exit"]
            bad = code not in (130, "130 (signal)") or r["left"] or r["traceback"] or r["seconds_to_exit"] > 10
            failures += bool(bad)
            print(f"| {name} | {moment:g} s | {code} | {r['seconds_to_exit']:.1f} | "
                  f"{', '.join(r['left']) or '–'} | {r['last_line']}{' **FAILS**' if bad else ''} |", flush=True)
    print(f"\n{failures} interrupted run(s) failed the rule (exit 130 within 10 s, nothing left, no traceback)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
