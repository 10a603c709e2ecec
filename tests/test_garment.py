"""The garment material and the cloth gonioreflectometer in Blender.

The garment shader reads cloth tables exactly as the table spec says, per side and along the UV
tangent, with the open weave transparent; the gonioreflectometer's cloth BSDF of the shipped red
cotton has the weave's symmetries, conserves energy, agrees with the in-plane validation rig at
normal incidence and view, and is cached.
"""

import json
import pathlib

import numpy as np
import OpenEXR
import pytest

from clothlight.garment.goniometry import side_to_world
from clothlight.garment.tables import (
    BRDF_FILES,
    GARMENT_LOBES,
    LOBE_FILE,
    LOBE_TILES,
    SPECULAR_VISIBILITY_FILES,
    SUMMARY_FILE,
    SUMMARY_SCHEMA,
    garment_lobe_responses,
    lobe_image,
    projected_view_grid,
)
from precompute.tables.closure_fit import LobeShape
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas, interpolate_rho
from precompute.tables.exr import TableError
from tests.helpers import add_sun_and_camera, cook_torrance_between, empty_render_scene, slow_fixture, unit, write_exr

bpy = pytest.importorskip("bpy")

from clothlight.blender.garment.bake import bake_cloth  # noqa: E402
from clothlight.blender.garment.material import (  # noqa: E402
    ClothTableFiles,
    apply_garment_material,
    build_garment_material,
    cloth_tables_from_bake,
)
from clothlight.blender.garment.measure import GoniometerSettings  # noqa: E402
from clothlight.blender.materials import GENERAL_MODE, SUN_MODE, sync_sun  # noqa: E402
from clothlight.blender.measurement_render import render_to_array  # noqa: E402
from clothlight.validation.framing import ParameterError  # noqa: E402
from clothlight.blender.validation.rig import RigSettings  # noqa: E402
from clothlight.blender.validation.run import ValidationRun, run_validation  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.render]

N_I, N_O, N_LOBES = 5, 6, 8
SUN_IRRADIANCE = 2.0
COVERAGE = {"front": 0.8, "back": 0.6}
SPECULAR = {"weight": 0.7, "slope": 0.5, "ior": 1.45}
YARN_BAKE = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"


def analytic_rho(wi, wo, side):
    wi, wo = np.broadcast_arrays(wi, wo)
    scale = 1.0 if side == "front" else 0.5
    r = scale * (0.30 + 0.10 * wi[..., 0] + 0.08 * wi[..., 2] + 0.05 * wo[..., 0] * wo[..., 2])
    g = scale * (0.10 + 0.05 * wi[..., 1] ** 2 + 0.04 * wo[..., 2])
    b = np.full_like(r, 0.02 if side == "front" else 0.07)
    return np.stack([r, g, b], axis=-1)


def analytic_specular_visibility(wi, wo, side):
    wi, wo = np.broadcast_arrays(wi, wo)
    v = (0.6 + 0.1 * wo[..., 0] - 0.1 * wi[..., 1]) if side == "front" else 0.3 + 0.1 * wi[..., 2]
    return np.repeat(v[..., None], 3, axis=-1)


def lobe_weights(view, side):
    """Weights (len(LOBE_TILES), 3) at a view (side frame): the diffuse one linear in (ω_x, ω_y)
    (bilinear lookups reproduce it exactly, so the view mapping is checked), the others constant."""
    view = np.asarray(view, float)
    sign = 1.0 if side == "front" else -1.0
    diffuse = np.array([0.5 + 0.2 * view[..., 0], 0.3 + sign * 0.15 * view[..., 1], 0.1 + 0.05 * view[..., 0]])
    weights = np.zeros(view.shape[:-1] + (len(LOBE_TILES), 3))
    constant = {"uniform": [0.1, 0.05, 0.2], "retroreflection": [0.05, 0.1, 0.02],
                "translucent": [0.4, 0.0, 0.1] if side == "front" else [0.1, 0.2, 0.0],
                "fibre_transmission": [0.3, 0.2, 0.0], "gloss": np.full(3, 0.2),  # grey: the yarns' specular term
                "open_weave": np.full(3, 1.0 - COVERAGE[side])}
    weights[..., LOBE_TILES.index("diffuse"), :] = np.moveaxis(diffuse, 0, -1)
    for tile, value in constant.items():
        weights[..., LOBE_TILES.index(tile), :] = value
    return weights


