"""The yarn shader reads baked tables exactly as the table spec says, in both lighting modes.

A synthetic table of a known analytic ρ is written in the table layout and
rendered on a flat patch whose yarn frame is known: sun mode must reproduce
the spec's interpolation (docs/table-spec.md) to float precision and the
analytic ρ to within the grid's interpolation error at off-centre directions;
general mode must turn lobe weights into clamped-cosine responses.
"""

import dataclasses
import math

import numpy as np
import pytest

from precompute.tables.closure_fit import LOBES, LobeShape, lobe_responses
from precompute.tables.grids import AngularGrid
from precompute.optics import ballistic
from precompute.optics.cook_torrance import beckmann_reflection
from precompute.optics.lommel_seeliger import (
    FUZZ_FORWARD_SLOPE,
    fuzz_albedo_at_view,
    fuzz_brdf,
    fuzz_general_lobes,
    fuzz_projected_area,
    fuzz_transmittance,
    hemispherical_transmittance,
    lommel_seeliger,
    lommel_seeliger_albedo,
)
from precompute.tables.layout import (
    brdf_atlas,
    interpolate_attenuation,
    interpolate_exit_tile,
    interpolate_rho,
    interpolate_unscattered_rho,
    lobe_atlas,
)
from tests.helpers import add_sun_and_camera, cook_torrance_between, direction, empty_render_scene, unit, write_exr

bpy = pytest.importorskip("bpy")

from clothlight.blender.materials import (  # noqa: E402
    GENERAL_MODE,
    LOBE_WEIGHT_SOCKETS,
    SUN_MODE,
    build_yarn_material,
    shader_node,
    sync_sun,
)
from clothlight.blender.measurement_render import configure_measurement_render, render_to_array  # noqa: E402
from clothlight.mesh_attributes import CLOTH_NORMAL, YARN_TANGENT  # noqa: E402
from clothlight.yarn_tables import YarnTableFiles, attenuation_reach  # noqa: E402

pytestmark = pytest.mark.render

N_I, N_O = 13, 8
SUN_IRRADIANCE = 2.0
INDEX = 1.557
#: Extinction per channel times the yarn radius: a red-tinted yarn's unscattered light.
EXTINCTION_R = np.array([0.15, 0.9, 0.6])
SPREAD = 0.05  # the shader's default cone, radians


def analytic_rho(wi, wo):
    """A smooth, positive, anisotropic ρ (1/sr) with a different shape per channel."""
    wi, wo = np.broadcast_arrays(wi, wo)
    r = 0.30 + 0.10 * wi[..., 0] + 0.08 * wi[..., 2] + 0.05 * wo[..., 0] * wo[..., 2]
    g = 0.10 + 0.05 * wi[..., 1] ** 2 + 0.04 * wo[..., 2]
    b = 0.05 + 0.03 * (wi[..., 2] + 1.0) * (1.0 + wo[..., 1])
    return np.stack([r, g, b], axis=-1)


