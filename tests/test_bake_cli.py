"""``python -m precompute bake`` and ``plot``: tables that follow the spec and describe themselves, exit codes."""

import json
import subprocess
import sys
import tomllib

import numpy as np
import OpenEXR
import pytest

import precompute
from precompute.bake import load_spectral
from precompute.tables.color import channel_ratios, clip_to_gamut, spectral_to_rgb
from precompute.optics.medium import PRESET_DIR, load_preset
from precompute.tables.layout import interpolate_rho
from precompute.tables.exr import HASH_KEY, SCHEMA, content_hash, read_table

pytestmark = pytest.mark.slow

N_I, N_O, PATHS, SEED = 5, 6, 300, 11
SMALL = [f"transport.incidence_resolution={N_I}", f"transport.angular_resolution={N_O}",
         "transport.n_around=8", "transport.n_along=4"]
SMALL_CLI = [arg for setting in SMALL for arg in ("--set", setting)]
TABLES = {"brdf": "brdf.exr", "brdf_stderr": "brdf_stderr.exr", "albedo": "albedo.exr", "closure_lobes": "lobes.exr",
          "unscattered": "unscattered.exr"}


def cli(*args):
    return subprocess.run([sys.executable, "-m", "precompute", *args], capture_output=True, text=True)


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    """One small bake of the default preset through the command line, exported with --out."""
    root = tmp_path_factory.mktemp("bake")
    run = cli("bake", *SMALL_CLI, "--paths", str(PATHS), "--seed", str(SEED), "--cache-dir", str(root / "cache"),
              "--out", str(root / "out"), "--json")
    assert run.returncode == 0, run.stderr[-3000:]
    return root / "out", json.loads(run.stdout), run.stderr


def test_progress_bar_with_time_left_on_stderr(baked):
    _, _, stderr = baked
    assert "100%" in stderr and "left" in stderr


def test_out_folder_holds_valid_tables_of_every_kind(baked):
    out, summary, _ = baked
    assert summary["folder"] == str(out) and summary["brdf_table"] == str(out / "brdf.exr")
    assert summary["simulated"] and not summary["cache_hit"]
    for kind, name in TABLES.items():
        table = read_table(out / name, kind=kind)
        assert table.metadata["schema"] == SCHEMA and table.metadata["cache_key"] == summary["cache_key"]
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no temporary files left


def test_header_carries_everything_needed_to_reproduce(baked):
    out, summary, _ = baked
    with OpenEXR.File(str(out / "brdf.exr")) as exr:
        header = dict(exr.header())
    table = read_table(out / "brdf.exr")
    meta = table.metadata
    assert header[HASH_KEY] == content_hash(table.pixels)
    assert meta["code_version"] == precompute.__version__ and len(meta["code_digest"]["spectral"]) == 64
    # Every medium parameter, with its unit in its name, exactly as the preset defines it.
    assert meta["medium"] == json.loads(json.dumps(load_preset().to_dict()))  # the default preset
    written = tomllib.loads((PRESET_DIR / "red_cotton.toml").read_text())  # the preset file's own numbers
    assert meta["medium"]["fibres"]["diameter_um"] == written["fibres"]["diameter_um"]
    assert meta["medium"]["yarn"]["radius_mm"] == written["yarn"]["radius_mm"] == 0.1
    assert len(meta["medium"]["dye"]["mass_absorption_cm2_per_g"]) > 10  # the dye spectrum itself
    assert meta["transport"] == {"n_around": 8, "n_along": 4, "angular_resolution": N_O, "incidence_resolution": N_I,
                                 "paths_per_cell": PATHS, "target_rel_stderr": None, "seed": SEED}
    assert meta["paths"]["per_incidence_cell"] == [PATHS] * N_O**2
    # n_along even: the reflection across the plane of the axis only, which pairs the N_O² cells
    assert meta["paths"]["incidence_cells_traced"] == N_O**2 // 2 and meta["paths"]["total"] == PATHS * N_O**2 // 2
    assert meta["layout"] == {"incidence_resolution": N_I, "exit_resolution": N_O}
    assert meta["colour"]["illuminant"] == "D65" and "1/sr" in meta["units"]["rho"]
    assert meta["wavelengths_nm"][0] == 390.0 and meta["host_index"] == written["host"]["refractive_index"] == 1.0


def test_tables_follow_the_layout_spec(baked):
    # docs/table-spec.md: pixel (x, y) = (i·N_o + p, j·N_o + q) holds incidence cell j·N_i + i, exit cell q·N_o + p.
    out, _, _ = baked
    spectral, _ = load_spectral(out / "spectral.npz")
    rgb, _ = clip_to_gamut(spectral_to_rgb(spectral["rho"], spectral["wavelengths_nm"]))
    atlas = read_table(out / "brdf.exr").pixels
    assert atlas.shape == (N_I * N_O, N_I * N_O, 3)
    for i, j, p, q in [(0, 0, 0, 0), (3, 1, 2, 5), (1, 2, 5, 0), (2, 3, 4, 4)]:
        np.testing.assert_allclose(atlas[j * N_O + q, i * N_O + p], rgb[j * N_I + i, q * N_O + p], rtol=1e-6)
    albedo_rgb, _ = clip_to_gamut(spectral_to_rgb(spectral["hemispherical_albedo"], spectral["wavelengths_nm"]))
    np.testing.assert_allclose(read_table(out / "albedo.exr").pixels, albedo_rgb.reshape(N_I, N_I, 3), rtol=1e-6)
    stderr = read_table(out / "brdf_stderr.exr").pixels
    assert np.all(stderr >= 0) and np.any(stderr > 0)
    lobes = read_table(out / "lobes.exr")
    assert lobes.pixels.shape == (N_O, lobes.metadata["layout"]["lobe_count"] * N_O, 3)