@pytest.fixture(scope="module")
def synthetic_cloth(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cloth")
    wi = AngularGrid("sphere", N_I).cell_centers()
    wo = AngularGrid("hemisphere", N_O).cell_centers()
    atlases, visibility = {}, {}
    for side in ("front", "back"):
        atlases[side] = brdf_atlas(analytic_rho(wi[:, None, :], wo[None, :, :], side))
        write_exr(folder / BRDF_FILES[side], atlases[side])
        visibility[side] = brdf_atlas(analytic_specular_visibility(wi[:, None, :], wo[None, :, :], side))
        write_exr(folder / SPECULAR_VISIBILITY_FILES[side], visibility[side])
    views = projected_view_grid(N_LOBES)
    write_exr(folder / LOBE_FILE, lobe_image({side: lobe_weights(views, side) for side in ("front", "back")}))
    tables = ClothTableFiles({side: folder / name for side, name in BRDF_FILES.items()},
                             {side: folder / name for side, name in SPECULAR_VISIBILITY_FILES.items()},
                             folder / LOBE_FILE, N_I, N_O, N_LOBES, LobeShape().to_dict(), SPECULAR)
    return tables, atlases, visibility


def garment_scene(tables, mode, toward_camera, toward_sun, warp_along_y=False, weave_repeats_per_uv=None,
                  transmission=True):
    scene = empty_render_scene(resolution=8, samples=1 if mode == SUN_MODE else 16, bounces=0)
    scene.cycles.shading_system = mode == SUN_MODE  # the general mode is plain nodes: no OSL
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    plane = bpy.context.active_object
    if warp_along_y:  # u along +y: the warp turns with it
        uv = plane.data.uv_layers.active
        for loop in plane.data.loops:
            co = plane.data.vertices[loop.vertex_index].co
            uv.data[loop.index].uv = (co.y / 20.0 + 0.5, -co.x / 20.0 + 0.5)
    material = apply_garment_material(plane, tables, mode=mode, weave_repeats_per_uv=weave_repeats_per_uv,
                                      transmission=transmission)
    sun = add_sun_and_camera(scene, toward_sun, toward_camera, SUN_IRRADIANCE)
    if mode == SUN_MODE:
        sync_sun(material, sun)
    return scene


@pytest.mark.parametrize("toward_camera, toward_sun, side", [
    (unit([0.3, 0.2, 0.9]), unit([-0.4, 0.3, 0.7]), "front"),       # reflection
    (unit([0.3, 0.2, 0.9]), unit([0.2, -0.5, -0.6]), "front"),      # transmission, seen from the front
    (unit([-0.5, 0.4, -0.7]), unit([0.1, 0.3, -0.9]), "back"),      # the back side's own reflection
])
@pytest.mark.parametrize("warp_along_y", [False, True], ids=["warp-x", "warp-y"])
def test_sun_mode_reads_each_side_in_its_frame(tmp_path, synthetic_cloth, toward_camera, toward_sun, side,
                                               warp_along_y):
    """ρ = the side's table + the specular term about the side's normal times its visibility table."""
    tables, atlases, visibility = synthetic_cloth
    scene = garment_scene(tables, SUN_MODE, toward_camera, toward_sun, warp_along_y)
    pixels = render_to_array(scene, tmp_path / "patch.exr").reshape(-1, 4)
    # World → cloth frame (x = warp), then → the side's frame.
    to_cloth = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) if warp_along_y else np.eye(3)
    wi = side_to_world(to_cloth @ toward_sun, side)
    wo = side_to_world(to_cloth @ toward_camera, side)
    specular = SPECULAR["weight"] * cook_torrance_between(wi, wo, SPECULAR["slope"], SPECULAR["ior"]) * max(wi[2], 0.0)
    assert (specular > 0.0) == (wi[2] > 0.0)  # the reflection cases check it
    expected = (interpolate_rho(atlases[side], N_I, wi, wo)
                + specular * interpolate_rho(visibility[side], N_I, wi, wo)) * SUN_IRRADIANCE
    np.testing.assert_allclose(pixels[:, :3].mean(axis=0), expected, rtol=3e-4, atol=1e-6)
    np.testing.assert_allclose(pixels[:, 3], COVERAGE[side], atol=1e-4)