@pytest.fixture(scope="module")
def synthetic_tables(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tables")
    wi = AngularGrid("sphere", N_I).cell_centers()
    wo = AngularGrid("hemisphere", N_O).cell_centers()
    rho = analytic_rho(wi[:, None, :], wo[None, :, :])
    atlas = brdf_atlas(rho)
    write_exr(folder / "rho.exr", atlas)
    # Every lobe with its own colour, the same for every exit cell.
    weights = np.zeros((N_O * N_O, len(LOBES), 3))
    weights[:, :, :] = [[0.5, 0.25, 0.125], [0.4, 0.0, 0.1], [0.3, 0.2, 0.0], [0.6, 0.1, 0.3], [0.2, 0.5, 0.1]]
    write_exr(folder / "lobes.exr", lobe_atlas(weights))
    attenuation = np.exp(-np.outer(ballistic.attenuation_lengths(), EXTINCTION_R))[None]
    write_exr(folder / "unscattered.exr", attenuation)
    tables = YarnTableFiles(folder / "rho.exr", folder / "lobes.exr", folder / "unscattered.exr", N_I, N_O,
                            LobeShape().to_dict(), INDEX, ballistic.ATTENUATION_SAMPLES)
    return tables, atlas, weights, attenuation


def spec_sun_rho(atlas, attenuation, wi, wo):
    """What the sun mode must emit per irradiance: the table's ρ plus the unscattered light."""
    return interpolate_rho(atlas, N_I, wi, wo) + interpolate_unscattered_rho(attenuation, INDEX, wi, wo, SPREAD)


def patch_scene(tables, mode, view_zenith_deg, view_azimuth_deg, sun_direction, *, cloth_normal=(0.0, 0.0, 1.0),
                specular_weight=0.0, specular_index=None, plain_nodes=None, fuzz_albedo=0.0, fuzz_depth=0.0,
                fuzz_shape=None):
    """A lit, viewed patch of yarn; the material in plain nodes renders under SVM, as a user's would.
    The specular term's slope is 0.8, its index ``specular_index`` (None: the host's); a fuzz of
    ``fuzz_depth`` 0 is left out of the record, as bakes from before it have none, and so are the
    fuzz's asymmetry and tint unless ``fuzz_shape`` gives them."""
    scene = empty_render_scene(resolution=8, samples=1 if mode == SUN_MODE else 16, bounces=0)
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    plane = bpy.context.active_object
    mesh = plane.data
    for name, value in ((YARN_TANGENT, (1.0, 0.0, 0.0)), (CLOTH_NORMAL, cloth_normal)):
        attribute = mesh.attributes.new(name, "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", np.tile(value, len(mesh.vertices)).astype(np.float32))
    index = {} if specular_index is None else {"index": specular_index}
    depth = {"fuzz_depth": fuzz_depth} if fuzz_depth else {}
    tables = dataclasses.replace(tables, specular={"weight": specular_weight, "slope": 0.8, "fuzz_albedo": fuzz_albedo,
                                                   **index, **depth, **(fuzz_shape or {})})
    material = build_yarn_material(tables, mode=mode, plain_nodes=plain_nodes)
    mesh.materials.append(material)

    wo = direction(view_zenith_deg, view_azimuth_deg)
    sun = add_sun_and_camera(scene, sun_direction, wo, SUN_IRRADIANCE)
    if shader_node(material) is None:
        scene.cycles.shading_system = False
    else:
        sync_sun(material, sun)
    return scene, wo


CASES = [
    # view zenith, view azimuth, direction toward the sun (yarn frame = world here)
    (35.0, 20.0, unit([0.3, -0.5, 0.8])),
    (62.0, 200.0, unit([-0.7, 0.2, 0.4])),
    (10.0, 95.0, unit([0.45, 0.55, -0.7])),  # sun behind the patch: light through the yarn
]


@pytest.mark.blender
@pytest.mark.parametrize("view_zenith, view_azimuth, sun_direction", CASES)
def test_sun_mode_reproduces_the_table_spec_and_the_analytic_rho(
    tmp_path, synthetic_tables, view_zenith, view_azimuth, sun_direction
):
    tables, atlas, _, attenuation = synthetic_tables
    scene, wo = patch_scene(tables, SUN_MODE, view_zenith, view_azimuth, sun_direction)
    pixels = render_to_array(scene, tmp_path / "patch.exr")[..., :3].reshape(-1, 3)
    measured_rho = pixels.mean(axis=0) / SUN_IRRADIANCE
    np.testing.assert_allclose(pixels.std(axis=0), 0.0, atol=1e-5)
    spec_rho = spec_sun_rho(atlas, attenuation, sun_direction, wo)
    np.testing.assert_allclose(measured_rho, spec_rho, rtol=2e-4, atol=1e-6)
    # Off the cell centres, linear interpolation of a smooth ρ stays close to it.
    np.testing.assert_allclose(measured_rho, analytic_rho(sun_direction, wo), rtol=0.03)


@pytest.mark.blender
@pytest.mark.parametrize("order, offset_rad", [(0, 0.0), (0, 0.04), (1, 0.02), (2, 0.0)],
                         ids=["through", "through-off-centre", "one-reflection", "two-reflections"])
def test_sun_mode_adds_the_unscattered_light_as_its_numpy_twin(tmp_path, synthetic_tables, order, offset_rad):
    # The sun where an unscattered path comes from (or within its cone): the shader's closed form
    # and cone must be the NumPy twin's, and they must dominate the scattered table there.
    tables, atlas, _, attenuation = synthetic_tables
    view_zenith, view_azimuth = 30.0, 60.0
    wo = direction(view_zenith, view_azimuth)
    paths, _, _ = ballistic.unscattered_paths(wo, INDEX)
    sun = unit(paths[order] + offset_rad * unit(np.cross(paths[order], [0.0, 0.0, 1.0])))
    scene, _ = patch_scene(tables, SUN_MODE, view_zenith, view_azimuth, sun)
    measured_rho = render_to_array(scene, tmp_path / "patch.exr")[..., :3].reshape(-1, 3).mean(axis=0) / SUN_IRRADIANCE
    unscattered = interpolate_unscattered_rho(attenuation, INDEX, sun, wo, SPREAD)
    assert unscattered.max() > 0.01 * interpolate_rho(atlas, N_I, sun, wo).max()
    np.testing.assert_allclose(measured_rho, spec_sun_rho(atlas, attenuation, sun, wo), rtol=1e-3, atol=1e-6)


def unscattered_only(folder, tables, index) -> YarnTableFiles:
    """``tables`` with ρ and the lobe weights zero: only the unscattered light, through a host of ``index``."""
    write_exr(folder / "rho.exr", np.zeros((N_I * N_O, N_I * N_O, 3)))
    write_exr(folder / "lobes.exr", np.zeros((N_O, len(LOBES) * N_O, 3)))
    return YarnTableFiles(folder / "rho.exr", folder / "lobes.exr", tables.unscattered_path, N_I, N_O,
                          LobeShape().to_dict(), index, ballistic.ATTENUATION_SAMPLES)


def render_under_a_white_sky(scene, folder) -> np.ndarray:
    """The patch's pixels (M, 3) with the scene's lights replaced by a uniform sky of radiance 1."""
    scene.cycles.samples = 256
    for obj in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(obj)
    scene.world = bpy.data.worlds.new("sky")
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = 1.0
    return render_to_array(scene, folder / "patch.exr")[..., :3].reshape(-1, 3)


@pytest.mark.blender
@pytest.mark.parametrize("index, plain_nodes", [(INDEX, False), (1.0, False), (1.0, True)],
                         ids=["refracting-host", "fibres-in-air-osl", "fibres-in-air-plain-nodes"])
@pytest.mark.parametrize("view_zenith, view_azimuth", [(0.0, 0.0), (30.0, 60.0), (55.0, 170.0), (70.0, 20.0)])
def test_general_mode_renders_each_unscattered_path_as_a_lobe_of_its_weight(
        tmp_path, synthetic_tables, view_zenith, view_azimuth, index, plain_nodes):
    # Under a uniform sky of radiance 1 each lobe of unit integral gives its weight: the patch
    # (no scattered light: ρ and the lobe weights zero) must shine with the closed form's
    # ∫ρ_u dω_i, and the lit-from-behind lobes (GGX refraction) are not lost.  A host of index 1
    # (fibres in air) has one straight path, which the plain nodes render too.
    tables = synthetic_tables[0]
    scene, wo = patch_scene(unscattered_only(tmp_path, tables, index), GENERAL_MODE, view_zenith, view_azimuth,
                            unit([0.0, 0.0, 1.0]), plain_nodes=plain_nodes)
    assert (shader_node(bpy.context.active_object.active_material) is None) == plain_nodes
    pixels = render_under_a_white_sky(scene, tmp_path)
    attenuation = synthetic_tables[3]
    expected = ballistic.unscattered_radiance_factor(
        wo, index, lambda length: np.asarray(interpolate_attenuation(attenuation, length)))
    np.testing.assert_allclose(pixels.mean(axis=0), expected, rtol=0.02)


@pytest.mark.blender
def test_general_mode_leaves_out_the_paths_beyond_the_reach_without_changing_a_pixel(tmp_path, synthetic_tables):
    # A yarn that scatters: the attenuation falls below the floor within a radius, so every path
    # but the short grazing ones is left out before its lookup, as the weight test would.
    tables = synthetic_tables[0]
    attenuation = np.exp(-np.outer(ballistic.attenuation_lengths(), [6.0, 4.0, 3.0]))[None]
    write_exr(tmp_path / "scattering.exr", attenuation)
    scattering = dataclasses.replace(tables, unscattered_path=tmp_path / "scattering.exr")
    reach = attenuation_reach(attenuation)
    assert 1.0 < reach < 2.0
    renders = []
    for tables in (scattering, dataclasses.replace(scattering, unscattered_reach=reach)):
        scene, _ = patch_scene(tables, GENERAL_MODE, 75.0, 30.0, unit([0.2, 0.3, -0.9]))
        renders.append(render_to_array(scene, tmp_path / f"reach{len(renders)}.exr"))
    np.testing.assert_array_equal(renders[0], renders[1])
    assert renders[0][..., :3].max() > 0.0


def without_unscattered_light(tables, folder):
    """``tables`` of a yarn that lets no light through unscattered: its general mode can be plain nodes."""
    write_exr(folder / "opaque.exr", np.zeros((1, ballistic.ATTENUATION_SAMPLES, 3)))
    return dataclasses.replace(tables, unscattered_path=folder / "opaque.exr", unscattered_reach=0.0)


@pytest.mark.blender
@pytest.mark.parametrize("plain_nodes", [True, False], ids=["plain-nodes", "osl"])
@pytest.mark.parametrize(
    "view_zenith, view_azimuth, sun_direction",
    [(20.0, 40.0, unit([0.3, -0.2, 0.9])),  # front: diffuse, fibre cone, retro-reflection
     (35.0, 10.0, unit([-0.5, 0.1, 0.85])),  # close to the fibre's specular cone
     (20.0, 40.0, unit([0.2, 0.3, -0.9])),  # behind: translucent, fibre transmission
     (80.0, 225.0, unit([0.3, -0.2, 0.9]))],  # a grazing view in the map's third octant pair
    ids=["front", "cone", "behind", "grazing"])
def test_general_mode_renders_the_lobe_mixture(tmp_path, synthetic_tables, view_zenith, view_azimuth, sun_direction,
                                               plain_nodes):
    tables, _, weights, _ = synthetic_tables
    # Each exit cell's weights its own (the material's image nodes must find the view's cell in
    # every tile, as the twin does), and the mixture alone: a yarn that lets no light through
    # unscattered.
    weights = weights * np.random.default_rng(3).uniform(0.3, 1.0, weights.shape)
    write_exr(tmp_path / "lobes.exr", lobe_atlas(weights))
    tables = dataclasses.replace(without_unscattered_light(tables, tmp_path), lobe_path=tmp_path / "lobes.exr")
    scene, wo = patch_scene(tables, GENERAL_MODE, view_zenith, view_azimuth, sun_direction, plain_nodes=plain_nodes)
    assert (shader_node(bpy.context.active_object.active_material) is None) == plain_nodes
    pixels = render_to_array(scene, tmp_path / "patch.exr")[..., :3].reshape(-1, 3)
    tiles = weights.reshape(N_O, N_O, len(LOBES), 3)
    at_view = np.stack([interpolate_exit_tile(tiles[:, :, k], wo) for k in range(len(LOBES))])
    expected = SUN_IRRADIANCE * lobe_responses(wo, sun_direction) @ at_view
    assert expected.min() > 1e-3
    np.testing.assert_allclose(pixels.mean(axis=0), expected, rtol=0.01, atol=1e-4)


def rendered_specular(tmp_path, tables, mode, view, sun_direction, cloth_normal, weight=1.0, plain_nodes=None,
                      specular_index=None):
    """Mean radiance of the patch with the specular term of ``weight`` minus without it."""
    zenith = math.degrees(math.acos(view[2]))
    azimuth = math.degrees(math.atan2(view[1], view[0]))
    means = []
    for weight in (weight, 0.0):
        scene, _ = patch_scene(tables, mode, zenith, azimuth, sun_direction, cloth_normal=cloth_normal,
                               specular_weight=weight, specular_index=specular_index, plain_nodes=plain_nodes)
        means.append(render_to_array(scene, tmp_path / f"{mode}{weight}.exr")[..., :3].reshape(-1, 3).mean(axis=0))
    return means[0] - means[1]


@pytest.mark.blender
@pytest.mark.parametrize("cloth_normal, sun_direction, lit", [
    (unit([0.3, 0.0, 0.95]), unit([-0.5, 0.1, 0.86]), True),  # the face toward the cloth normal and the sun
    (unit([0.6, 0.0, -0.8]), unit([0.8, 0.0, -0.6]), False),  # a face turned below the cloth: sun behind it
], ids=["face-lit", "face-below-cloth"])
@pytest.mark.parametrize("plain_nodes", [True, False], ids=["plain-nodes", "osl"])
def test_general_mode_specular_is_the_sun_modes(tmp_path, synthetic_tables, cloth_normal, sun_direction, lit,
                                                plain_nodes):
    # The Cook-Torrance term is about the cloth normal, but a face lit from behind reflects none of
    # it (the sun mode's rule): Cycles' closure must give the same on either side of the cloth plane.
    # In plain nodes it is the Metallic BSDF with extinction 0: the same exact dielectric Fresnel.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view = unit([0.8, 0.1, 0.6])
    sun = rendered_specular(tmp_path, tables, SUN_MODE, view, sun_direction, cloth_normal)
    general = rendered_specular(tmp_path, tables, GENERAL_MODE, view, sun_direction, cloth_normal,
                                plain_nodes=plain_nodes)
    if lit:
        assert sun.min() > 1e-2
        np.testing.assert_allclose(general, sun, rtol=0.02)
    else:
        np.testing.assert_allclose(sun, 0.0, atol=1e-6)
        np.testing.assert_allclose(general, 0.0, atol=1e-4)


@pytest.mark.blender
@pytest.mark.parametrize("mode, plain_nodes", [(SUN_MODE, False), (GENERAL_MODE, False), (GENERAL_MODE, True)],
                         ids=["sun", "general-osl", "general-plain-nodes"])
def test_the_specular_is_the_same_on_both_faces_of_the_cloth(tmp_path, synthetic_tables, mode, plain_nodes):
    # Seen and lit from the cloth's back, the term is about the back's normal: the same sheen.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view, sun_direction = unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86])
    front = rendered_specular(tmp_path, tables, mode, view, sun_direction, (0.0, 0.0, 1.0), plain_nodes=plain_nodes)
    back = rendered_specular(tmp_path, tables, mode, view, sun_direction, (0.0, 0.0, -1.0), plain_nodes=plain_nodes)
    assert front.min() > 1e-2
    np.testing.assert_allclose(back, front, rtol=1e-3 if mode == SUN_MODE else 0.02)


@pytest.mark.blender
@pytest.mark.parametrize("mode, plain_nodes", [(SUN_MODE, False), (GENERAL_MODE, False), (GENERAL_MODE, True)],
                         ids=["sun", "general-osl", "general-plain-nodes"])
def test_the_sheen_reflects_at_its_own_index_not_the_hosts(tmp_path, synthetic_tables, mode, plain_nodes):
    # A yarn of fibres reflects its sheen off the fibres (SpecularIOR), whatever index the host has
    # (IOR, which refracts the unscattered light); at the host's 1.2 the Fresnel factor is 1/5 of it.
    tables = dataclasses.replace(without_unscattered_light(synthetic_tables[0], tmp_path), host_index=1.2)
    view, sun_direction = unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86])
    sheen = rendered_specular(tmp_path, tables, mode, view, sun_direction, (0.0, 0.0, 1.0), plain_nodes=plain_nodes,
                              specular_index=INDEX)
    expected = SUN_IRRADIANCE * cook_torrance_between(sun_direction, view, 0.8, INDEX) * sun_direction[2]
    assert expected > 3.0 * SUN_IRRADIANCE * cook_torrance_between(sun_direction, view, 0.8, 1.2) * sun_direction[2]
    np.testing.assert_allclose(sheen, expected, rtol=1e-3 if mode == SUN_MODE else 0.02)


