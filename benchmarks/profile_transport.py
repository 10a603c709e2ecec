"""Where the transport kernels spend their time: a sampling profile of the numba code (issue 24).

    python benchmarks/profile_transport.py [yarn|slab] [--paths N | --target E]

Runs itself under ``perf record -e cpu-clock`` (the one event a virtual machine offers; skipped with
the reason where perf is missing or not permitted) while tracing, on one thread, the default preset's
yarn (``--paths`` per incidence cell, default 512; or, as a bake traces it, to the relative error
``--target`` on every cell's albedo: adapted hero wavelengths and the roulette by need) or the van de
Hulst slab (``--paths`` in all, default 2·10⁶).  numba's machine code is anonymous memory that perf
cannot name, so the traced process copies its executable anonymous mappings out before it exits; the
samples are then sorted into

* numba's reference counting (``NRT_incref`` / ``NRT_decref``, atomic; recognised by their code),
* the rest of the compiled kernels,
* each libm function (``exp``, ``log``, ...), and every other library,

and the hottest instructions of the kernels are printed with the disassembly around them
(``objdump``), so that a stall can be read against the code: a load that misses the cache, a chain of
divisions, a call.  Only the samples taken while tracing are counted.
"""

from __future__ import annotations

import collections
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
#: The environment variable that tells the traced child where to write.
CHILD = "CLOTHLIGHT_PROFILE_DIR"
#: numba's NRT_incref starts ``mov $1, %eax; lock xadd`` and lies on its own page.
NRT_PAGE_START = bytes.fromhex("b801000000f0480fc107")
SAMPLES_PER_SECOND = 4000


def run_traced(mode: str, paths: int, target: float | None, folder: pathlib.Path) -> None:
    """The traced child: warm up, trace, and copy the executable anonymous mappings into ``folder``."""
    sys.path.insert(0, str(REPO))
    from precompute.optics.coefficients import load_preset, medium_optics
    from precompute.transport import TransportGrids, YarnGeometry, simulate_hg_slab, simulate_yarn
    from subject_medium import SUBJECT_PRESET

    if mode == "yarn":
        optics = medium_optics(load_preset(SUBJECT_PRESET))
        geometry = YarnGeometry(0.1, optics.boundary_index)
        simulate_yarn(optics, geometry, TransportGrids(8, 2, 3), paths_per_cell=16, threads=1)

        def work():
            amount = {"paths_per_cell": paths} if target is None else {"target_rel_stderr": target}
            return simulate_yarn(optics, geometry, TransportGrids(), **amount, seed=3, threads=1).events
    else:
        simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=1000)

        def work():
            return simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=paths, seed=1, threads=1).events
    start = time.clock_gettime(time.CLOCK_MONOTONIC)
    events = work()
    end = time.clock_gettime(time.CLOCK_MONOTONIC)
    (folder / "window").write_text(f"{start} {end} {events}")
    with open("/proc/self/maps") as maps, open("/proc/self/mem", "rb") as memory:
        for line in maps:
            fields = line.split()
            named = len(fields) > 5 and (fields[5].startswith("/") or fields[5].startswith("["))
            low, high = (int(x, 16) for x in fields[0].split("-"))
            if "x" in fields[1] and not named and high - low <= 64 << 20:
                memory.seek(low)
                (folder / f"{low:x}-{high:x}.bin").write_bytes(memory.read(high - low))


def disassembly(path: pathlib.Path, low: int) -> list[tuple[int, str]]:
    listing = subprocess.run(["objdump", "-D", "-b", "binary", "-mi386:x86-64", f"--adjust-vma={low:#x}", str(path)],
                             capture_output=True, text=True, check=True).stdout
    lines = []
    for line in listing.splitlines():
        head = line.strip().split(":")[0]
        try:
            lines.append((int(head, 16), line))
        except ValueError:
            continue
    return lines


def report(folder: pathlib.Path, data: pathlib.Path, hottest: int = 8) -> None:
    start, end, events = (float(x) for x in (folder / "window").read_text().split())
    regions = []
    for dump in folder.glob("*.bin"):
        low, high = (int(x, 16) for x in dump.stem.split("-"))
        regions.append((low, high, dump))
    nrt = [low for low, high, dump in regions if dump.read_bytes().startswith(NRT_PAGE_START)]
    script = subprocess.run(["perf", "script", "-i", str(data), "-F", "time,ip,sym,dso"], capture_output=True,
                            text=True).stdout
    shares, kernel_ips = collections.Counter(), collections.Counter()
    for line in script.splitlines():
        fields = line.split()
        if len(fields) < 3 or not fields[0].endswith(":"):
            continue
        if not start <= float(fields[0][:-1]) <= end:
            continue
        ip, library = int(fields[1], 16), fields[-1].strip("()")
        if any(low <= ip < low + 0x100 for low in nrt):
            shares["numba reference counting (NRT_incref/decref)"] += 1
        elif any(low <= ip < high for low, high, _ in regions):
            shares["compiled kernels"] += 1
            kernel_ips[ip] += 1
        elif "libm" in library:
            shares[f"libm {fields[2]}"] += 1
        else:
            shares[pathlib.Path(library).name] += 1
    total = sum(shares.values())
    print(f"{total} samples while tracing ({(end - start):.2f} s, {events:.3g} scattering events):")
    for name, count in shares.most_common(12):
        print(f"  {100 * count / total:5.1f} %  {name}")
    code = max(regions, key=lambda region: sum(c for ip, c in kernel_ips.items() if region[0] <= ip < region[1]))
    lines = disassembly(code[2], code[0])
    where = {address: i for i, (address, _) in enumerate(lines)}
    for ip, count in kernel_ips.most_common(hottest):
        if ip not in where:
            continue
        print(f"\n{100 * count / total:.1f} % at {ip:#x}:")
        i = where[ip]
        for address, line in lines[max(0, i - 8):i + 2]:
            print(("> " if address == ip else "  ") + line.strip())


def main(arguments: list[str]) -> int:
    mode = "slab" if "slab" in arguments else "yarn"
    paths = int(arguments[arguments.index("--paths") + 1]) if "--paths" in arguments else (
        2_000_000 if mode == "slab" else 512)
    target = float(arguments[arguments.index("--target") + 1]) if "--target" in arguments else None
    if CHILD in os.environ:
        run_traced(mode, paths, target, pathlib.Path(os.environ[CHILD]))
        return 0
    for tool in ("perf", "objdump"):
        if shutil.which(tool) is None:
            print(f"profile skipped: {tool} is not installed")
            return 0
    with tempfile.TemporaryDirectory(prefix="clothlight-profile-") as folder:
        folder = pathlib.Path(folder)
        data = folder / "perf.data"
        command = ["perf", "record", "-q", "-e", "cpu-clock", "-F", str(SAMPLES_PER_SECOND), "-k", "CLOCK_MONOTONIC",
                   "-o", str(data), sys.executable, __file__, *arguments]
        run = subprocess.run(command, env={**os.environ, CHILD: str(folder)})
        if run.returncode != 0 or not (folder / "window").exists():
            print(f"profile skipped: perf record failed (exit {run.returncode}; "
                  "kernel.perf_event_paranoid may forbid it)")
            return 0
        amount = f"{paths:,} paths per incidence cell" if target is None else f"to a {target:g} relative error"
        what = (f"the default preset's yarn, {amount}" if mode == "yarn"
                else f"the van de Hulst slab (a 0.9, g 0.75, tau 2, n 1), {paths:,} paths")
        print(f"{what}, one thread")
        report(folder, data)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
