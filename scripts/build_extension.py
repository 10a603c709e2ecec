"""Build the ClothLight extension zip(s) with Blender's own extension tool, then validate them.

    python scripts/build_extension.py --output-dir dist --prebake-cloth       # linux-x64, wheels, pre-baked tables
    python scripts/build_extension.py --platforms linux-x64 windows-x64 macos-arm64 macos-x64
    python scripts/build_extension.py --no-wheels --prebake none              # add-on only, any platform

What a zip holds, and why:

* the add-on (``clothlight/``, ``osl/``, ``precompute/``), as ``blender_manifest.toml``'s
  ``[build]`` table selects;
* **wheels** of what the in-Blender bake and fit import and Blender does not ship
  (:data:`clothlight.jobs.BUNDLED_DEPENDENCIES`: numba, llvmlite, scipy, colour-science,
  typing-extensions, miepython, OpenEXR, platformdirs, and the fit's optimiser cma, pure Python),
  for CPython 3.11 and the zip's platform; with them, where the platform has a wheel of it, Embree's
  ``embreex`` (:data:`clothlight.jobs.CLOTH_TRACE_DEPENDENCIES`), with which Bake Cloth traces a new
  weave's cloth response in seconds (no macOS 12 wheel: there it renders it).
  Never numpy: all extensions' wheels share one folder that comes before Blender's own
  site-packages, so a bundled numpy would replace Blender's.  Versions come from
  ``requirements.txt`` (the one place for pins); a dependency it does not pin (numba's llvmlite,
  colour-science's typing-extensions) takes the version installed in this environment, which was
  resolved from ``requirements.txt``.  If one of them has no wheel for a platform, that
  platform's zip bundles none of them and the add-on there bakes nothing but uses the pre-baked
  tables (the panel says why);
* **pre-baked tables** of the shipped medium presets (``prebaked/<preset>/``), baked here by
  the same worker the add-on runs (cached in the bake's user cache, so only the first build bakes);
* **pre-baked cloth tables** of the same presets (``prebaked_cloth/<preset>/``): the garment's
  cloth BSDF measured with those yarn tables on the default woven sample by the add-on's Bake Cloth
  worker (:class:`clothlight.jobs.ClothBakeJob`), so that Apply Garment Material needs no bake.  The
  first build renders the weave's cloth response (docs/garment.md, cached); every preset after it
  takes seconds.

Each platform gets its own zip (``clothlight-<version>-<platform>.zip``), its staged manifest
listing that platform and its wheels, and ``blender_version_max = "5.1.0"`` whenever binary
wheels are in it (Blender 5.1 moves to Python 3.13).  Downloaded wheels are kept in
``--wheelhouse`` so later builds work offline.  Prints one zip path per line, last.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.metadata
import importlib.util
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(REPO_ROOT) not in sys.path:  # a script in scripts/: make the repository's packages importable
    sys.path.insert(0, str(REPO_ROOT))

from clothlight.jobs import (BUNDLED_DEPENDENCIES, CLOTH_TRACE_DEPENDENCIES, BakeCancelled, BakeFailed,  # noqa: E402
                             BakeJob, ClothBakeJob, JobCancelled, JobFailed)
from clothlight.medium_settings import preset_request  # noqa: E402

#: pip's platform tags for each Blender platform: Blender 5.0 needs glibc 2.28 on Linux and
#: runs on macOS 11.2+; scipy's and numba's macOS wheels need macOS 12, which is what a bake
#: there needs too.
PLATFORM_TAGS = {
    "linux-x64": ["manylinux_2_28_x86_64"],
    "windows-x64": ["win_amd64"],
    "macos-arm64": ["macosx_12_0_arm64"],
    "macos-x64": ["macosx_12_0_x86_64"],
}
PYTHON_VERSION = "3.11"
#: Blender versions whose Python (3.11) the bundled binary wheels are built for.
BLENDER_VERSION_MAX = "5.1.0"
#: What the stage copy of the source leaves out (the manifest's [build] table filters the rest).
STAGE_IGNORE = shutil.ignore_patterns(".git", ".venv", "dist", "out", "__pycache__", ".pytest_cache", ".hypothesis",
                                      "*.oso", "*.pyc", "*.nbi", "*.nbc", "example_blends", "benchmarks", "tests",
                                      "prebaked", "prebaked_cloth", "wheels")
#: Goniometer settings a cloth pre-bake may set (:class:`clothlight.jobs.ClothBakeJob`).
CLOTH_SETTING_KEYS = ("incidence_resolution", "exit_resolution", "pixels_per_patch", "samples")
#: Files of a bake folder the add-on reads (spectral.npz stays behind: it is large and only the bake uses it).
PREBAKED_FILES = ("brdf.exr", "lobes.exr", "unscattered.exr", "brdf_stderr.exr", "albedo.exr", "summary.json")


def _normalise(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def requirement_pins(path: pathlib.Path = REPO_ROOT / "requirements.txt") -> dict[str, str]:
    """``name==version`` lines of a requirements file, by normalised name."""
    pins = {}
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        match = re.fullmatch(r"([A-Za-z0-9][A-Za-z0-9._-]*)\s*==\s*([^\s;]+)", line)
        if match:
            pins[_normalise(match.group(1))] = match.group(2)
    return pins


def bundled_versions(dependencies: dict[str, str] = BUNDLED_DEPENDENCIES) -> tuple[dict[str, str], list[str]]:
    """Version of every distribution of ``dependencies`` (import name → distribution), and notes on those
    requirements.txt does not pin."""
    pins = requirement_pins()
    versions, notes = {}, []
    for dist in dependencies.values():
        if _normalise(dist) == "numpy":
            raise SystemExit("numpy must never be bundled: it would replace Blender's")
        version = pins.get(_normalise(dist))
        if version is None:
            try:
                version = importlib.metadata.version(dist)
            except importlib.metadata.PackageNotFoundError:
                raise SystemExit(f"{dist} is neither pinned in requirements.txt nor installed: "
                                 "run `make setup`") from None
            notes.append(f"{dist}=={version} (not pinned in requirements.txt: the version installed from it)")
        versions[dist] = version
    return versions, notes


def blender_extension_tool() -> pathlib.Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("bpy is not installed: run `make setup`")
    tools = sorted(pathlib.Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not tools:
        raise SystemExit("Blender's extension tool (blender_ext.py) is missing from the bpy wheel")
    return tools[-1]


# -- wheels --------------------------------------------------------------------------------------


def _pip_download(requirement: str, platform: str, dest: pathlib.Path, wheelhouse: pathlib.Path,
                  offline: bool) -> bool:
    abi = "cp" + PYTHON_VERSION.replace(".", "")
    command = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:",
               "--python-version", PYTHON_VERSION, "--implementation", "cp", "--abi", abi,
               "--find-links", str(wheelhouse), "--dest", str(dest), requirement]
    for tag in PLATFORM_TAGS[platform]:
        command += ["--platform", tag]
    if offline:
        command.insert(4, "--no-index")
    return subprocess.run(command, capture_output=True, text=True).returncode == 0


def platform_wheels(platform: str, versions: dict[str, str],
                    wheelhouse: pathlib.Path) -> tuple[list[pathlib.Path], list[str]]:
    """Wheels of every bundled distribution for ``platform`` (from the wheelhouse, else downloaded
    into it), and the distributions that have none."""
    wheelhouse.mkdir(parents=True, exist_ok=True)
    found, missing = [], []
    with tempfile.TemporaryDirectory() as scratch:
        for dist, version in versions.items():
            dest = pathlib.Path(scratch) / _normalise(dist)
            requirement = f"{dist}=={version}"
            if not (_pip_download(requirement, platform, dest, wheelhouse, offline=True)
                    or _pip_download(requirement, platform, dest, wheelhouse, offline=False)):
                missing.append(requirement)
                continue
            for wheel in dest.glob("*.whl"):
                kept = wheelhouse / wheel.name
                if not kept.exists():
                    shutil.copy2(wheel, kept)
                found.append(kept)
    return found, missing


# -- pre-baked tables ----------------------------------------------------------------------------


def prebake(presets: list[str], stage: pathlib.Path, cache_dir: pathlib.Path | None,
            transport: dict | None = None, cloth_settings: dict | None = None) -> None:
    """Bake each preset's tables (or find them in the cache) into ``stage/prebaked/<preset>``: the
    untouched preset's bake, or with ``transport`` settings replacing its own (tests use tiny ones);
    then its cloth tables (:func:`prebake_cloth`) unless ``cloth_settings`` is None."""
    from precompute.cache import entries as cache

    cache_dir = cache_dir or cache.default_cache_dir()
    for name in presets:
        request = dataclasses.replace(preset_request(name), **(transport or {}))
        started = time.perf_counter()
        job = BakeJob(request, cache_dir=cache_dir)
        shown = [-1]

        def progress(fraction, name=name):
            if int(fraction * 10) != shown[0]:
                shown[0] = int(fraction * 10)
                print(f"pre-baking {name}: {fraction:.0%}", file=sys.stderr, flush=True)

        try:
            outcome = job.wait(on_progress=progress)
        except (BakeFailed, BakeCancelled, OSError) as error:
            print(job.log, file=sys.stderr)
            raise SystemExit(f"pre-baking {name} failed: {error}") from None
        folder = stage / "prebaked" / name
        folder.mkdir(parents=True, exist_ok=True)
        for file_name in PREBAKED_FILES:
            shutil.copy2(outcome.folder / file_name, folder / file_name)
        (folder / "request.json").write_text(request.to_json())
        print(f"pre-baked {name} in {time.perf_counter() - started:.0f} s "
              f"({'cache hit' if outcome.cache_hit else 'baked'})", file=sys.stderr)
        if cloth_settings is not None:
            prebake_cloth(name, folder, stage, cache_dir, cloth_settings)


def prebake_cloth(name: str, yarn: pathlib.Path, stage: pathlib.Path, cache_dir: pathlib.Path,
                  settings: dict) -> None:
    """The cloth tables of the pre-baked yarn tables ``yarn`` (goniometer ``settings`` by name, {}:
    the defaults) into ``stage/prebaked_cloth/<name>``, with the yarn's request beside them."""
    from clothlight.garment.tables import CLOTH_FOLDER_FILES

    started = time.perf_counter()
    job = ClothBakeJob(yarn, cache_dir=cache_dir, settings=settings)
    try:
        outcome = job.wait(on_progress=lambda fraction: None)
    except (JobFailed, JobCancelled, OSError) as error:
        print(job.log, file=sys.stderr)
        raise SystemExit(f"pre-baking {name}'s cloth failed: {error}") from None
    folder = stage / "prebaked_cloth" / name
    folder.mkdir(parents=True, exist_ok=True)
    for file_name in CLOTH_FOLDER_FILES:
        if (outcome.folder / file_name).is_file():
            shutil.copy2(outcome.folder / file_name, folder / file_name)
    shutil.copy2(yarn / "request.json", folder / "request.json")
    print(f"pre-baked {name}'s cloth in {time.perf_counter() - started:.0f} s "
          f"({'measured' if outcome.rendered else 'cache hit'})", file=sys.stderr)