@pytest.mark.blender
@pytest.mark.parametrize("mode, plain_nodes", [(SUN_MODE, False), (GENERAL_MODE, False), (GENERAL_MODE, True)],
                         ids=["sun", "general-osl", "general-plain-nodes"])
def test_the_fuzz_is_lommel_seeliger_in_sun_mode_and_its_albedo_in_the_general_mode(tmp_path, synthetic_tables, mode,
                                                                                   plain_nodes):
    # Sun mode: A μi / (4π (μi + μo)) exactly.  General mode: a diffuse lobe about the cloth normal that
    # returns the term's directional albedo at the view, a(μo) μi / π under the sun.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view, sun_direction, albedo = unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86]), 0.3
    zenith, azimuth = math.degrees(math.acos(view[2])), math.degrees(math.atan2(view[1], view[0]))
    means = []
    for fuzz in (albedo, 0.0):
        scene, _ = patch_scene(tables, mode, zenith, azimuth, sun_direction, plain_nodes=plain_nodes, fuzz_albedo=fuzz)
        means.append(render_to_array(scene, tmp_path / f"{mode}{fuzz}.exr")[..., :3].reshape(-1, 3).mean(axis=0))
    fuzz = means[0] - means[1]
    if mode == SUN_MODE:
        expected = SUN_IRRADIANCE * lommel_seeliger(sun_direction, view, albedo) * sun_direction[2]
        np.testing.assert_allclose(fuzz, expected, rtol=1e-3)
    else:
        expected = SUN_IRRADIANCE * lommel_seeliger_albedo(view[2], albedo) / math.pi * sun_direction[2]
        np.testing.assert_allclose(fuzz, expected, rtol=0.02)


