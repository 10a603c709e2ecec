"""The Yarn Medium panel's Target Colour and Match Colour (issue 44): the request and its file
(clothlight/colour_match_job.py), the Base Medium "Custom File" a recipe becomes
(clothlight/medium_settings.py, clothlight/blender/properties.py), and the operator through bpy: its
job in a child process (clothlight/fit/colour_match_worker.py) writes a recipe whose swatch has the
colour, an unreachable colour writes nothing unless its nearest recipe is applied, Esc cancels, and
registering and unregistering leave Blender as it was.

The yarn is red cotton on the smallest grids (4 × 2 cells, 4 × 4 angular grids): its shade model
(the swatches' response, four renders, and the clear yarn's absorption series) is made once for the
module into a shared cache, in about 25 s."""

from __future__ import annotations

import pathlib
import re
from types import SimpleNamespace

import pytest

from clothlight.colour_match_job import (ColourMatchOutcome, ColourMatchRequest, recipe_file_name, srgb_hex,
                                         write_preset)
from clothlight.medium_settings import BakeRequest, medium_config, preset_request
from precompute.errors import ParameterError

#: Red cotton on the smallest grids: the panel's yarn in these tests.
TINY_GRIDS = {"n_around": 4, "n_along": 2, "angular_resolution": 4}
#: MERL red-fabric2's colour (benchmarks/bench_colour_match.py), which the dyes reach on red cotton.
RED_FABRIC2 = "#6a2717"


def srgb(hex_colour: str) -> tuple[float, float, float]:
    return tuple(int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5))


# -- the request, its file, the custom-file medium (no Blender) -----------------------------------


def test_a_request_round_trips_names_its_file_and_dyes_the_panels_yarn(tmp_path):
    yarn = BakeRequest(preset="voided_red_cotton", overrides=(("dye.weight_percent", 2.0), ("yarn.radius_mm", 0.2)),
                       **TINY_GRIDS)
    request = ColourMatchRequest(target=srgb(RED_FABRIC2), medium=yarn, out=str(tmp_path / "x.toml"))
    assert ColourMatchRequest.from_json(request.to_json()) == request and request.hex == RED_FABRIC2
    # the file: the yarn, the colour, a hash of the yarn's changes (the dye's is the recipe's, not kept)
    name = recipe_file_name(yarn, request.target)
    assert name.startswith("voided_red_cotton_6a2717_") and name.endswith(".toml")
    assert recipe_file_name(BakeRequest(preset="voided_red_cotton"), request.target) == "voided_red_cotton_6a2717.toml"
    assert recipe_file_name(BakeRequest(preset="voided_red_cotton", overrides=(("dye.weight_percent", 2.0),)),
                            request.target) == "voided_red_cotton_6a2717.toml"
    # a recipe solved again for another colour keeps the yarn's name, not the old colour's
    assert recipe_file_name(BakeRequest(preset="/x/colours/red_cotton_6a2717.toml"), srgb("#2b2d45")) \
        == "red_cotton_2b2d45.toml"
    # the yarn to dye: the panel's changes but the dye's, and the changed grids
    config, _ = request.base_config()
    assert config["yarn"]["radius_mm"] == 0.2 and config["transport"]["n_around"] == 4
    assert config["dye"]["weight_percent"] == medium_config("voided_red_cotton")["dye"]["weight_percent"]
    untouched = ColourMatchRequest(medium=preset_request("voided_red_cotton"), out=str(tmp_path / "y.toml"))
    assert untouched.base_config()[0] == medium_config("voided_red_cotton")  # shares the command line's shade model


@pytest.mark.parametrize("changes, field", [
    ({"target": (1.2, 0.0, 0.0)}, "target colour"),
    ({"medium": BakeRequest(preset="no_such_preset")}, "preset"),
    ({"out": ""}, "out"),
])
def test_a_bad_request_is_refused_before_a_child_starts_naming_the_field(tmp_path, changes, field):
    fields = {"target": srgb(RED_FABRIC2), "medium": BakeRequest(), "out": str(tmp_path / "x.toml"), **changes}
    with pytest.raises(ParameterError) as refusal:
        ColourMatchRequest(**fields).check()
    assert refusal.value.name == field


