"""One check of a table folder (precompute/tables/folder.py), used by every reader, and output folders
written as a whole.

A bake folder passes with exactly the data it was written with, or is refused with a TableError that
names the file and the reason — truncated, resized, of another layout than its summary, NaN or
negative, foreign, of an older schema, mixed from two bakes, missing — and never reaches a render.
``bake --out DIR`` swaps a complete new folder in for the previous one: a process killed at any
moment leaves one of the two, complete.
"""

import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import types

import numpy as np
import OpenEXR
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from precompute.tables import folder as table_folder
from precompute.errors import ParameterError
from precompute.tables.folder import (
    FILE_HASHES_KEY,
    SPECTRAL_FILE,
    SUMMARY_FILE,
    YARN_FOLDER_FILES,
    check_output_folder,
    check_yarn_table_folder,
    replace_folder,
    staged_folder,
)
from precompute.tables.exr import (
    CACHE_KEY_KEY,
    HASH_KEY,
    KIND_KEY,
    METADATA_KEY,
    SCHEMA,
    SCHEMA_KEY,
    VERSION_KEY,
    TableError,
    content_hash,
    read_table,
    write_table,
)
from tests.helpers import PREBAKED_TRANSPORT, REPO, write_exr, write_yarn_table_folder

N_I, N_O, LOBES, SAMPLES = 5, 4, 5, 9
#: What a reader takes from a yarn folder's summary besides the tables.
READER_KEYS = ("incidence_resolution", "exit_resolution", "lobe_count", "lobe_shape", "host_index",
               "unscattered_samples", "cache_key")


def images(seed):
    rng = np.random.default_rng(seed)
    brdf = 10.0 ** rng.uniform(-4.0, 0.0, (N_I * N_O, N_I * N_O, 3))  # five decades, as a real ρ
    return brdf, rng.uniform(0.0, 1.0, (N_O, LOBES * N_O, 3)), rng.uniform(0.0, 1.0, (1, SAMPLES, 3))


def yarn_folder(path, seed, **options):
    """A yarn bake folder (tests/helpers.py), the bake ``seed``'s: its own pixels and cache key."""
    return write_yarn_table_folder(path, *images(seed), incidence_resolution=N_I, exit_resolution=N_O,
                                   cache_key=f"{seed:02x}" * 32, **options)


@pytest.fixture(scope="module")
def bakes(tmp_path_factory):
    """Two bakes, A and B, each with and without the summary's list of file hashes; never modified."""
    root = tmp_path_factory.mktemp("bakes")
    return {(name, listed): yarn_folder(root / f"{name}{'_listed' if listed else ''}", seed, listed=listed)
            for name, seed in (("A", 1), ("B", 2)) for listed in (True, False)}


def copy_of(folder, into) -> pathlib.Path:
    target = pathlib.Path(into) / "bake"
    shutil.copytree(folder, target)
    return target


def same_data(checked, reference) -> bool:
    """The check gave exactly the data of ``reference`` (another check's result)."""
    return (sorted(checked.tables) == sorted(reference.tables)
            and all(np.array_equal(checked.tables[name].pixels, reference.tables[name].pixels)
                    for name in reference.tables)
            and all(checked.summary.get(key) == reference.summary.get(key) for key in READER_KEYS))


# ---- edits that make a folder wrong -------------------------------------------------------------


def truncate(folder, name, keep=0.6):
    data = (folder / name).read_bytes()
    (folder / name).write_bytes(data[: int(len(data) * keep)])


def raw_table(folder, name, pixels=None, schema=SCHEMA, **edits):
    """Rewrite a table bypassing write_table's checks, its header consistent with the new pixels (the
    content hash recomputed): what a careless tool, not a damaged disk, would leave."""
    table = read_table(folder / name)
    pixels = np.ascontiguousarray(table.pixels if pixels is None else pixels, dtype=np.float32)
    metadata = {**table.metadata, **edits}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, SCHEMA_KEY: schema, KIND_KEY: metadata["table"],
              VERSION_KEY: "test", CACHE_KEY_KEY: metadata["cache_key"], HASH_KEY: content_hash(pixels),
              METADATA_KEY: json.dumps(metadata)}
    with OpenEXR.File(header, {"RGB": pixels}) as exr:
        exr.write(str(folder / name))


def rewrite(folder, name, scale=1.0, **edits):
    """Rewrite a table with write_table: a valid table, of the same bake id unless edited."""
    table = read_table(folder / name)
    write_table(folder / name, table.pixels * scale, {**table.metadata, **edits})


def edit_summary(folder, **edits):
    summary = json.loads((folder / SUMMARY_FILE).read_text())
    summary.update(edits)
    (folder / SUMMARY_FILE).write_text(json.dumps(summary))