#: A fuzz of optical depth (the specular record's fuzz_depth) and its albedo, for the tests of its shading.
FUZZ_DEPTH, FUZZ_ALBEDO = 0.3, 0.4
#: The share of a fuzz's fibres that lie flat, for the tests of a fuzz of fibres lying flat.
FLAT_FUZZ = 0.8
#: A fuzz of dyed fibres that scatter forward: its asymmetry and tint (the record's keys).
FORWARD_RED_FUZZ = {"fuzz_asymmetry": 0.6, "fuzz_tint_red": 2.0, "fuzz_tint_blue": 0.5}



def render_patch_mean(tmp_path, tables, mode, view, sun_direction, **scene_options):
    """Mean radiance of the patch of :func:`patch_scene` seen from ``view`` (a unit vector)."""
    zenith, azimuth = math.degrees(math.acos(view[2])), math.degrees(math.atan2(view[1], view[0]))
    scene, _ = patch_scene(tables, mode, zenith, azimuth, sun_direction, **scene_options)
    return render_to_array(scene, tmp_path / "patch.exr")[..., :3].reshape(-1, 3).mean(axis=0)


@pytest.mark.blender
@pytest.mark.parametrize("mode, plain_nodes", [(SUN_MODE, False), (GENERAL_MODE, False), (GENERAL_MODE, True)],
                         ids=["sun", "general-osl", "general-plain-nodes"])
