"""The yarn material sets the shader's specular term from the bake's record (tests/test_fitted_specular.py
for the bake side), and the cloth bake's measurement is keyed by it."""

import pytest

bpy = pytest.importorskip("bpy")

from clothlight.blender.garment.bake import measurement_inputs  # noqa: E402
from clothlight.blender.garment.measure import GoniometerSettings  # noqa: E402
from clothlight.blender.materials import SPECULAR_SOCKETS, build_yarn_material, shader_node  # noqa: E402
from clothlight.yarn_tables import yarn_tables_from_bake  # noqa: E402
from precompute.tables.folder import default_specular  # noqa: E402
from tests.helpers import empty_render_scene  # noqa: E402
from tests.test_fitted_specular import RECORDED, folder  # noqa: E402


def specular_inputs(material) -> dict:
    node = shader_node(material)
    return {key: node.inputs[socket].default_value for socket, key in SPECULAR_SOCKETS.items()}


def test_the_yarn_material_takes_the_recorded_specular_or_the_defaults(tmp_path):
    empty_render_scene(resolution=8, samples=1)  # Cycles with OSL: the script node compiles
    fitted = yarn_tables_from_bake(folder(tmp_path / "fitted", specular=RECORDED))
    older = yarn_tables_from_bake(folder(tmp_path / "older"))
    for tables, expected in ((fitted, RECORDED), (older, {**default_specular(), "index": older.host_index})):
        material = build_yarn_material(tables, name="test fitted specular")
        node, inputs = shader_node(material), specular_inputs(material)
        assert inputs == {**{key: pytest.approx(expected[key], rel=1e-6) for key in ("weight", "slope")},
                          "fuzz_albedo": 0.0, "fuzz_depth": 0.0, "fuzz_asymmetry": 0.0, "fuzz_flatness": 0.0}
        assert tuple(node.inputs["FuzzTint"].default_value)[:3] == (1.0, 1.0, 1.0)  # white: none recorded
        # the sheen's Fresnel index apart from the host's, which refracts the unscattered light
        assert node.inputs["SpecularIOR"].default_value == pytest.approx(expected["index"], rel=1e-6)
        assert node.inputs["IOR"].default_value == pytest.approx(tables.host_index, rel=1e-6)
    # The cloth bake measures that material: its measurement is another with another specular term.
    settings = GoniometerSettings()
    assert measurement_inputs(fitted, settings)["specular"] == {"weight": 0.55, "slope": 0.35}
    assert measurement_inputs(fitted, settings)["specular_index"] == RECORDED["index"]
    assert measurement_inputs(fitted, settings) != measurement_inputs(older, settings)
    other_index = yarn_tables_from_bake(folder(tmp_path / "other index", specular={**RECORDED, "index": 1.4}))
    assert measurement_inputs(other_index, settings) != measurement_inputs(fitted, settings)
    # the fuzz is part of what the material emits with ρ, and so of the measurement
    fuzzy = yarn_tables_from_bake(folder(tmp_path / "fuzz", specular={**RECORDED, "fuzz_albedo": 0.1}))
    assert measurement_inputs(fuzzy, settings) != measurement_inputs(fitted, settings)
    assert specular_inputs(build_yarn_material(fuzzy, name="test fuzz"))["fuzz_albedo"] == pytest.approx(0.1)