def wider_table(folder):
    """brdf.exr rewritten as a consistent table of N_o = 6 exit cells where the summary says 4."""
    table = read_table(folder / "brdf.exr")
    layout = {**table.metadata["layout"], "exit_resolution": 6}
    write_table(folder / "brdf.exr", np.full((N_I * 6, N_I * 6, 3), 0.1), {**table.metadata, "layout": layout})


def with_pixel(folder, name, value):
    pixels = read_table(folder / name).pixels.copy()
    pixels[0, 1, 0] = value
    raw_table(folder, name, pixels)


#: (what is done to a copy of bake A, given A's and B's folders; the file the message names; its reason)
BROKEN = {
    "truncated brdf.exr": (lambda f, b: truncate(f, "brdf.exr"), "brdf.exr", "truncated"),
    "truncated lobes.exr": (lambda f, b: truncate(f, "lobes.exr", 0.9), "lobes.exr", "truncated"),
    "truncated summary.json": (lambda f, b: truncate(f, SUMMARY_FILE), SUMMARY_FILE, "unreadable"),
    "resized EXR, its hash consistent": (
        lambda f, b: raw_table(f, "brdf.exr", read_table(f / "brdf.exr").pixels[:, :-1]), "brdf.exr", "its layout"),
    "6 × 6 exit grid where the summary says 4 × 4": (
        lambda f, b: wider_table(f), "brdf.exr", "exit_resolution 6, where the folder's summary.json says 4"),
    "summary resolution other than the tables'": (
        lambda f, b: edit_summary(f, incidence_resolution=7), "brdf.exr", "incidence_resolution 5, where"),
    "NaN pixel": (lambda f, b: with_pixel(f, "brdf.exr", np.nan), "brdf.exr", "not finite"),
    "negative pixel": (lambda f, b: with_pixel(f, "lobes.exr", -0.25), "lobes.exr", "not finite and ≥ 0"),
    "foreign EXR": (lambda f, b: write_exr(f / "unscattered.exr", np.ones((1, SAMPLES, 3))), "unscattered.exr",
                    "not a ClothLight table"),
    "table of an older schema": (lambda f, b: raw_table(f, "brdf.exr", schema="clothlight-table/3"), "brdf.exr",
                                 "schema 'clothlight-table/3', this version reads .*bake it again"),
    "folder of an older schema": (lambda f, b: edit_summary(f, schema="clothlight-table/3"), SUMMARY_FILE,
                                  "schema 'clothlight-table/3', this ClothLight reads .*bake them again"),
    "another kind under the name": (lambda f, b: shutil.copy(f / "brdf_stderr.exr", f / "brdf.exr"), "brdf.exr",
                                    "a 'brdf_stderr' table, not the 'brdf' table"),
    "a table of another bake": (lambda f, b: shutil.copy(b / "lobes.exr", f / "lobes.exr"), "lobes.exr",
                                "another bake"),
    "an optional table of another bake": (lambda f, b: shutil.copy(b / "albedo.exr", f / "albedo.exr"),
                                          "albedo.exr", "another bake"),
    "the summary of another bake": (lambda f, b: shutil.copy(b / SUMMARY_FILE, f / SUMMARY_FILE), "brdf.exr",
                                    "another bake"),
    "the simulation of another bake": (lambda f, b: shutil.copy(b / SPECTRAL_FILE, f / SPECTRAL_FILE),
                                       SPECTRAL_FILE, "another bake"),
    "truncated spectral.npz": (lambda f, b: truncate(f, SPECTRAL_FILE), SPECTRAL_FILE, "truncated or corrupt"),
    "missing table": (lambda f, b: (f / "unscattered.exr").unlink(), "unscattered.exr", "missing"),
    "missing summary": (lambda f, b: (f / SUMMARY_FILE).unlink(), "", "no summary.json"),
    "host index edited in the summary": (lambda f, b: edit_summary(f, host_index=1.5), "brdf.exr",
                                         "header host_index 1.557, where the folder's summary.json says 1.5"),
    "lobe shape edited in the summary": (
        lambda f, b: edit_summary(f, lobe_shape={**json.loads((f / SUMMARY_FILE).read_text())["lobe_shape"],
                                                 "retroreflection_alpha": 0.9}), "lobes.exr", "lobe_shape"),
    "resolution not an integer": (lambda f, b: edit_summary(f, exit_resolution=4.0), SUMMARY_FILE,
                                  "exit_resolution 4.0 is not an integer"),
    "summary not an object": (lambda f, b: (f / SUMMARY_FILE).write_text("[1, 2]"), SUMMARY_FILE,
                              "not a bake summary"),
}
#: Found only through the summary's list of file hashes (bakes write it; older folders lack it).
BROKEN_LISTED = {
    "a table of the same bake id, other pixels": (lambda f, b: rewrite(f, "brdf.exr", scale=1.62), "brdf.exr",
                                                  "not those its summary.json lists"),
    "a file the list lacks": (
        lambda f, b: edit_summary(f, **{FILE_HASHES_KEY: {
            name: digest for name, digest in json.loads((f / SUMMARY_FILE).read_text())[FILE_HASHES_KEY].items()
            if name != "albedo.exr"}}), "albedo.exr", "not among the files"),
}