@pytest.mark.parametrize("depth", [0.0, FUZZ_DEPTH], ids=["veneer", "of-depth"])
def test_a_fuzz_that_scatters_forward_is_its_phase_function_in_sun_mode_and_leans_forward_in_the_general_mode(
        tmp_path, synthetic_tables, mode, plain_nodes, depth):
    # Sun mode: the layer's law times 4π p_HG(−l·v; g), per channel its tint.  General mode: a diffuse
    # lobe and a forward Beckmann lobe that return its directional albedo at the view and its excess
    # of light from the far side (sums over light cosines and azimuths; in plain nodes Float Curves
    # over μo).  The sun behind the view (forward scattering): far more than the isotropic fuzz in sun
    # mode, and in the general mode far more than a diffuse lobe of the same albedo gave.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view, sun_direction = unit([0.96, 0.03, 0.28]), unit([-0.96, 0.0, 0.28])
    tint = np.array([FORWARD_RED_FUZZ["fuzz_tint_red"], 1.0, FORWARD_RED_FUZZ["fuzz_tint_blue"]])
    asymmetry = FORWARD_RED_FUZZ["fuzz_asymmetry"]
    means = [render_patch_mean(tmp_path, tables, mode, view, sun_direction, plain_nodes=plain_nodes,
                               fuzz_albedo=albedo, fuzz_depth=depth, fuzz_shape=FORWARD_RED_FUZZ)
             for albedo in (FUZZ_ALBEDO, 0.0)]
    fuzz = (means[0] - means[1]) / SUN_IRRADIANCE  # the yarn's light, shaded alike by a fuzz of any albedo
    if mode == SUN_MODE:
        expected = fuzz_brdf(sun_direction, view, FUZZ_ALBEDO, depth, asymmetry) * sun_direction[2] * tint
        assert expected[1] > 2.0 * fuzz_brdf(sun_direction, view, FUZZ_ALBEDO, depth) * sun_direction[2]
        np.testing.assert_allclose(fuzz, expected, rtol=1e-3)
    else:
        diffuse, forward = fuzz_general_lobes(view[2], FUZZ_ALBEDO, depth, asymmetry)
        expected = (diffuse / math.pi + forward * beckmann_reflection(sun_direction, view, FUZZ_FORWARD_SLOPE)
                    ) * sun_direction[2] * tint
        diffuse_alone = fuzz_albedo_at_view(view[2], FUZZ_ALBEDO, depth, asymmetry) / math.pi * sun_direction[2]
        assert expected[1] > 3.0 * diffuse_alone
        np.testing.assert_allclose(fuzz, expected, rtol=0.02)