@pytest.mark.parametrize("toward_camera, toward_sun, side", [
    (unit([0.2, 0.3, 0.9]), unit([0.3, -0.2, 0.9]), "front"),     # reflection
    (unit([0.5, -0.3, 0.6]), unit([-0.3, 0.4, -0.8]), "front"),   # back-lit: translucent, fibre transmission
    (unit([-0.4, 0.2, -0.8]), unit([0.1, -0.5, -0.7]), "back"),   # the back side, in its own frame
])
@pytest.mark.parametrize("warp_along_y", [False, True], ids=["warp-x", "warp-y"])
def test_general_mode_renders_the_lobe_mixture_and_the_open_weave(tmp_path, synthetic_cloth, toward_camera,
                                                                  toward_sun, side, warp_along_y):
    tables, *_ = synthetic_cloth
    scene = garment_scene(tables, GENERAL_MODE, toward_camera, toward_sun, warp_along_y)
    pixels = render_to_array(scene, tmp_path / "patch.exr").reshape(-1, 4)
    to_cloth = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) if warp_along_y else np.eye(3)
    view = side_to_world(to_cloth @ toward_camera, side)
    light = side_to_world(to_cloth @ toward_sun, side)
    weights = lobe_weights(view, side)
    expected = (SUN_IRRADIANCE * garment_lobe_responses(view, light, LobeShape(), SPECULAR["ior"])
                @ weights[: len(GARMENT_LOBES)])
    assert expected[0] > 1e-3
    np.testing.assert_allclose(pixels[:, :3].mean(axis=0), expected, rtol=0.02, atol=2e-4)
    np.testing.assert_allclose(pixels[:, 3].mean(), COVERAGE[side], atol=0.02)  # sampled: 16 spp


def test_without_transmission_the_garment_reflects_the_same_and_passes_no_light(tmp_path, synthetic_cloth):
    """transmission=False: lit from the viewer's side the same radiance as the full material, lit
    from behind none (the open weave's see-through stays)."""
    tables, *_ = synthetic_cloth
    toward_camera = unit([0.3, 0.2, 0.9])
    for toward_sun, passes_light in ((unit([-0.4, 0.3, 0.7]), False), (unit([0.2, -0.5, -0.6]), True)):
        means = {}
        for transmission in (True, False):
            scene = garment_scene(tables, GENERAL_MODE, toward_camera, toward_sun, transmission=transmission)
            means[transmission] = render_to_array(scene, tmp_path / "patch.exr").reshape(-1, 4).mean(axis=0)
        assert means[True][0] > 1e-3
        np.testing.assert_allclose(means[False][3], means[True][3], atol=0.02)  # alpha: the open weave
        if passes_light:
            np.testing.assert_array_equal(means[False][:3], 0.0)
        else:
            np.testing.assert_allclose(means[False][:3], means[True][:3], rtol=0.02, atol=2e-4)