# ---- the check ----------------------------------------------------------------------------------


@pytest.mark.parametrize("listed", [True, False])
def test_a_complete_folder_passes_with_the_data_it_was_written_with(bakes, listed):
    folder = bakes["A", listed]
    checked = check_yarn_table_folder(folder)
    brdf, lobes, unscattered = images(1)
    assert sorted(checked.tables) == ["albedo.exr", "brdf.exr", "brdf_stderr.exr", "lobes.exr", "unscattered.exr"]
    np.testing.assert_array_equal(checked.tables["brdf.exr"].pixels, brdf.astype(np.float32))
    np.testing.assert_array_equal(checked.tables["lobes.exr"].pixels, lobes.astype(np.float32))
    np.testing.assert_array_equal(checked.tables["unscattered.exr"].pixels, unscattered.astype(np.float32))
    assert checked.folder == folder.absolute() and checked.summary["cache_key"] == "01" * 32


def test_the_check_knows_the_files_a_bake_writes():
    from precompute import bake

    assert table_folder.SPECTRAL_FILE == bake.SPECTRAL_FILE and table_folder.YARN_TABLE_FILES == bake.TABLE_FILES


def test_a_folder_of_the_tables_the_material_reads_passes(tmp_path):
    """Pre-baked tables and the example scenes ship brdf.exr, lobes.exr, unscattered.exr and the
    summary only."""
    folder = yarn_folder(tmp_path / "shipped", 3, optional=False)
    assert sorted(check_yarn_table_folder(folder).tables) == ["brdf.exr", "lobes.exr", "unscattered.exr"]


def assert_refused_naming_the_file(bakes, tmp_path, breakage, listed):
    """Bake A's folder, broken by ``breakage`` = (break_it(folder, bake_b), file name, reason):
    refused with a message that names the file and matches the reason."""
    break_it, name, reason = breakage
    folder = copy_of(bakes["A", listed], tmp_path)
    break_it(folder, bakes["B", listed])
    with pytest.raises(TableError, match=reason) as refusal:
        check_yarn_table_folder(folder)
    assert str(folder / name) in str(refusal.value)


@pytest.mark.parametrize("listed", [True, False])
@pytest.mark.parametrize("case", sorted(BROKEN))
def test_a_broken_folder_is_refused_naming_the_file_and_the_reason(bakes, tmp_path, case, listed):
    assert_refused_naming_the_file(bakes, tmp_path, BROKEN[case], listed)


@pytest.mark.parametrize("case", sorted(BROKEN_LISTED))
def test_the_summarys_list_ties_every_file_to_its_bake(bakes, tmp_path, case):
    assert_refused_naming_the_file(bakes, tmp_path, BROKEN_LISTED[case], listed=True)


def test_a_folder_baked_before_the_list_is_still_read(bakes, tmp_path):
    """Without the list the headers are all there is: a table re-written consistently with the
    folder's bake id passes, as it did before bakes listed their files."""
    older = copy_of(bakes["A", False], tmp_path)
    rewrite(older, "brdf.exr", scale=1.62)
    np.testing.assert_array_equal(check_yarn_table_folder(older).tables["brdf.exr"].pixels,
                                  1.62 * read_table(bakes["A", False] / "brdf.exr").pixels)


def test_yarn_tables_from_bake_checks_the_whole_folder(bakes, tmp_path):
    from clothlight.yarn_tables import yarn_tables_from_bake

    tables = yarn_tables_from_bake(bakes["A", True])
    assert tables.brdf_path == bakes["A", True].resolve() / "brdf.exr"
    assert (tables.incidence_resolution, tables.exit_resolution, tables.unscattered_samples) == (N_I, N_O, SAMPLES)
    assert tables.host_index == 1.557
    folder = copy_of(bakes["A", True], tmp_path)
    truncate(folder, "brdf.exr")
    with pytest.raises(TableError, match="brdf.exr: truncated"):
        yarn_tables_from_bake(folder)
    with pytest.raises(TableError, match="no such folder"):
        yarn_tables_from_bake(tmp_path / "nothing")


# ---- cloth folders ------------------------------------------------------------------------------