@pytest.mark.blender
@pytest.mark.parametrize("plain_nodes", [False, True], ids=["osl", "plain-nodes"])
def test_a_forward_fuzz_seen_from_the_lights_side_is_dimmer_than_a_diffuse_lobe_in_the_general_mode(
        tmp_path, synthetic_tables, plain_nodes):
    # The sun low on the view's own side (back-scattering): the forward lobe sends it little, so the
    # general mode gives less than the diffuse lobe of the same albedo did, and is closer to the fuzz.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view, sun_direction = unit([0.8, 0.05, 0.6]), unit([0.85, -0.05, 0.52])
    tint = np.array([FORWARD_RED_FUZZ["fuzz_tint_red"], 1.0, FORWARD_RED_FUZZ["fuzz_tint_blue"]])
    asymmetry = FORWARD_RED_FUZZ["fuzz_asymmetry"]
    means = [render_patch_mean(tmp_path, tables, GENERAL_MODE, view, sun_direction, plain_nodes=plain_nodes,
                               fuzz_albedo=albedo, fuzz_depth=FUZZ_DEPTH, fuzz_shape=FORWARD_RED_FUZZ)
             for albedo in (FUZZ_ALBEDO, 0.0)]
    fuzz = (means[0] - means[1]) / SUN_IRRADIANCE
    diffuse, forward = fuzz_general_lobes(view[2], FUZZ_ALBEDO, FUZZ_DEPTH, asymmetry)
    expected = (diffuse / math.pi + forward * beckmann_reflection(sun_direction, view, FUZZ_FORWARD_SLOPE)
                ) * sun_direction[2] * tint
    diffuse_alone = fuzz_albedo_at_view(view[2], FUZZ_ALBEDO, FUZZ_DEPTH, asymmetry) / math.pi * sun_direction[2]
    exact = fuzz_brdf(sun_direction, view, FUZZ_ALBEDO, FUZZ_DEPTH, asymmetry) * sun_direction[2]
    assert expected[1] < 0.7 * diffuse_alone and abs(expected[1] - exact) < 0.5 * abs(diffuse_alone - exact)
    np.testing.assert_allclose(fuzz, expected, rtol=0.02)


@pytest.mark.blender
@pytest.mark.parametrize("view, sun_direction", [
    (unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86])),  # the sun in front: yarn, fuzz and sheen
    (direction(30.0, 60.0), unit(ballistic.unscattered_paths(direction(30.0, 60.0), INDEX)[0][0])),  # behind
], ids=["front", "behind-unscattered"])
@pytest.mark.parametrize("flatness", [0.0, FLAT_FUZZ], ids=["fibres-every-way", "fibres-lying-flat"])
def test_a_fuzz_of_depth_lets_through_t_of_the_yarn_and_reflects_the_rest_in_sun_mode(tmp_path, synthetic_tables,
                                                                                       view, sun_direction, flatness):
    # The fuzz stands between the yarns and the sun, and between them and the viewer: the yarn's ρ and
    # its unscattered light are T(μi, μo) of what they were, T = exp(−τ (s_i/|μi| + s_o/μo)) (the sun
    # from behind crosses the fuzz of the back face; s = 1 unless its fibres lie flat), the fuzz reflects
    # (1 − T) of its Lommel–Seeliger law, and the sheen, the top fibres' own reflection, is not shaded.
    tables, atlas, _, attenuation = synthetic_tables
    shape = {"fuzz_flatness": flatness} if flatness else {}
    measured = render_patch_mean(tmp_path, tables, SUN_MODE, view, sun_direction, specular_weight=1.0,
                                 fuzz_albedo=FUZZ_ALBEDO, fuzz_depth=FUZZ_DEPTH, fuzz_shape=shape) / SUN_IRRADIANCE
    mu_i = sun_direction[2]
    transmittance = fuzz_transmittance(mu_i, view[2], FUZZ_DEPTH, flatness)
    assert 0.2 < transmittance < 0.7
    yarn = spec_sun_rho(atlas, attenuation, sun_direction, view)
    sheen = cook_torrance_between(sun_direction, view, 0.8, INDEX) * max(mu_i, 0.0)
    fuzz = fuzz_brdf(sun_direction, view, FUZZ_ALBEDO, FUZZ_DEPTH, 0.0, flatness)
    expected = transmittance * yarn + fuzz * mu_i + sheen
    np.testing.assert_allclose(measured, expected, rtol=1e-3, atol=1e-6)
    if mu_i < 0.0:  # light through the yarn: its unscattered part, shaded too, is most of it
        assert interpolate_unscattered_rho(attenuation, INDEX, sun_direction, view, SPREAD).max() > yarn.max() / 2
    else:
        assert sheen > 1e-2 and fuzz > 1e-3


@pytest.mark.blender
@pytest.mark.parametrize("plain_nodes", [False, True], ids=["osl", "plain-nodes"])
@pytest.mark.parametrize("flatness", [0.0, FLAT_FUZZ], ids=["fibres-every-way", "fibres-lying-flat"])
def test_a_fuzz_of_depth_in_the_general_mode_is_its_albedo_at_the_view_over_the_shaded_yarn(
        tmp_path, synthetic_tables, plain_nodes, flatness):
    # No light direction: the yarn's lobes take exp(−τ s(μo)/μo) times the hemispherical transmittance,
    # the fuzz's diffuse lobe the directional albedo of a layer of depth τ at the view (Gauss–Legendre
    # over μi; s = 1 unless its fibres lie flat), and the sheen is as without a fuzz.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    weights = synthetic_tables[2][0]  # every exit cell's lobe weights are the same
    view, sun_direction = unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86])
    shape = {"fuzz_flatness": flatness} if flatness else {}
    measured = render_patch_mean(tmp_path, tables, GENERAL_MODE, view, sun_direction, specular_weight=1.0,
                                 fuzz_albedo=FUZZ_ALBEDO, fuzz_depth=FUZZ_DEPTH, plain_nodes=plain_nodes,
                                 fuzz_shape=shape)
    assert (shader_node(bpy.context.active_object.active_material) is None) == plain_nodes
    mu_i, mu_o = sun_direction[2], view[2]
    share = (math.exp(-FUZZ_DEPTH * float(fuzz_projected_area(mu_o, flatness)) / mu_o)
             * hemispherical_transmittance(FUZZ_DEPTH, flatness))
    assert 0.2 < share < 0.7
    yarn = lobe_responses(view, sun_direction) @ weights
    fuzz = fuzz_albedo_at_view(mu_o, FUZZ_ALBEDO, FUZZ_DEPTH, flatness=flatness) / math.pi * mu_i
    assert fuzz < 0.8 * lommel_seeliger_albedo(mu_o, FUZZ_ALBEDO) / math.pi * mu_i
    sheen = cook_torrance_between(sun_direction, view, 0.8, INDEX) * mu_i
    np.testing.assert_allclose(measured, SUN_IRRADIANCE * (share * yarn + fuzz + sheen), rtol=0.01, atol=1e-4)


