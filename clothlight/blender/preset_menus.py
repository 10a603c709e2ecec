"""Weave and medium presets through Blender's preset system.

Shipped presets are Python files in ``clothlight/blender/presets/<subdir>/`` (registered with
:func:`bpy.utils.register_preset_path`, read-only because they sit in the extension); presets a
user adds with the ➕ button go where Blender keeps every user preset
(``<user scripts>/presets/<subdir>/``).  A medium preset sets the base medium first, which loads
the shipped TOML preset, then the values saved with it.
"""

from __future__ import annotations

import pathlib

import bpy
from bl_operators.presets import AddPresetBase
from bl_ui.utils import PresetPanel

#: The folder holding ``presets/``.
PRESET_ROOT = pathlib.Path(__file__).resolve().parent
WEAVE_SUBDIR = "clothlight_weave"
MEDIUM_SUBDIR = "clothlight_medium"

WEAVE_VALUES = [f"weave.{name}" for name in (
    "pattern", "custom_draft", "wif_path", "warp_count", "weft_count", "spacing_mm", "cross_section",
    "yarn_radius_mm", "half_width_mm", "half_thickness_mm", "section_relaxation", "auto_crimp", "crimp_warp_mm",
    "crimp_weft_mm", "segments_per_crossing", "segments_around", "real_world_size", "use_plies", "spacing_jitter",
    "height_jitter", "ply_radius_jitter", "irregularity_seed", "flyaway_density_per_mm", "flyaway_length_mm",
    "flyaway_curl_per_mm")]
# "base" first (after the Custom File it may name): setting it loads the TOML preset, the saved values
# then override it (a fit's values the panel does not show among them).
MEDIUM_VALUES = [f"medium.{name}" for name in (
    "custom_path", "base", "dye_weight_percent", "particle_diameter_nm", "particle_volume_fraction", "yarn_radius_mm",
    "fitted_overrides",
    "budget", "target_error", "paths_per_cell", "seed", "n_around", "n_along", "angular_resolution",
    "incidence_resolution")]


class CLOTHLIGHT_PT_weave_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Weave Presets"
    preset_subdir = WEAVE_SUBDIR
    preset_operator = "script.execute_preset"
    preset_add_operator = "clothlight.weave_preset_add"


class CLOTHLIGHT_PT_medium_presets(PresetPanel, bpy.types.Panel):
    bl_label = "Medium Presets"
    preset_subdir = MEDIUM_SUBDIR
    preset_operator = "script.execute_preset"
    preset_add_operator = "clothlight.medium_preset_add"


class CLOTHLIGHT_OT_weave_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a ClothLight weave preset"""

    bl_idname = "clothlight.weave_preset_add"
    bl_label = "Add Weave Preset"
    preset_menu = "CLOTHLIGHT_PT_weave_presets"
    preset_subdir = WEAVE_SUBDIR
    preset_defines = ["weave = bpy.context.scene.clothlight.weave"]
    preset_values = WEAVE_VALUES


class CLOTHLIGHT_OT_medium_preset_add(AddPresetBase, bpy.types.Operator):
    """Add or remove a ClothLight medium preset (the medium and its bake settings)"""

    bl_idname = "clothlight.medium_preset_add"
    bl_label = "Add Medium Preset"
    preset_menu = "CLOTHLIGHT_PT_medium_presets"
    preset_subdir = MEDIUM_SUBDIR
    preset_defines = ["medium = bpy.context.scene.clothlight.medium"]
    preset_values = MEDIUM_VALUES


CLASSES = (CLOTHLIGHT_PT_weave_presets, CLOTHLIGHT_PT_medium_presets, CLOTHLIGHT_OT_weave_preset_add,
           CLOTHLIGHT_OT_medium_preset_add)