CLOTH_N = 3


@pytest.fixture(scope="module")
def cloth_bake(tmp_path_factory, bakes):
    """A cloth bake folder written by the garment bake's own writers from a synthetic measurement, one
    that sends away less light than it receives (the writer refuses any other: check_energy)."""
    from clothlight.garment.goniometry import ClothMeasurement
    from clothlight.garment.tables import DETAIL_FILE, write_cloth_summary, write_cloth_tables
    from clothlight.yarn_tables import yarn_tables_from_bake

    folder = tmp_path_factory.mktemp("cloth") / "cloth"
    rng = np.random.default_rng(5)
    cells = (CLOTH_N**2, CLOTH_N**2)
    measurement = ClothMeasurement(
        rho={side: rng.uniform(0.005, 0.05, (*cells, 3)) for side in ("front", "back")},
        specular={side: rng.uniform(0.0, 0.01, cells) for side in ("front", "back")},
        specular_visibility={side: rng.uniform(0.0, 1.0, cells) for side in ("front", "back")},
        coverage={side: rng.uniform(0.5, 0.9, CLOTH_N**2) for side in ("front", "back")},
        specular_parameters={"weight": 1.0, "slope": 0.8, "ior": 1.557}, patch_mm=1.0, sample_size_mm=(4.0, 4.0),
        half_thickness_mm=0.2, render_seconds=0.0)
    goniometer = types.SimpleNamespace(incidence_resolution=CLOTH_N, exit_resolution=CLOTH_N, weave=None,
                                       to_dict=lambda: {"incidence_resolution": CLOTH_N, "exit_resolution": CLOTH_N})
    # A real yarn: the light between yarns reads its albedo (the random bakes' send away twice what they get).
    yarn = yarn_tables_from_bake(pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables"
                                 / "paper_2008")
    summary = write_cloth_tables(folder, measurement, goniometer, yarn, cache_key="c1" * 32, code_digest="test")
    detail = {"repeat_mm": 1.0, "mean_coverage": 0.75, "resolution": 8, "weave": {"pattern": "plain"},
              "encoding": "RGB (n + 1)/2, tangent space x = warp; A coverage"}
    texture = np.concatenate([np.full((8, 8, 3), 0.5), np.full((8, 8, 1), 0.75)], axis=-1).astype(np.float32)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "clothlight_weave_detail": json.dumps(detail)},
                      {"RGBA": texture}) as exr:
        exr.write(str(folder / DETAIL_FILE))
    summary["weave_detail"] = {"file": DETAIL_FILE, **detail}
    write_cloth_summary(folder, summary)
    return folder


def test_a_cloth_bake_passes_and_broken_ones_are_refused_naming_the_file(cloth_bake, tmp_path):
    from clothlight.garment.tables import check_cloth_table_folder

    checked = check_cloth_table_folder(cloth_bake)
    assert sorted(checked.tables) == ["back_brdf.exr", "back_specular_visibility.exr", "front_brdf.exr",
                                      "front_specular_visibility.exr", "lobes.exr"]
    broken = {
        "truncated": (lambda f: truncate(f, "front_brdf.exr"), "front_brdf.exr", "truncated"),
        "sides swapped": (lambda f: [shutil.move(f / a, f / b) for a, b in (
            ("front_brdf.exr", "x"), ("back_brdf.exr", "front_brdf.exr"), ("x", "back_brdf.exr"))],
            "front_brdf.exr", "header side 'back'"),
        "visibility for ρ": (lambda f: shutil.copy(f / "front_specular_visibility.exr", f / "front_brdf.exr"),
                             "front_brdf.exr", "header quantity 'specular visibility'"),
        "missing detail": (lambda f: (f / "weave_detail.exr").unlink(), "weave_detail.exr", "missing"),
        "another weave's detail": (lambda f: edit_summary(f, weave_detail={
            **json.loads((f / SUMMARY_FILE).read_text())["weave_detail"], "mean_coverage": 0.5}),
            "weave_detail.exr", "another weave detail"),
        "older yarn tables": (lambda f: edit_summary(f, table_schema="clothlight-table/3"), SUMMARY_FILE,
                              "schema 'clothlight-table/3'.*bake the cloth again"),
        "lobe image of another grid": (lambda f: edit_summary(f, lobe_grid_resolution=8), "lobes.exr",
                                       "exit_resolution 16, where the folder's summary.json says 8"),
    }
    for case, (break_it, name, reason) in broken.items():
        for listed in (True, False):
            folder = copy_of(cloth_bake, tmp_path / f"{case}{listed}")
            if not listed:
                summary = json.loads((folder / SUMMARY_FILE).read_text())
                del summary[FILE_HASHES_KEY]
                (folder / SUMMARY_FILE).write_text(json.dumps(summary))
                check_cloth_table_folder(folder)
            break_it(folder)
            with pytest.raises(TableError, match=reason) as refusal:
                check_cloth_table_folder(folder)
            assert str(folder / name) in str(refusal.value), case