@pytest.mark.blender
@pytest.mark.parametrize("index, plain_nodes", [(INDEX, False), (1.0, True)],
                         ids=["refracting-host-osl", "fibres-in-air-plain-nodes"])
def test_a_fuzz_of_depth_shades_the_unscattered_lobes_in_the_general_mode(tmp_path, synthetic_tables, index,
                                                                          plain_nodes):
    # Under a uniform sky of radiance 1 the unscattered lobes give their weights times the yarn's share
    # under a black fuzz (albedo 0) of depth τ, exp(−τ/μo) times the hemispherical transmittance.
    scene, wo = patch_scene(unscattered_only(tmp_path, synthetic_tables[0], index), GENERAL_MODE, 30.0, 60.0,
                            unit([0.0, 0.0, 1.0]), plain_nodes=plain_nodes, fuzz_depth=FUZZ_DEPTH)
    assert (shader_node(bpy.context.active_object.active_material) is None) == plain_nodes
    pixels = render_under_a_white_sky(scene, tmp_path)
    unshaded = ballistic.unscattered_radiance_factor(
        wo, index, lambda length: np.asarray(interpolate_attenuation(synthetic_tables[3], length)))
    share = math.exp(-FUZZ_DEPTH / wo[2]) * hemispherical_transmittance(FUZZ_DEPTH)
    assert unshaded.min() > 0.01 and share < 0.5
    np.testing.assert_allclose(pixels.mean(axis=0), share * unshaded, rtol=0.02)


@pytest.mark.blender
def test_plain_nodes_carry_a_specular_weight_above_one(tmp_path, synthetic_tables):
    # A Mix Shader's factor stops at 1: a weight of 2.5 is three copies of the lobe at 5/6 each.
    tables = without_unscattered_light(synthetic_tables[0], tmp_path)
    view, sun_direction = unit([0.8, 0.1, 0.6]), unit([-0.5, 0.1, 0.86])
    once = rendered_specular(tmp_path, tables, GENERAL_MODE, view, sun_direction, (0.0, 0.0, 1.0), plain_nodes=True)
    more = rendered_specular(tmp_path, tables, GENERAL_MODE, view, sun_direction, (0.0, 0.0, 1.0), weight=2.5,
                             plain_nodes=True)
    assert once.min() > 1e-2
    np.testing.assert_allclose(more, 2.5 * once, rtol=0.02)


@pytest.mark.blender
@pytest.mark.parametrize("fuzz", [{}, {"fuzz_albedo": FUZZ_ALBEDO, "fuzz_depth": FUZZ_DEPTH}], ids=["no-fuzz", "fuzz"])
@pytest.mark.parametrize("fibres_in_air", [False, True], ids=["opaque-yarn", "fibres-in-air"])
@pytest.mark.parametrize("light_between_yarns", [False, True], ids=["sun", "sun-sky-bounces"])
def test_plain_nodes_render_the_woven_sample_as_the_osl_general_mode(tmp_path, synthetic_tables, light_between_yarns,
                                                                    fibres_in_air, fuzz):
    # The same closures with the same weights on a woven sample.  Under the sun alone, direct light:
    # pixel for pixel the same image.  With a grey sky and four bounces (light between yarns and
    # through their far faces) the two pick closures to sample in another order, so their noise
    # differs, and their means agree.  The camera frames the inside of the sample: through a cut
    # yarn end it would see the yarn's far face, where the OSL shader turns its frame outward and a
    # Hair BSDF node cannot.  A yarn of fibres in air (host index 1) lets light through unscattered
    # along a straight line, one more lobe in both.  A fuzz of depth: its diffuse lobe of the layer's
    # albedo at the view, and the yarn's closures shaded under it, in both.
    from clothlight.blender.sample_object import build_sample_object
    from clothlight.weave import WeaveParameters

    tables, _, weights, _ = synthetic_tables
    weights = weights * np.random.default_rng(4).uniform(0.3, 1.0, weights.shape)
    write_exr(tmp_path / "lobes.exr", lobe_atlas(weights))
    tables = dataclasses.replace(tables if fibres_in_air else without_unscattered_light(tables, tmp_path),
                                 lobe_path=tmp_path / "lobes.exr", specular={"weight": 0.5, "slope": 0.3, **fuzz},
                                 host_index=1.0 if fibres_in_air else tables.host_index)
    scene = empty_render_scene(resolution=48, samples=64 if light_between_yarns else 4,
                               bounces=4 if light_between_yarns else 0)
    if light_between_yarns:
        scene.world = bpy.data.worlds.new("grey")
        scene.world.color = (0.2, 0.2, 0.2)
    sample = build_sample_object(WeaveParameters(warp_count=6, weft_count=6))
    add_sun_and_camera(scene, unit([0.3, -0.4, 0.85]), unit([0.0, -0.5, 0.85]), SUN_IRRADIANCE)
    scene.camera.data.ortho_scale = 0.5 * min(sample.dimensions[:2])
    scene.camera.location = np.asarray(scene.camera.location) + np.asarray(sample.location)
    images = {}
    for plain_nodes in (True, False):
        material = build_yarn_material(tables, f"general {plain_nodes}", mode=GENERAL_MODE, plain_nodes=plain_nodes)
        sample.data.materials.clear()
        sample.data.materials.append(material)
        scene.cycles.shading_system = not plain_nodes
        images[plain_nodes] = render_to_array(scene, tmp_path / f"{plain_nodes}.exr")[..., :3]
    assert (images[False].sum(axis=-1) > 0).mean() > 0.5
    if light_between_yarns:
        np.testing.assert_allclose(images[True].mean(axis=(0, 1)), images[False].mean(axis=(0, 1)), rtol=0.01)
    else:
        np.testing.assert_allclose(images[True], images[False], rtol=1e-3, atol=1e-6)


