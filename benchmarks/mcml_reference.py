"""MCML 1.2 (Wang, Jacques & Zheng 1995), the classic C Monte-Carlo code for layered media, built from
its public source and run on a slab: the speed anchor of issue 24, measured in the same run on the
same machine as ClothLight's transport (bench_transport.py's ``mcml`` mode).

The source is not shipped with ClothLight.  It is taken, in this order, from ``--mcml-source DIR`` or
``$CLOTHLIGHT_MCML_SOURCE`` (a folder holding ``mcmlmain.c`` … ``mcml.h``), else downloaded from the
authors' public repository (:data:`SOURCE_ARCHIVE`) into a temporary folder; built with the C compiler
found on the path (``cc``, ``gcc`` or ``clang``) at ``-O3 -march=native``.  Without a compiler or a
source, :func:`build_mcml` says why and the benchmark skips the comparison.
"""

from __future__ import annotations

import io
import os
import pathlib
import re
import shutil
import subprocess
import tarfile
import tempfile
import time
import urllib.request

#: The authors' repository (Lihong V. Wang): MCML 1.2's C files are under SOURCE_FOLDER in it.
SOURCE_ARCHIVE = "https://github.com/lhvwang/MCML/archive/refs/heads/main.tar.gz"
SOURCE_FOLDER = "V1/mcR5unix/mcmlcode"
SOURCE_FILES = ("mcmlmain.c", "mcmlgo.c", "mcmlio.c", "mcmlnr.c", "mcml.h")
CFLAGS = ("-O3", "-march=native")


class MCMLUnavailable(RuntimeError):
    """No MCML to compare with here: the reason is the message."""


def _source_folder(explicit: str | None, workdir: pathlib.Path) -> pathlib.Path:
    for candidate in (explicit, os.environ.get("CLOTHLIGHT_MCML_SOURCE")):
        if candidate:
            folder = pathlib.Path(candidate)
            missing = [name for name in SOURCE_FILES if not (folder / name).is_file()]
            if missing:
                raise MCMLUnavailable(f"{folder} is not MCML's source folder (missing {', '.join(missing)})")
            return folder
    try:
        with urllib.request.urlopen(SOURCE_ARCHIVE, timeout=20) as response:
            data = response.read()
    except OSError as error:
        raise MCMLUnavailable(f"MCML's source could not be downloaded ({error}); give its folder with "
                              "--mcml-source or CLOTHLIGHT_MCML_SOURCE") from None
    target = workdir / "source"
    target.mkdir()
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as archive:
        for member in archive.getmembers():
            parts = member.name.split("/", 1)
            if len(parts) == 2 and parts[1].rsplit("/", 1)[0] == SOURCE_FOLDER and member.isfile():
                name = parts[1].rsplit("/", 1)[1]
                if name in SOURCE_FILES:
                    (target / name).write_bytes(archive.extractfile(member).read())
    return _source_folder(str(target), workdir)


def build_mcml(source: str | None = None) -> pathlib.Path:
    """Compile MCML into a temporary folder; returns the executable.  :class:`MCMLUnavailable` when
    there is no C compiler or no source."""
    compiler = next((name for name in ("cc", "gcc", "clang") if shutil.which(name)), None)
    if compiler is None:
        raise MCMLUnavailable("no C compiler (cc, gcc or clang) on the path")
    workdir = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-mcml-"))
    folder = _source_folder(source, workdir)
    executable = workdir / "mcml"
    sources = [str(folder / name) for name in SOURCE_FILES if name.endswith(".c")]
    built = subprocess.run([compiler, *CFLAGS, "-w", "-o", str(executable), *sources, "-lm"],
                           capture_output=True, text=True)
    if built.returncode != 0:
        raise MCMLUnavailable(f"MCML did not compile with {compiler}: {built.stderr.strip()[:400]}")
    return executable


def slab_input(photons: int, albedo: float, g: float, tau: float, index: float, output: str) -> str:
    """An MCML input file (.mci) of one slab of optical thickness ``tau`` (μt = 1 /cm, so its
    thickness is ``tau`` cm) between media of index 1, with the coarsest grids (1 × 1 × 1 bins: the
    totals are what is compared, and finer grids only cost MCML time)."""
    mua, mus = 1.0 - albedo, albedo
    return (f"1.0\n1\n{output} A\n{int(photons)}\n{tau} {tau}\n1 1 1\n1\n1.0\n"
            f"{index} {mua} {mus} {g} {tau}\n1.0\n")


def run_slab(executable: pathlib.Path, photons: int, albedo: float, g: float, tau: float, index: float) -> dict:
    """Run MCML on the slab; returns the wall seconds of the whole process, photons/s and its total
    reflectance (specular + diffuse) and transmittance."""
    with tempfile.TemporaryDirectory(prefix="clothlight-mcml-run-") as folder:
        folder = pathlib.Path(folder)
        (folder / "slab.mci").write_text(slab_input(photons, albedo, g, tau, index, "slab.mco"))
        start = time.perf_counter()
        subprocess.run([str(executable), "slab.mci"], cwd=folder, check=True, capture_output=True)
        wall = time.perf_counter() - start
        output = (folder / "slab.mco").read_text()
    values = {}
    for key, label in (("specular", "Specular reflectance"), ("diffuse", "Diffuse reflectance"),
                       ("transmitted", "Transmittance")):
        match = re.search(rf"^\s*([-+0-9.eE]+)\s+#{label}", output, re.MULTILINE)
        if match is None:
            raise MCMLUnavailable(f"MCML's output has no {label}")
        values[key] = float(match.group(1))
    return {"wall_s": wall, "photons_per_s": photons / wall, "R_total": values["specular"] + values["diffuse"],
            "T_total": values["transmitted"]}