# ---- Apply Material -----------------------------------------------------------------------------


def test_apply_material_refuses_a_truncated_folder_and_builds_nothing(bpy, bakes, cloth_bake, tmp_path):
    from clothlight.blender import registration

    registration.register()
    try:
        bpy.ops.wm.read_homefile(use_empty=True)
        scene = bpy.context.scene
        assert bpy.ops.clothlight.build_sample() == {"FINISHED"}
        sample = bpy.context.active_object
        before = (set(bpy.data.materials.keys()), [slot.material for slot in sample.material_slots])
        yarn = copy_of(bakes["A", True], tmp_path / "yarn")
        truncate(yarn, "brdf.exr")
        scene.clothlight.medium.tables_dir = str(yarn)
        with pytest.raises(RuntimeError, match="brdf.exr: truncated"):
            bpy.ops.clothlight.apply_material()
        cloth = copy_of(cloth_bake, tmp_path / "cloth")
        truncate(cloth, "lobes.exr")
        scene.clothlight.cloth_tables_dir = str(cloth)
        with pytest.raises(RuntimeError, match="lobes.exr: truncated"):
            bpy.ops.clothlight.apply_garment_material()
        assert (set(bpy.data.materials.keys()), [slot.material for slot in sample.material_slots]) == before
    finally:
        registration.unregister()


# ---- fuzz: the reader and the folder check ------------------------------------------------------

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: A change of a file's bytes: truncation, bit flips, or bytes overwritten, at fractions of its length.
EDITS = st.one_of(
    st.tuples(st.just("truncate"), st.floats(0.0, 1.0, exclude_max=True)),
    st.tuples(st.just("flip"), st.lists(st.tuples(st.floats(0.0, 1.0, exclude_max=True), st.integers(0, 7)),
                                        min_size=1, max_size=6)),
    st.tuples(st.just("overwrite"), st.floats(0.0, 1.0, exclude_max=True), st.binary(min_size=1, max_size=12)),
)
#: Where to edit: anywhere, or in the header (the first few hundred bytes), where parsing happens.
WHERE = st.one_of(st.just(1.0), st.just(0.3))


def edited(data: bytes, edit, span: float) -> bytes:
    data = bytearray(data)
    at = lambda fraction: min(int(fraction * span * len(data)), len(data) - 1)  # noqa: E731
    if edit[0] == "truncate":
        return bytes(data[: at(edit[1])])
    if edit[0] == "flip":
        for fraction, bit in edit[1]:
            data[at(fraction)] ^= 1 << bit
        return bytes(data)
    start = at(edit[1])
    return bytes(data[:start] + edit[2] + data[start + len(edit[2]):])


@FUZZ
@given(name=st.sampled_from(["brdf.exr", "lobes.exr", "unscattered.exr"]), edit=EDITS, span=WHERE)
def test_fuzz_the_reader_gives_the_table_or_a_table_error(bakes, name, edit, span):
    original = read_table(bakes["A", True] / name)
    with tempfile.TemporaryDirectory() as scratch:
        path = pathlib.Path(scratch) / name
        path.write_bytes(edited((bakes["A", True] / name).read_bytes(), edit, span))
        try:
            table = read_table(path)
        except TableError as error:
            assert str(path) in str(error)
            return
    np.testing.assert_array_equal(table.pixels, original.pixels)
    assert table.metadata["table"] == original.metadata["table"]


JSON_VALUES = st.one_of(st.none(), st.booleans(), st.integers(-3, 10**12), st.floats(allow_nan=True),
                        st.text(max_size=8), st.lists(st.integers(0, 9), max_size=3))


@st.composite
def header_edits(draw):
    """An edit of one ClothLight header attribute: any text, or the metadata with one entry set."""
    key = draw(st.sampled_from([SCHEMA_KEY, KIND_KEY, HASH_KEY, METADATA_KEY, CACHE_KEY_KEY]))
    if key != METADATA_KEY or draw(st.booleans()):
        return key, draw(st.text(max_size=40)), None
    return key, None, (draw(st.sampled_from(["table", "layout", "cache_key", "host_index", "lobe_shape",
                                             "layout.incidence_resolution", "layout.exit_resolution",
                                             "layout.lobe_count", "layout.attenuation_samples"])),
                       draw(JSON_VALUES))