# -- manifest and build --------------------------------------------------------------------------


def staged_manifest(source: str, platforms: list[str] | None, wheels: list[str], binary: bool) -> str:
    """``source`` with ``platforms``, ``wheels`` and (for binary wheels) ``blender_version_max`` added
    as top-level keys (before the first table)."""
    lines = []
    if platforms:
        lines.append("platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]")
    if wheels:
        lines.append("wheels = [\n" + "".join(f'  "./wheels/{w}",\n' for w in wheels) + "]")
    if binary:
        lines.append(f'blender_version_max = "{BLENDER_VERSION_MAX}"')
    for key in ("platforms", "wheels", "blender_version_max"):
        if re.search(rf"^{key}\s*=", source, re.MULTILINE):
            raise SystemExit(f"blender_manifest.toml must not set {key}: the build script writes it")
    table = re.search(r"^\[", source, re.MULTILINE)
    cut = table.start() if table else len(source)
    added = "# Written by scripts/build_extension.py\n" + "\n".join(lines) + "\n\n" if lines else ""
    return source[:cut] + added + source[cut:]


def _run_tool(tool: pathlib.Path, *args: str) -> None:
    result = subprocess.run([sys.executable, str(tool), *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"blender_ext.py {args[0]} failed:\n{result.stdout}{result.stderr}")


def build_extension(output_dir: pathlib.Path, *, platforms: list[str] | None = ("linux-x64",),
                    prebake_presets: list[str] = (), prebake_transport: dict | None = None,
                    prebake_cloth_settings: dict | None = None,
                    wheelhouse: pathlib.Path | None = None,
                    cache_dir: pathlib.Path | None = None) -> list[pathlib.Path]:
    """Build and validate one zip per platform (one universal zip without wheels when ``platforms``
    is None); return their paths."""
    output_dir.mkdir(parents=True, exist_ok=True)
    tool = blender_extension_tool()
    manifest_source = (REPO_ROOT / "blender_manifest.toml").read_text()
    zips = []
    with tempfile.TemporaryDirectory(prefix="clothlight-stage-") as scratch:
        stage = pathlib.Path(scratch) / "clothlight"
        shutil.copytree(REPO_ROOT, stage, ignore=STAGE_IGNORE)
        if prebake_presets:
            prebake(list(prebake_presets), stage, cache_dir, prebake_transport, prebake_cloth_settings)
        version = re.search(r'^version\s*=\s*"([^"]+)"', manifest_source, re.MULTILINE).group(1)
        if platforms is None:
            (stage / "blender_manifest.toml").write_text(staged_manifest(manifest_source, None, [], False))
            zip_path = output_dir / f"clothlight-{version}.zip"
            _run_tool(tool, "build", "--source-dir", str(stage), "--output-filepath", str(zip_path))
            _run_tool(tool, "validate", str(zip_path))
            return [zip_path]
        versions, notes = bundled_versions()
        tracer_versions, tracer_notes = bundled_versions(CLOTH_TRACE_DEPENDENCIES)
        for note in notes + tracer_notes:
            print(f"note: {note}", file=sys.stderr)
        for platform in platforms:
            wheels, missing = platform_wheels(platform, versions, wheelhouse)
            if missing:
                print(f"warning: {platform}: no wheel for {', '.join(missing)}; its zip bundles no wheels, so "
                      "Bake is unavailable there and the pre-baked tables are used", file=sys.stderr)
                wheels = []
            else:
                tracer, missing = platform_wheels(platform, tracer_versions, wheelhouse)
                if missing:
                    print(f"note: {platform}: no wheel for {', '.join(missing)}; Bake Cloth renders a new weave's "
                          "cloth response there (about an hour) instead of tracing it", file=sys.stderr)
                wheels += tracer
            wheel_dir = stage / "wheels"
            shutil.rmtree(wheel_dir, ignore_errors=True)
            wheel_dir.mkdir()
            for wheel in wheels:
                shutil.copy2(wheel, wheel_dir / wheel.name)
            binary = any(not wheel.name.endswith("-none-any.whl") for wheel in wheels)
            (stage / "blender_manifest.toml").write_text(
                staged_manifest(manifest_source, [platform], sorted(w.name for w in wheels), binary))
            zip_path = output_dir / f"clothlight-{version}-{platform.replace('-', '_')}.zip"
            _run_tool(tool, "build", "--source-dir", str(stage), "--output-filepath", str(zip_path))
            _run_tool(tool, "validate", str(zip_path))
            zips.append(zip_path)
    return zips


def main(argv=None) -> None:
    from precompute.optics import medium

    presets = medium.preset_names()
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output-dir", type=pathlib.Path, default=REPO_ROOT / "dist")
    parser.add_argument("--platforms", nargs="+", choices=[*PLATFORM_TAGS, "all"], default=["linux-x64"],
                        help="platforms to build a zip for, with their wheels (default: linux-x64)")
    parser.add_argument("--no-wheels", action="store_true",
                        help="one zip for every platform, without wheels: no bakes in Blender, pre-baked tables only")
    parser.add_argument("--prebake", nargs="+", default=["all"], metavar="PRESET",
                        help="presets whose tables to ship: 'all' (default), 'none' or names from "
                             + ", ".join(presets))
    parser.add_argument("--prebake-transport", nargs="+", default=[], metavar="KEY=VALUE",
                        help="transport settings of the pre-bakes instead of each preset's, e.g. paths_per_cell=64 "
                             "angular_resolution=4 (tests); the add-on uses them for exactly those settings")
    parser.add_argument("--prebake-cloth", nargs="*", default=None, metavar="KEY=VALUE",
                        help="ship each pre-baked preset's cloth tables too: with no value at the defaults of "
                             "python -m clothlight.garment bake, or with these goniometer settings, e.g. "
                             "incidence_resolution=3 exit_resolution=2 (tests); absent: no cloth tables")
    parser.add_argument("--wheelhouse", type=pathlib.Path,
                        default=pathlib.Path.home() / ".cache" / "clothlight" / "wheels",
                        help="folder keeping downloaded wheels between builds (default ~/.cache/clothlight/wheels)")
    parser.add_argument("--cache-dir", type=pathlib.Path,
                        help="bake cache for the pre-baked tables (default: the user cache)")
    args = parser.parse_args(argv)
    chosen = presets if args.prebake == ["all"] else [] if args.prebake == ["none"] else args.prebake
    unknown = sorted(set(chosen) - set(presets))
    if unknown:
        parser.error(f"--prebake: unknown preset {unknown[0]!r}; choose from {', '.join(presets)}, all or none")
    transport = {}
    for item in args.prebake_transport:
        key, _, value = item.partition("=")
        if key not in ("seed", "paths_per_cell", "target_rel_stderr", "n_around", "n_along", "angular_resolution",
                       "incidence_resolution") or not value:
            parser.error(f"--prebake-transport: {item!r} is not KEY=VALUE with a transport key of BakeRequest")
        if key == "target_rel_stderr":
            transport[key] = float(value)
        else:
            transport[key] = value if (key, value) == ("incidence_resolution", "auto") else int(value)
    if "paths_per_cell" in transport:
        transport.setdefault("target_rel_stderr", None)
    cloth_settings = None
    if args.prebake_cloth is not None:
        cloth_settings = {}
        for item in args.prebake_cloth:
            key, _, value = item.partition("=")
            if key not in CLOTH_SETTING_KEYS or not value.isdigit():
                parser.error(f"--prebake-cloth: {item!r} is not KEY=VALUE with an integer value and a key of "
                             + ", ".join(CLOTH_SETTING_KEYS))
            cloth_settings[key] = int(value)
    platforms = None if args.no_wheels else (list(PLATFORM_TAGS) if "all" in args.platforms else args.platforms)
    for zip_path in build_extension(args.output_dir.resolve(), platforms=platforms, prebake_presets=chosen,
                                    prebake_transport=transport, prebake_cloth_settings=cloth_settings,
                                    wheelhouse=args.wheelhouse,
                                    cache_dir=args.cache_dir):
        print(zip_path)


if __name__ == "__main__":
    main()