@pytest.mark.blender
def test_plain_nodes_answer_a_shadow_ray_without_the_lobes(tmp_path, synthetic_tables):
    # Cycles' SVM jumps over the input of a Mix Shader whose weight is zero, and the nodes only
    # that input reads.  A shadow ray asks a yarn's near face only whether it passes: the lobe
    # lookups must sit behind a Mix on Is Shadow Ray whose shadow side is empty
    # (benchmarks/bench_closeup.py), and nothing else may read them.
    bpy.ops.wm.read_homefile(use_empty=True)
    material = build_yarn_material(without_unscattered_light(synthetic_tables[0], tmp_path), mode=GENERAL_MODE,
                                   plain_nodes=True)
    nodes = material.node_tree.nodes

    def upstream(node, stop=None):
        seen, todo = set(), [node]
        while todo:
            current = todo.pop()
            if current.name in seen:
                continue
            seen.add(current.name)
            for socket in current.inputs:
                if stop is not None and current == stop and socket == stop.inputs[1]:
                    continue
                todo += [link.from_node for link in socket.links]
        return {nodes[name] for name in seen}

    gates = [node for node in nodes if node.type == "MIX_SHADER" and node.inputs["Fac"].is_linked
             and node.inputs["Fac"].links[0].from_socket.name == "Is Shadow Ray"]
    assert len(gates) == 1
    gate = gates[0]
    assert not gate.inputs[2].is_linked
    output = next(node for node in nodes if node.type == "OUTPUT_MATERIAL")
    behind_the_gate = upstream(gate.inputs[1].links[0].from_node)
    lookups = {node for node in nodes if node.type == "TEX_IMAGE"}
    assert lookups and lookups <= behind_the_gate
    assert not lookups & upstream(output, stop=gate)


@pytest.mark.blender
@pytest.mark.parametrize("mode, plain_nodes", [(SUN_MODE, False), (GENERAL_MODE, False), (GENERAL_MODE, True)],
                         ids=["sun", "general-osl", "general-plain-nodes"])
def test_the_yarn_material_is_no_light_to_sample(tmp_path, synthetic_tables, mode, plain_nodes):
    # Cycles cannot tell whether an OSL shader emits; sampling every triangle of the cloth as a
    # light made the general mode 1.7x slower, for no light (clothlight.blender.materials).
    bpy.ops.wm.read_homefile(use_empty=True)
    configure_measurement_render(bpy.context.scene, resolution=(8, 8), samples=1)
    material = build_yarn_material(without_unscattered_light(synthetic_tables[0], tmp_path), mode=mode,
                                   plain_nodes=plain_nodes)
    assert material.cycles.emission_sampling == "NONE"
    assert not material.cycles.use_bump_map_correction


def test_the_material_feeds_the_lobe_weights_in_the_order_of_the_tiles():
    assert tuple(LOBE_WEIGHT_SOCKETS) == LOBES


@pytest.mark.blender
def test_new_tables_reach_a_material_saved_with_an_older_shader(synthetic_tables):
    # A .blend keeps the shader its material was made with: one from before UnscatteredReach (an
    # older ClothLight) is built again with this version's when it is pointed at other tables
    # (the Dye Range's recolour), in its mode and under its sun.
    from clothlight.blender.materials import material_mode, read_other_tables
    from clothlight.blender.osl_shaders import shader_source
    from tests.helpers import script_material

    bpy.ops.wm.read_homefile(use_empty=True)
    configure_measurement_render(bpy.context.scene, resolution=(8, 8), samples=1)
    source = shader_source("cloth_yarn")
    older = source.replace("    float UnscatteredReach = 1e9,", "").replace("UnscatteredReach,", "1e9,")
    assert older != source
    material, node = script_material("saved yarn", "cloth_yarn", older)
    node.inputs["SunMode"].default_value = 1
    node.inputs["SunDirection"].default_value = (0.6, 0.0, 0.8)
    assert "UnscatteredReach" not in node.inputs
    tables = synthetic_tables[0]
    read_other_tables(material, tables)
    node = shader_node(material)
    assert "UnscatteredReach" in node.inputs
    assert node.inputs["Table"].default_value == str(tables.brdf_path)
    assert material_mode(material) == SUN_MODE
    assert tuple(node.inputs["SunDirection"].default_value) == pytest.approx((0.6, 0.0, 0.8))