def test_a_shadow_ray_reads_only_the_open_weave_and_sees_the_same_cloth(tmp_path, synthetic_cloth):
    """Shadow rays meet a Mix Shader on Is Shadow Ray whose shadow side is the open weave alone, so
    the other lobes' lookups sit behind it; the picture is the one without the shortcut. A floor
    under the cloth, seen through its gaps from above and lit through them: what the floor adds is
    the front's open share along the view times the back's along the sun (a shadow ray from below
    meets the back face) times the floor's direct light."""
    tables, *_ = synthetic_cloth
    toward_camera, toward_sun = np.array([0.0, 0.0, 1.0]), unit([0.3, -0.2, 0.9])
    scene = garment_scene(tables, GENERAL_MODE, toward_camera, toward_sun)
    scene.cycles.samples = 64
    cloth = next(obj for obj in scene.objects if obj.type == "MESH")
    nodes, links = cloth.active_material.node_tree.nodes, cloth.active_material.node_tree.links
    gates = [node for node in nodes if node.type == "MIX_SHADER" and node.inputs["Fac"].is_linked
             and node.inputs["Fac"].links[0].from_socket.name == "Is Shadow Ray"]
    assert len(gates) == 1
    gate = gates[0]
    passes = gate.inputs[2].links[0].from_node
    assert passes.type == "BSDF_TRANSPARENT"

    def upstream(socket):
        seen, todo = set(), [link.from_node for link in socket.links]
        while todo:
            node = todo.pop()
            if node.name not in seen:
                seen.add(node.name)
                todo += [link.from_node for inp in node.inputs for link in inp.links]
        return {nodes[name] for name in seen}

    lookups = {node for node in nodes if node.type == "TEX_IMAGE"}
    assert len(lookups & upstream(gate.inputs[2])) == 1 and lookups <= upstream(gate.inputs[1])

    bpy.ops.mesh.primitive_plane_add(size=20.0, location=(0.0, 0.0, -1.0))
    floor = bpy.context.active_object
    white = bpy.data.materials.new("white")
    white.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    white.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 1.0
    white.node_tree.nodes["Principled BSDF"].inputs["Specular IOR Level"].default_value = 0.0
    floor.data.materials.append(white)
    with_floor = render_to_array(scene, tmp_path / "shortcut.exr")[..., :3]
    surface = gate.inputs[1].links[0].from_socket
    output = next(node for node in nodes if node.type == "OUTPUT_MATERIAL")
    links.new(surface, output.inputs["Surface"])
    np.testing.assert_allclose(render_to_array(scene, tmp_path / "no shortcut.exr")[..., :3], with_floor,
                               rtol=1e-6, atol=1e-7)
    floor.hide_render = True
    without_floor = render_to_array(scene, tmp_path / "no floor.exr")[..., :3]
    open_share = {side: 1.0 - COVERAGE[side] for side in ("front", "back")}
    floor_lit = SUN_IRRADIANCE * toward_sun[2] / np.pi
    np.testing.assert_allclose((with_floor - without_floor).mean(axis=(0, 1)),
                               open_share["front"] * open_share["back"] * floor_lit, rtol=0.05)


def test_weave_detail_shows_the_yarns_and_keeps_the_mean(tmp_path, synthetic_cloth):
    """A detail texture of stripes (coverage 1 and 0.6, flat normals; its mean the bake's 0.8 at
    normal view, as a real bake's is) tiled four times across a view straight down: pixels differ
    stripe by stripe, the image's mean radiance and alpha are those of the material without detail."""
    import dataclasses

    tables, *_ = synthetic_cloth
    coverage = np.where(np.arange(32) < 16, 1.0, 0.6)[None, :].repeat(32, axis=0)
    texture = np.concatenate([np.full((32, 32, 3), (0.5, 0.5, 1.0)), coverage[..., None]], axis=-1)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, {"RGBA": texture.astype(np.float32)}) as exr:
        exr.write(str(tmp_path / "detail.exr"))
    detailed = dataclasses.replace(tables, detail_path=tmp_path / "detail.exr", detail_mean_coverage=0.8)
    toward_camera, toward_sun = np.array([0.0, 0.0, 1.0]), unit([0.3, -0.2, 0.9])
    means = []
    for cloth, repeats in ((tables, None), (detailed, 80.0)):
        scene = garment_scene(cloth, GENERAL_MODE, toward_camera, toward_sun, weave_repeats_per_uv=repeats)
        scene.render.resolution_x = scene.render.resolution_y = 64
        pixels = render_to_array(scene, tmp_path / "patch.exr").reshape(64, 64, 4)
        means.append(pixels.reshape(-1, 4).mean(axis=0))
        spread = pixels[..., 0].mean(axis=0)  # per image column: stripes run along the image's columns
        assert (np.ptp(spread) > 0.5 * spread.mean()) == (repeats is not None)
    np.testing.assert_allclose(means[1], means[0], rtol=0.03)
    with pytest.raises(ValueError, match="weave detail"):
        build_garment_material(tables, mode=GENERAL_MODE, weave_repeats_per_uv=10.0)