def with_header_edit(path, edit) -> None:
    key, text, entry = edit
    with OpenEXR.File(str(path), separate_channels=True) as exr:
        header = dict(exr.header())
        channels = {name: np.array(channel.pixels) for name, channel in exr.channels().items()}
    if entry is None:
        header[key] = text
    else:
        metadata = json.loads(header[METADATA_KEY])
        *parents, last = entry[0].split(".")
        node = metadata
        for part in parents:
            node = node[part]
        node[last] = entry[1]
        header[key] = json.dumps(metadata)
    header = {name: value for name, value in header.items() if name not in ("channels", "dataWindow",
                                                                            "displayWindow")}
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))


@FUZZ
@given(name=st.sampled_from(["brdf.exr", "lobes.exr", "unscattered.exr"]), edit=header_edits(),
       listed=st.booleans())
def test_fuzz_header_edits_give_the_same_data_or_a_table_error(bakes, name, edit, listed):
    reference = check_yarn_table_folder(bakes["A", listed])
    with tempfile.TemporaryDirectory() as scratch:
        folder = copy_of(bakes["A", listed], scratch)
        with_header_edit(folder / name, edit)
        try:
            table = read_table(folder / name)
            assert np.array_equal(table.pixels, reference.tables[name].pixels)
        except TableError as error:
            assert str(folder / name) in str(error)
        try:
            checked = check_yarn_table_folder(folder)
        except TableError as error:
            assert str(folder) in str(error)
            return
        assert same_data(checked, reference)


@FUZZ
@given(name=st.sampled_from(sorted(YARN_FOLDER_FILES)), edit=EDITS, span=WHERE, listed=st.booleans())
def test_fuzz_a_damaged_file_gives_the_same_data_or_a_table_error(bakes, name, edit, span, listed):
    reference = check_yarn_table_folder(bakes["A", listed])
    with tempfile.TemporaryDirectory() as scratch:
        folder = copy_of(bakes["A", listed], scratch)
        data = (folder / name).read_bytes()
        damaged = edited(data, edit, span)
        (folder / name).write_bytes(damaged)
        try:
            checked = check_yarn_table_folder(folder)
        except TableError as error:
            assert str(folder) in str(error)
            return
    assert same_data(checked, reference)
    if listed and name != SUMMARY_FILE:
        assert damaged == data  # every listed file's bytes are checked