def test_a_preset_file_is_read_again_when_it_changes(tmp_path):
    path = tmp_path / "mine.toml"
    text = (pathlib.Path(__file__).parents[1] / "precompute" / "presets" / "voided_red_cotton.toml").read_text()
    write_preset(text, path)
    shipped = medium_config("voided_red_cotton")
    assert medium_config(str(path))["dye"]["weight_percent"] == shipped["dye"]["weight_percent"]
    write_preset(re.sub(r"(?m)^weight_percent = [0-9.]+", "weight_percent = 3.25", text, count=1), path)
    assert medium_config(str(path))["dye"]["weight_percent"] == 3.25
    assert not list(tmp_path.glob(".*partial"))
    with pytest.raises(ParameterError):
        medium_config(str(tmp_path / "gone.toml"))


# -- the add-on -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def shade_cache(tmp_path_factory) -> pathlib.Path:
    """One cache for the module's matches: the shade model of the tiny red cotton is made once."""
    return tmp_path_factory.mktemp("shade-cache")


@pytest.fixture
def addon(bpy, shade_cache, tmp_path, monkeypatch):
    """The development checkout registered as an add-on; its cache the module's, its recipes in tmp_path/colours."""
    from clothlight.blender import operators, preferences, registration

    cache = SimpleNamespace(folder=shade_cache)
    monkeypatch.setattr(preferences, "cache_directory", lambda context=None: str(cache.folder))
    monkeypatch.setattr(operators, "colour_directory", lambda: str(tmp_path / "colours"))
    registration.register()
    try:
        bpy.ops.wm.read_homefile(use_empty=True)
        medium = bpy.context.scene.clothlight.medium
        medium.base = "voided_red_cotton"  # Congo red in a host, the medium these matches were measured on
        for key, value in TINY_GRIDS.items():
            setattr(medium, key, value)
        yield SimpleNamespace(scene=bpy.context.scene, cache=cache, colours=tmp_path / "colours")
    finally:
        registration.unregister()
        bpy.ops.wm.read_homefile(use_empty=True)


def panel_labels(bpy, scene) -> list[str]:
    from tests.test_addon_operators import _Layout

    labels = []
    bpy.types.CLOTHLIGHT_PT_medium.draw(SimpleNamespace(layout=_Layout(labels)), SimpleNamespace(scene=scene))
    return labels


def swatch_delta_e(preset: pathlib.Path, target_hex: str, cache: pathlib.Path) -> float:
    """CIEDE2000 between ``target_hex`` and the front swatch of the recipe in ``preset`` (its [dye] and
    fibre absorption read back from the file, evaluated from the file's content as a bake reads it)."""
    from clothlight.fit.colour_match import RECIPE_DYES, ShadeModel
    from precompute.optics.medium import load_preset_config
    from precompute.tables.color import delta_e_2000, linear_rgb_to_lab, srgb_to_linear_rgb

    config, base_dir = load_preset_config(preset)
    dye = config["dye"]
    percent = dict(zip(dye["spectrum_csv"], (share * dye["weight_percent"] for share in dye["shares"])))
    recipe = [percent.get(name, 0.0) for name in RECIPE_DYES] + [config["host"]["absorption_per_mm"]]
    swatch = ShadeModel(config, base_dir, cache_dir=cache)(recipe, exact=True)
    return float(delta_e_2000(linear_rgb_to_lab(swatch), linear_rgb_to_lab(srgb_to_linear_rgb(srgb(target_hex)))))