def test_garment_material_refuses_meshes_without_uvs_and_incomplete_bakes(tmp_path, synthetic_cloth):
    tables, *_ = synthetic_cloth
    bpy.ops.wm.read_homefile(use_empty=True)
    mesh = bpy.data.meshes.new("no uv")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    obj = bpy.data.objects.new("no uv", mesh)
    with pytest.raises(ValueError, match="UV"):
        apply_garment_material(obj, tables)
    with pytest.raises(TableError, match="no summary.json"):
        cloth_tables_from_bake(tmp_path)
    older = tmp_path / "older"
    older.mkdir()
    (older / SUMMARY_FILE).write_text(json.dumps({"schema": SUMMARY_SCHEMA, "table_schema": "clothlight-table/3",
                                                   "lobe_tiles": list(LOBE_TILES)}))
    with pytest.raises(ValueError, match="schema 'clothlight-table/3'.*bake the cloth again"):
        cloth_tables_from_bake(older)  # measured from yarn tables whose ρ held the unscattered light
    with pytest.raises(ParameterError, match="cloth_dir"):
        ValidationRun(None, tmp_path, materials=("garment",), cloth_dir=tmp_path)
    with pytest.raises(ValueError, match="mode"):
        build_garment_material(tables, mode="MOON")


@pytest.fixture(scope="module")
@slow_fixture
def red_cotton_cloth(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    settings = GoniometerSettings(incidence_resolution=3, exit_resolution=3, pixels_per_patch=10, samples=2)
    # The render-based measurement, the response's check (tests/test_garment_response_render.py)
    folder, measured = bake_cloth(YARN_BAKE, settings, cache_dir=cache, method="render")
    assert measured
    return folder, settings, cache


def test_cloth_bake_is_cached_and_self_describing(tmp_path, red_cotton_cloth):
    from precompute.tables.exr import read_table

    folder, settings, cache = red_cotton_cloth
    again, measured = bake_cloth(YARN_BAKE, settings, cache_dir=cache, method="render")
    assert again == folder and not measured
    # A yarn bake whose lobes were refitted (another cache key, the same ρ) measures nothing again.
    import shutil

    from precompute.tables.folder import FILE_HASHES_KEY, file_hashes
    from precompute.tables.exr import write_table

    refitted = tmp_path / "refitted"
    shutil.copytree(YARN_BAKE, refitted)
    for path in refitted.glob("*.exr"):  # every table of the folder is of the one bake
        table = read_table(path)
        write_table(path, table.pixels, {**table.metadata, "cache_key": "0" * 64})
    summary = json.loads((refitted / "summary.json").read_text())
    summary["cache_key"] = "0" * 64
    if FILE_HASHES_KEY in summary:
        summary[FILE_HASHES_KEY] = file_hashes(refitted, summary[FILE_HASHES_KEY])
    (refitted / "summary.json").write_text(json.dumps(summary))
    assert bake_cloth(refitted, settings, cache_dir=cache, method="render")[1] is False
    tables = cloth_tables_from_bake(folder)
    for side, path in tables.brdf_paths.items():
        table = read_table(path, "brdf")
        assert table.metadata["side"] == side and table.metadata["goniometer"]["exit_resolution"] == 3
    lobes = read_table(tables.lobe_path, "cloth_lobes")
    assert lobes.metadata["tiles"] == list(LOBE_TILES)
    assert lobes.pixels.shape == (2 * tables.lobe_resolution, len(LOBE_TILES) * tables.lobe_resolution, 3)


def test_weave_detail_tiles_and_covers_what_the_gonioreflectometer_measured(red_cotton_cloth):
    """The detail texture (one repeat seen straight down) wraps around without a seam, and its mean
    coverage is the cloth's coverage at normal view measured by the gonioreflectometer's regions:
    two framings of the same weave."""
    folder, _, _ = red_cotton_cloth
    summary = json.loads((folder / "summary.json").read_text())
    with OpenEXR.File(str(folder / summary["weave_detail"]["file"])) as exr:
        texture = np.array(exr.channels()["RGBA"].pixels, dtype=float)
    coverage = texture[..., 3]
    assert summary["weave_detail"]["mean_coverage"] == pytest.approx(coverage.mean())
    assert coverage.mean() == pytest.approx(summary["coverage_normal"]["front"], abs=0.02)
    for axis in (0, 1):
        neighbours = np.abs(np.diff(coverage, axis=axis)).mean()
        seam = np.abs(np.take(coverage, 0, axis) - np.take(coverage, -1, axis)).mean()
        assert seam <= 2.0 * neighbours + 1e-3
    normals = 2.0 * texture[..., :3] - 1.0
    assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-3) and normals[..., 2].min() > -1e-3