@FUZZ
@given(mixed=st.sets(st.sampled_from(sorted(YARN_FOLDER_FILES))), listed=st.booleans())
def test_fuzz_files_mixed_from_two_bakes_are_refused(bakes, mixed, listed):
    """A folder holding some files of bake B among bake A's passes only as all of A or all of B."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = copy_of(bakes["A", listed], scratch)
        for name in mixed:
            shutil.copy(bakes["B", listed] / name, folder / name)
        whole = {frozenset(): "A", frozenset(YARN_FOLDER_FILES): "B"}.get(frozenset(mixed))
        if whole is None:
            with pytest.raises(TableError, match="another bake|not those its summary.json lists"):
                check_yarn_table_folder(folder)
        else:
            assert same_data(check_yarn_table_folder(folder), check_yarn_table_folder(bakes[whole, listed]))


# ---- output folders written as a whole ----------------------------------------------------------


def copier(source):
    def write(staging):
        for name in YARN_FOLDER_FILES:
            shutil.copy2(source / name, staging / name)
        check_yarn_table_folder(staging)

    return write


def leftovers(parent) -> list:
    return sorted(entry.name for entry in pathlib.Path(parent).iterdir() if entry.name.startswith("."))


def key_of(folder) -> str:
    return check_yarn_table_folder(folder).summary["cache_key"]


def test_replace_folder_swaps_the_new_folder_in_for_an_earlier_bakes(bakes, tmp_path):
    out = copy_of(bakes["A", True], tmp_path)
    assert replace_folder(out, copier(bakes["B", True]), YARN_FOLDER_FILES) == out.resolve()
    assert key_of(out) == "02" * 32 and leftovers(tmp_path) == []
    assert replace_folder(tmp_path / "new" / "out", copier(bakes["A", True]), YARN_FOLDER_FILES).is_dir()


def test_a_failure_before_the_swap_leaves_the_earlier_folder_whole(bakes, tmp_path, monkeypatch):
    out = copy_of(bakes["A", True], tmp_path)

    def half_then_fail(staging):
        shutil.copy2(bakes["B", True] / "brdf.exr", staging / "brdf.exr")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        replace_folder(out, half_then_fail, YARN_FOLDER_FILES)
    assert key_of(out) == "01" * 32 and leftovers(tmp_path) == []
    monkeypatch.setattr(table_folder, "_exchange", lambda first, second: (_ for _ in ()).throw(OSError("EIO")))
    with pytest.raises(OSError, match="EIO"):
        replace_folder(out, copier(bakes["B", True]), YARN_FOLDER_FILES)
    assert key_of(out) == "01" * 32 and leftovers(tmp_path) == []


def test_without_an_atomic_swap_the_folder_is_replaced_by_two_renames(bakes, tmp_path, monkeypatch):
    out = copy_of(bakes["A", True], tmp_path)
    monkeypatch.setattr(table_folder, "_exchange", lambda first, second: False)
    replace_folder(out, copier(bakes["B", True]), YARN_FOLDER_FILES)
    assert key_of(out) == "02" * 32 and leftovers(tmp_path) == []
    renames = []
    real_rename = os.rename

    def second_rename_fails(source, target):
        renames.append(target)
        if len(renames) == 2:
            raise OSError("EIO")
        return real_rename(source, target)

    monkeypatch.setattr(table_folder.os, "rename", second_rename_fails)
    with pytest.raises(OSError, match="EIO"):
        replace_folder(out, copier(bakes["A", True]), YARN_FOLDER_FILES)
    monkeypatch.undo()
    assert key_of(out) == "02" * 32 and leftovers(tmp_path) == []  # the earlier folder renamed back


def test_the_next_run_clears_the_staging_folders_of_killed_runs_and_keeps_those_of_live_ones(bakes, tmp_path):
    out = copy_of(bakes["A", True], tmp_path)
    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                              text=True, check=True)
    dead, alive = int(finished.stdout), os.getppid()  # a process that has ended, and one that runs
    killed = tmp_path / f".{out.name}.{dead}.0123abcd.partial"
    killed_aside = tmp_path / f".{out.name}.{dead}.4567ef01.previous.partial"
    running = tmp_path / f".{out.name}.{alive}.89abcdef.partial"
    for staging in (killed, killed_aside, running):
        staging.mkdir()
        (staging / "brdf.exr").write_bytes(b"half written")
    replace_folder(out, copier(bakes["B", True]), YARN_FOLDER_FILES)
    assert key_of(out) == "02" * 32
    assert not killed.exists() and not killed_aside.exists()
    assert running.is_dir()  # another run into the same place, still writing


def test_out_must_be_new_empty_or_an_earlier_bakes_folder(bakes, tmp_path):
    (tmp_path / "a file").write_text("x")
    with pytest.raises(ParameterError, match="--out.*this is a file"):
        check_output_folder(tmp_path / "a file", YARN_FOLDER_FILES)
    documents = copy_of(bakes["A", True], tmp_path / "documents")
    (documents / "notes.txt").write_text("mine")
    with pytest.raises(ParameterError, match="--out.*notes.txt"):
        replace_folder(documents, copier(bakes["B", True]), YARN_FOLDER_FILES)
    assert (documents / "notes.txt").read_text() == "mine" and key_of(documents) == "01" * 32
    (tmp_path / "empty").mkdir()
    assert check_output_folder(tmp_path / "empty", YARN_FOLDER_FILES) == (tmp_path / "empty").resolve()
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(ParameterError, match="not writable"):
            check_output_folder(locked / "out", YARN_FOLDER_FILES)


#: Run in a child process: the command line (``sys.argv[2:]``, ``python -m precompute …``) or a
#: replace_folder copying one folder onto another, killed with SIGKILL as it starts its
#: ``sys.argv[1]``-th step that changes the file system (a copy, a rename, the swap, a removal).
KILLED_AT_A_STEP = """
import os, shutil, signal, sys
from precompute.tables import folder as table_folder
count, kill_at = [0], int(sys.argv[1])
def step(function):
    def run(*args, **kwargs):
        count[0] += 1
        if count[0] == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)
        return function(*args, **kwargs)
    return run
shutil.copy2, shutil.rmtree, os.rename = step(shutil.copy2), step(shutil.rmtree), step(os.rename)
table_folder._exchange = step(table_folder._exchange)
if sys.argv[2] == "replace":
    import pathlib
    source = pathlib.Path(sys.argv[3])
    def write(staging):
        for name in table_folder.YARN_FOLDER_FILES:
            shutil.copy2(source / name, staging / name)
    table_folder.replace_folder(sys.argv[4], write, table_folder.YARN_FOLDER_FILES)
else:
    from precompute.__main__ import main
    sys.exit(main(sys.argv[2:]))