@pytest.mark.render
@pytest.mark.slow
def test_match_colour_writes_a_recipe_of_the_colour_and_makes_it_the_baked_medium(addon, bpy):
    from precompute.bake import bake_configuration

    scene, medium = addon.scene, addon.scene.clothlight.medium
    assert medium.base == "voided_red_cotton" and medium.last_colour_match() is None
    medium.target_colour = srgb(RED_FABRIC2)
    # In background mode INVOKE_DEFAULT runs execute(): the solve in its child, to the end.
    assert bpy.ops.clothlight.match_colour("INVOKE_DEFAULT") == {"FINISHED"}
    outcome = medium.last_colour_match()
    preset = addon.colours / "voided_red_cotton_6a2717.toml"
    assert outcome.reached and outcome.written and outcome.preset == preset and preset.is_file()
    assert [p.name for p in addon.colours.iterdir()] == [preset.name]  # nothing else, no partial file
    assert preset.read_text(encoding="utf-8") == outcome.text and "Match Colour in Blender" in outcome.text
    # the recipe's swatch, read back from the file, has the colour within ΔE2000 2
    delta_e = swatch_delta_e(preset, RED_FABRIC2, addon.cache.folder)
    assert delta_e <= 2.0 and delta_e == pytest.approx(outcome.delta_e, abs=1e-3)
    assert srgb_hex(medium.matched_colour) == srgb_hex(outcome.cloth_srgb)
    # the panel's medium is the recipe: its Custom File, its values, and what a bake is asked for
    assert medium.base == "CUSTOM" and pathlib.Path(medium.custom_path) == preset
    request = medium.request()
    assert request.preset == str(preset) and request.overrides == () and request.n_around == 4
    assert medium.dye_weight_percent == pytest.approx(sum(outcome.dye_percent), rel=1e-5)
    arguments = {key: value for key, value in request.bake_arguments().items() if key != "dye_series"}
    baked = bake_configuration(**arguments).medium
    assert baked.dye.weight_percent == pytest.approx(sum(outcome.dye_percent), rel=1e-6)
    assert baked.host.absorption_per_mm == pytest.approx(outcome.fibre_absorption_per_mm, rel=1e-6)
    medium.dye_weight_percent = 0.3  # the panel's dye scales the recipe, and reaches the bake
    assert dict(medium.request().overrides) == {"dye.weight_percent": pytest.approx(0.3)}
    assert bake_configuration(**{**arguments, "overrides": medium.request().bake_arguments()["overrides"]}) \
        .medium.dye.weight_percent == pytest.approx(0.3)
    # the panel shows the match: ΔE2000, each dye's %, the fibre's absorption; nothing to apply
    labels = panel_labels(bpy, scene)
    assert f"{RED_FABRIC2} matched: ΔE2000 {outcome.delta_e:.2f}" in labels
    assert any(label.startswith("Congo red: ") and label.endswith("% of fibre weight") for label in labels)
    assert any(label.startswith("Fibre absorption: ") for label in labels)
    assert not bpy.ops.clothlight.apply_colour_match.poll()
    # shipped presets are as they were
    medium.base = "voided_red_cotton"
    assert medium.request() == preset_request("voided_red_cotton")


@pytest.mark.render
@pytest.mark.slow
def test_an_unreachable_colour_is_reported_and_written_only_when_applied_anyway(addon, bpy):
    scene, medium = addon.scene, addon.scene.clothlight.medium
    medium.target_colour = (1.0, 1.0, 1.0)  # lighter than the undyed cloth
    before = medium.request()
    assert bpy.ops.clothlight.match_colour("INVOKE_DEFAULT") == {"FINISHED"}
    outcome = medium.last_colour_match()
    assert not outcome.reached and not outcome.written and outcome.delta_e > 2.0
    assert not addon.colours.exists() or not list(addon.colours.iterdir())  # nothing written
    assert medium.base == "voided_red_cotton" and medium.request() == before  # the medium is unchanged
    labels = panel_labels(bpy, scene)
    assert f"#ffffff out of reach: nearest ΔE2000 {outcome.delta_e:.2f}" in labels
    assert bpy.ops.clothlight.apply_colour_match.poll()
    # applied anyway: the nearest recipe is written and becomes the medium
    assert bpy.ops.clothlight.apply_colour_match() == {"FINISHED"}
    preset = addon.colours / "voided_red_cotton_ffffff.toml"
    assert preset.read_text(encoding="utf-8") == outcome.text
    assert medium.base == "CUSTOM" and medium.request().preset == str(preset)
    assert medium.last_colour_match().written and not bpy.ops.clothlight.apply_colour_match.poll()