def test_cloth_bsdf_has_the_plain_weaves_mirror_symmetry(red_cotton_cloth):
    """A plain weave of round yarns is its own mirror image across x (and y): ρ at mirrored
    incidence and exit cells must agree, within the measurement's noise.  That noise is heavy-
    tailed (light grazing through the gaps reaches a few pixels), so the check is on the whole
    table: the RMS of the mirror differences against the RMS of ρ, and the median cell."""
    from precompute.tables.layout import rho_from_brdf_atlas
    from precompute.tables.exr import read_table

    folder, settings, _ = red_cotton_cloth
    tables = cloth_tables_from_bake(folder)
    incidence = AngularGrid("sphere", 3).cell_centers()
    exits = AngularGrid("hemisphere", 3).cell_centers()
    for side in ("front", "back"):
        rho = rho_from_brdf_atlas(read_table(tables.brdf_paths[side]).pixels, 3)[..., 0]
        for mirror in (np.array([-1.0, 1.0, 1.0]), np.array([1.0, -1.0, 1.0])):
            i_mirror = AngularGrid("sphere", 3).cell_of(incidence * mirror)
            o_mirror = AngularGrid("hemisphere", 3).cell_of(exits * mirror)
            mirrored = rho[i_mirror][:, o_mirror]
            assert np.sqrt(np.mean((mirrored - rho) ** 2)) < 0.1 * np.sqrt(np.mean(rho**2))
            assert np.median(np.abs(mirrored - rho) / rho) < 0.05


def test_cloth_bsdf_conserves_energy(red_cotton_cloth):
    folder, _, _ = red_cotton_cloth
    summary = json.loads((folder / "summary.json").read_text())
    total = np.array(summary["energy"]["per_incidence_total_rgb"])
    open_weave = np.array(summary["energy"]["per_incidence_open"])
    assert np.all(total <= 1.0) and summary["energy"]["max_total"] <= 1.0
    # Something is reflected or transmitted, and the open weave passes part of the light.
    assert np.all(total[:, 0] > open_weave) and np.all((open_weave > 0.0) & (open_weave < 1.0))