def test_table1_ratios_are_those_of_the_table_at_normal_incidence_and_view(baked):
    out, summary, _ = baked
    normal = np.array([0.0, 0.0, 1.0])
    rho = interpolate_rho(read_table(out / "brdf.exr").pixels, N_I, normal, normal)
    ratios = channel_ratios(rho)
    assert summary["table1_ratios_normal"] == pytest.approx(ratios, rel=1e-5)
    # A red yarn: red dominates at normal incidence and view.
    assert 0 <= ratios["B/R"] < 1 and 0 <= ratios["G/R"] < 1


def test_second_command_line_bake_is_a_cache_hit(baked):
    out, summary, _ = baked
    cache_dir = out.parent / "cache"
    again = cli("bake", *SMALL_CLI, "--paths", str(PATHS), "--seed", str(SEED), "--cache-dir", str(cache_dir), "--json")
    assert again.returncode == 0
    result = json.loads(again.stdout)
    assert result["cache_hit"] and not result["simulated"] and result["folder"] == summary["cache_folder"]


def test_a_preset_file_with_transport_and_bake_tables(tmp_path):
    preset = (PRESET_DIR / "undyed_cotton.toml").read_text()
    preset += ("\n[transport]\nn_around = 8\nn_along = 4\nangular_resolution = 4\nincidence_resolution = 5\n"
               "paths_per_cell = 64\nseed = 3\n\n[bake]\nilluminant = \"D50\"\n")
    (tmp_path / "mine.toml").write_text(preset)
    run = cli("bake", "--config", str(tmp_path / "mine.toml"), "--cache-dir", str(tmp_path / "cache"), "--json")
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads(run.stdout)
    assert summary["transport"]["seed"] == 3 and summary["transport"]["paths_per_cell"] == 64
    assert summary["transport"]["target_rel_stderr"] is None and summary["colour"]["illuminant"] == "D50"
    text = cli("bake", "--config", str(tmp_path / "mine.toml"), "--cache-dir", str(tmp_path / "cache"))
    assert text.returncode == 0 and "cache hit" in text.stdout and "B/R =" in text.stdout


@pytest.mark.parametrize(
    "args, parameter",
    [
        (["--set", "dye.weight_percent=-3"], "dye.weight_percent"),
        (["--set", "transport.photons=5"], "transport.photons"),
        (["--set", "transport.n_around=2.5"], "transport.n_around"),
        (["--set", "transport.incidence_resolution=1"], "transport.incidence_resolution"),
        (["--set", "bake.illuminant=D66"], "bake.illuminant"),
        (["--set", "yarn.cross_section=\"ellipse\"", "--set", "yarn.semi_axes_mm=[0.1, 0.05]"], "yarn.cross_section"),
        (["--set", "no-equals-sign"], "--set"),
        (["--preset", "silk"], "--preset"),
        (["--paths", "0"], "transport.paths_per_cell"),
        (["--target-error", "1.5"], "transport.target_rel_stderr"),
        (["--threads", "0"], "threads"),
        (["--seed", "-1"], "transport.seed"),
        # a wrong value hidden by a later one is refused all the same
        (["--set", "dye.weight_percent=-3", "--set", "dye.weight_percent=2"], "dye.weight_percent"),
        (["--set", "transport.seed=-1", "--seed", "3"], "transport.seed"),
        (["--set", "transport.paths_per_cell=0", "--target-error", "0.05"], "transport.paths_per_cell"),
    ],
)
def test_bad_input_exits_2_naming_the_parameter(tmp_path, args, parameter):
    run = cli("bake", *args, "--cache-dir", str(tmp_path))
    assert run.returncode == 2, run.stderr
    # Checked by the API (error: NAME = …) or, for options with bounds, as argparse parses them
    # (… error: argument --paths: NAME = …): either way the parameter and its range, no traceback.
    assert run.stderr.startswith(f"error: {parameter} = ") or f"error: argument {args[0]}: {parameter} = " in run.stderr
    assert "Traceback" not in run.stderr
    assert not (tmp_path / "tables").exists()  # refused before any work


def test_an_unusable_cache_folder_is_bad_input(tmp_path):
    blocked = tmp_path / "a-file"
    blocked.write_text("")
    run = cli("bake", *SMALL_CLI, "--paths", "16", "--cache-dir", str(blocked))
    assert run.returncode == 2 and run.stderr.startswith("error: --cache-dir = ") and "Traceback" not in run.stderr


def test_plot_writes_the_figures(baked, tmp_path):
    out, _, _ = baked
    run = cli("plot", str(out / "brdf.exr"), "--out", str(tmp_path / "plots"))
    assert run.returncode == 0, run.stderr[-2000:]
    names = {"rho_in_plane.png", "rho_polar.png", "albedo_spectra.png", "swatches_front_back.png"}
    assert {p.name for p in (tmp_path / "plots").iterdir()} == names
    for name in names:
        assert (tmp_path / "plots" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (tmp_path / "plots" / name).stat().st_size > 10_000


def test_plot_refuses_what_is_not_a_table(tmp_path):
    with OpenEXR.File({}, {"RGB": np.ones((4, 4, 3), np.float32)}) as exr:
        exr.write(str(tmp_path / "render.exr"))
    run = cli("plot", str(tmp_path / "render.exr"), "--out", str(tmp_path / "plots"))
    assert run.returncode == 2 and run.stderr.startswith("error: TABLE = ") and "not a ClothLight table" in run.stderr