@pytest.mark.render
@pytest.mark.slow
def test_esc_cancels_a_match_and_nothing_is_written(addon, bpy, tmp_path):
    from clothlight.blender import operators, running_jobs
    from clothlight.colour_match_job import ColourMatchCancelled
    from tests.test_addon_operators import _tick, interactive_operator

    addon.cache.folder = tmp_path / "fresh-cache"  # the swatches' response renders: time to cancel
    scene, medium = addon.scene, addon.scene.clothlight.medium
    medium.target_colour = srgb(RED_FABRIC2)
    operator, context = interactive_operator(operators.CLOTHLIGHT_OT_match_colour, scene)
    assert operator._start_modal(context) == {"RUNNING_MODAL"}
    job = running_jobs.running_colour_match()
    assert job is not None and not bpy.ops.clothlight.match_colour.poll()
    assert any(label.startswith("Matching: ") for label in panel_labels(bpy, scene))
    _tick(operator, context, lambda result: job.stage.startswith("cloth response") or result != {"PASS_THROUGH"})
    assert not job.done, job.log[-3000:]
    assert operator.modal(context, SimpleNamespace(type="ESC", value="PRESS")) == {"RUNNING_MODAL"}
    assert _tick(operator, context, lambda result: result != {"PASS_THROUGH"}) == {"CANCELLED"}
    assert isinstance(job.error, ColourMatchCancelled) and job.returncode == 130, job.log[-3000:]
    assert operator.reports[-1][0] == "WARNING" and "nothing was written" in operator.reports[-1][1]
    assert running_jobs.running_colour_match() is None and medium.last_colour_match() is None
    assert medium.base == "voided_red_cotton" and not addon.colours.exists()


def test_register_and_unregister_add_and_take_back_the_colour_picker(bpy):
    from clothlight.blender import registration, running_jobs

    names = ("CLOTHLIGHT_OT_match_colour", "CLOTHLIGHT_OT_cancel_colour_match", "CLOTHLIGHT_OT_apply_colour_match")
    for _ in range(2):
        registration.register()
        try:
            assert all(hasattr(bpy.types, name) for name in names)
            settings = bpy.types.Scene.bl_rna.properties["clothlight"].fixed_type
            colour = settings.properties["medium"].fixed_type.properties["target_colour"]
            assert (colour.subtype, colour.array_length, colour.hard_min, colour.hard_max) == ("COLOR_GAMMA", 3, 0, 1)
            cancelled = []
            running_jobs.RunningColourMatch.job = SimpleNamespace(cancel=lambda: cancelled.append(True))
        finally:
            registration.unregister()
        assert cancelled == [True] and running_jobs.running_colour_match() is None  # disabling stops the match
        assert not any(hasattr(bpy.types, name) for name in names) and not hasattr(bpy.types.Scene, "clothlight")


def test_an_outcome_round_trips_as_the_scene_stores_it(tmp_path):
    outcome = ColourMatchOutcome(target_srgb=srgb(RED_FABRIC2), dyes=("congo_red.csv", "evans_blue.csv"),
                                 dye_percent=(0.112, 0.0), fibre_absorption_per_mm=0.145, delta_e=1.49, reached=True,
                                 cloth_srgb=(0.4, 0.15, 0.09), preset=tmp_path / "r.toml", written=True, text="x")
    assert ColourMatchOutcome.from_json(outcome.to_json()) == outcome
    assert outcome.recipe_text() == "Congo red 0.112 %; fibre absorption 0.145 /mm"