def test_cloth_bsdf_agrees_with_the_in_plane_rig_at_normal_incidence_and_view(tmp_path, red_cotton_cloth):
    """Two framings of the same measurement: the gonioreflectometer's regions at (normal, normal)
    (a cell centre of both odd grids) and the validation rig's in-plane sweep at θi = θv = 0."""
    folder, _, _ = red_cotton_cloth
    results = run_validation(None, tmp_path, materials=("yarn", "garment", "garment_general"), tables_dir=YARN_BAKE,
                             cloth_dir=folder,
                             settings=RigSettings(incidences_deg=(0.0,), views_deg=(0.0,), resolution=48, samples=4),
                             swatches=False)
    yarn = np.array(results["materials"]["yarn"]["views"][0]["brdf_rgb"])
    garment = np.array(results["materials"]["garment"]["views"][0]["brdf_rgb"])
    # The rig's yarn sample has no light between yarns; the cloth tables add it (and say how much).
    between = np.array(json.loads((folder / "summary.json").read_text())["light_between_yarns"][
        "normal_incidence_and_view_rho_rgb"])
    assert 0.0 < between[0] < 0.5 * garment[0]
    np.testing.assert_allclose(garment[0] - between[0], yarn[0], rtol=0.05)
    assert results["garment_vs_yarn"]["views_compared"] == 1
    # The general mode against the cloth BSDF it stands for (the closure mixture's own error).
    general = np.array(results["materials"]["garment_general"]["views"][0]["brdf_rgb"])
    mixture = results["garment_general_vs_garment"]
    assert mixture["views_compared"] == 1
    np.testing.assert_allclose(mixture["R"]["relative_rms"], abs(general[0] / garment[0] - 1.0), rtol=1e-6)


def test_bake_command_copies_a_cached_bake_and_names_bad_input(tmp_path, red_cotton_cloth, capsys):
    from clothlight.garment.__main__ import main

    folder, settings, cache = red_cotton_cloth
    common = ["--exit-resolution", "3", "--incidence-resolution", "3", "--pixels-per-patch",
              str(settings.pixels_per_patch), "--samples", str(settings.samples), "--cache-dir", str(cache)]
    # The fixture measured by rendering: the command finds that measurement and its tables cached.
    assert main(["bake", "--tables", str(YARN_BAKE), "--out", str(tmp_path / "cloth"), "--method", "render",
                 *common]) == 0
    assert "from the cache" in capsys.readouterr().out
    assert sorted(p.name for p in (tmp_path / "cloth").iterdir()) == sorted(
        p.name for p in folder.iterdir() if p.name != "entry.json")
    assert cloth_tables_from_bake(tmp_path / "cloth").detail_path is not None
    assert main(["bake", "--tables", str(tmp_path / "nothing"), "--out", str(tmp_path / "x")]) == 2
    assert main(["bake", "--tables", str(YARN_BAKE), "--out", str(tmp_path / "x"), "--incidence-resolution", "8"]) == 2
    assert "incidence_resolution" in capsys.readouterr().err


def test_specular_part_is_the_cook_torrance_term_times_its_visibility(red_cotton_cloth):
    """The gonioreflectometer separates the yarns' specular term: at every cell centre it is the
    Cook–Torrance term about the cloth normal (the same at every point of the cloth) times the
    fraction of the patch where it shines, which is part of what yarn covers; on either side, in
    that side's frame (its normal toward its viewers)."""
    from clothlight.blender.garment.bake import load_measurement
    from clothlight.garment.tables import SPECULAR_KEYS

    folder, settings, cache = red_cotton_cloth
    (path,) = pathlib.Path(cache).glob("cloth_measurement/*/measurement.npz")
    measured = load_measurement(path)
    summary = json.loads((folder / "summary.json").read_text())
    assert set(summary["specular"]) == set(SPECULAR_KEYS)
    weight, slope, ior = (summary["specular"][key] for key in ("weight", "slope", "ior"))
    incidence = AngularGrid("sphere", settings.incidence_resolution).cell_centers()
    exits = AngularGrid("hemisphere", settings.exit_resolution).cell_centers()
    term = np.array([[weight * cook_torrance_between(wi, wo, slope, ior) * max(wi[2], 0.0) for wo in exits]
                     for wi in incidence])
    for side in ("front", "back"):
        visibility = measured.specular_visibility[side]
        # Coverage is the mean over the regions, V each region's own: up to the regions' spread.
        assert visibility.max() > 0.1 and np.all(visibility <= measured.coverage[side][None, :] + 0.01)
        np.testing.assert_allclose(measured.specular[side], term * visibility, rtol=2e-3, atol=1e-7)
    # The tables hold ρ without the term and its visibility; the summary the term's parameters.
    tables = cloth_tables_from_bake(folder)
    assert tables.specular == pytest.approx(summary["specular"])