"""


def kill_at_every_step(arguments, out, earlier, earlier_key, new_key) -> list:
    """Kill the child at each of its steps in turn, out holding the earlier bake's folder each time,
    until it runs to the end; after each, out holds one of the two bakes, whole.  Returns the cache
    key found after each kill."""
    found = []
    for step in range(1, 100):
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(earlier, out)
        run = subprocess.run([sys.executable, "-c", KILLED_AT_A_STEP, str(step), *arguments], cwd=REPO,
                             capture_output=True, text=True)
        key = key_of(out)  # a complete folder of one bake, or a TableError
        if run.returncode == 0:
            assert key == new_key
            return found
        assert run.returncode == -signal.SIGKILL, run.stderr[-2000:]
        assert key in (earlier_key, new_key)
        found.append(key)
    raise AssertionError("the child never ran to the end")


def test_a_folder_replaced_by_a_process_killed_at_any_step_is_one_bakes_whole(bakes, tmp_path):
    out = tmp_path / "out"
    found = kill_at_every_step(["replace", str(bakes["B", True]), str(out)], out, bakes["A", True],
                               "01" * 32, "02" * 32)
    # killed before the swap the earlier folder is kept, after it the new one: both were reached
    swapped = found.index("02" * 32)
    assert 0 < swapped and found == ["01" * 32] * swapped + ["02" * 32] * (len(found) - swapped)


TINY_CLI = [arg for key, value in PREBAKED_TRANSPORT.items() if key != "paths_per_cell"
            for arg in ("--set", f"transport.{key}={value}")] + ["--paths", str(PREBAKED_TRANSPORT["paths_per_cell"]),
                                                                 "--threads", "1"]


@pytest.mark.slow
def test_bake_out_killed_at_any_step_leaves_one_bakes_whole_folder(tmp_path):
    """``python -m precompute bake --out DIR`` over an earlier bake (tiny bakes, both in the cache):
    the real command killed at each step of its export."""
    cache, earlier = tmp_path / "cache", tmp_path / "earlier"

    def bake(seed, out):
        run = subprocess.run([sys.executable, "-m", "precompute", "bake", *TINY_CLI, "--seed", str(seed),
                              "--cache-dir", str(cache), "--out", str(out), "--json"], cwd=REPO,
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr[-3000:]
        return json.loads(run.stdout)["cache_key"]

    earlier_key = bake(1, earlier)
    new_key = bake(2, tmp_path / "new")
    assert check_yarn_table_folder(earlier).summary[FILE_HASHES_KEY]  # a real bake lists its files
    out = tmp_path / "out"
    found = kill_at_every_step(["bake", *TINY_CLI, "--seed", "2", "--cache-dir", str(cache), "--out", str(out)],
                               out, earlier, earlier_key, new_key)
    assert found[0] == earlier_key and found[-1] == new_key



#: A validation-like folder: files and sub-folders (names ending in "/") a new run may replace.
RUN_NAMES = ("results.json", "report.md", "renders/", "swatches/")
#: Entries of an existing folder: name → a folder (True) or a file (False).
ENTRIES = st.dictionaries(st.sampled_from(["results.json", "report.md", "renders", "swatches", "notes.txt"]),
                          st.booleans(), max_size=5)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(entries=ENTRIES, fail_after=st.one_of(st.none(), st.integers(0, 2)))
def test_a_staged_folder_replaces_only_an_earlier_runs_folder_and_only_as_a_whole(tmp_path, entries, fail_after):
    """Whatever the folder holds and wherever the writing stops: a folder holding anything but an
    earlier run's entries (a file where a folder is named, too) is refused before any work; else
    ``out`` ends as the earlier folder, untouched, or the complete new one, and nothing is left beside it."""
    root = pathlib.Path(tempfile.mkdtemp(dir=tmp_path))
    out = root / "out"
    out.mkdir()
    for name, is_folder in entries.items():
        (out / name).mkdir() if is_folder else (out / name).write_text("earlier")
    earlier = sorted(p.relative_to(out) for p in out.rglob("*"))
    foreign = {name for name, is_folder in entries.items() if name + "/" * is_folder not in RUN_NAMES}
    written = ["renders/a.exr", "renders/b.exr", "results.json"]

    def write_run():
        with staged_folder(out, RUN_NAMES, "out_dir", job="run") as staging:
            for done, name in enumerate(written):
                if done == fail_after:
                    raise KeyboardInterrupt
                (staging / name).parent.mkdir(exist_ok=True)
                (staging / name).write_text("new")

    if foreign:
        with pytest.raises(ParameterError, match="out_dir = .*an earlier run only"):
            write_run()
    elif fail_after is not None:
        with pytest.raises(KeyboardInterrupt):
            write_run()
    else:
        write_run()
    after = sorted(p.relative_to(out) for p in out.rglob("*"))
    complete = foreign == set() and fail_after is None
    assert after == (sorted(map(pathlib.Path, ["renders", *written])) if complete else earlier)
    assert [p.name for p in root.iterdir()] == ["out"]
