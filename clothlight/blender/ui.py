"""ClothLight panels: the 3D View sidebar's "Cloth" tab, and the Material properties of a ClothLight material.

Sidebar (N panel → Cloth): ClothLight (render set-up) with sub-panels Woven Sample, Yarn Medium
(its Target Colour and Match Colour under the base medium; with Bake Settings and Grids, and Fit to
Measurement), Material and Validation, in the order of the work.  The weave and medium panels carry
their preset menus in the header, as Blender's own panels do.
"""

from __future__ import annotations

import bpy

from . import operators, running_jobs
from .closeup_operator import CLOTHLIGHT_OT_add_flyaways
from ..colour_match_job import dye_label, srgb_hex
from ..fit_job import fit_unavailable_reason
from ..jobs import bake_unavailable_reason
from ..medium_settings import CUSTOM_BASE, takes_dye_series
from ..prebaked import prebaked_tables
from ..weave import WeaveParameterError
from .garment.operator import BAKE_COMMAND
from .materials import material_mode
from .preset_menus import CLOTHLIGHT_PT_medium_presets, CLOTHLIGHT_PT_weave_presets


def _engine_ready(scene) -> bool:
    return scene.render.engine == "CYCLES" and scene.cycles.shading_system and scene.cycles.device == "CPU"


class _SidebarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Cloth"


class CLOTHLIGHT_PT_main(_SidebarPanel, bpy.types.Panel):
    bl_label = "ClothLight"
    bl_idname = "CLOTHLIGHT_PT_main"

    def draw(self, context):
        layout = self.layout
        if _engine_ready(context.scene):
            layout.label(text="Cycles, OSL on the CPU", icon="CHECKMARK")
        else:
            layout.label(text="Sun mode and clear yarns render in Cycles with OSL on the CPU", icon="INFO")
        layout.operator("clothlight.setup_render", icon="SHADING_RENDERED")


class CLOTHLIGHT_PT_sample(_SidebarPanel, bpy.types.Panel):
    bl_label = "Woven Sample"
    bl_parent_id = "CLOTHLIGHT_PT_main"

    def draw_header_preset(self, _context):
        CLOTHLIGHT_PT_weave_presets.draw_panel_header(self.layout)

    def draw(self, context):
        weave = context.scene.clothlight.weave
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(weave, "pattern")
        if weave.pattern == "CUSTOM":
            layout.prop(weave, "custom_draft")
        elif weave.pattern == "WIF":
            layout.prop(weave, "wif_path")
        col = layout.column(align=True)
        col.prop(weave, "warp_count")
        col.prop(weave, "weft_count")
        layout.prop(weave, "spacing_mm")
        layout.prop(weave, "cross_section")
        col = layout.column(align=True)
        if weave.cross_section == "ROUND":
            col.prop(weave, "yarn_radius_mm")
        else:
            col.prop(weave, "half_width_mm")
            col.prop(weave, "half_thickness_mm")
        layout.prop(weave, "section_relaxation")
        layout.prop(weave, "auto_crimp")
        if not weave.auto_crimp:
            col = layout.column(align=True)
            col.prop(weave, "crimp_warp_mm")
            col.prop(weave, "crimp_weft_mm")
        col = layout.column(align=True)
        col.prop(weave, "segments_per_crossing")
        col.prop(weave, "segments_around")
        layout.prop(weave, "real_world_size")
        rebuild = operators.is_sample(context.active_object)
        layout.operator("clothlight.build_sample", text="Rebuild Sample" if rebuild else "Build Sample",
                        icon="FILE_REFRESH" if rebuild else "MESH_GRID")


class CLOTHLIGHT_PT_closeup(_SidebarPanel, bpy.types.Panel):
    bl_label = "Close-Up"
    bl_parent_id = "CLOTHLIGHT_PT_sample"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        weave = context.scene.clothlight.weave
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(weave, "use_plies")
        if weave.use_plies:
            try:
                plies, twist = weave.medium_plies()
            except WeaveParameterError as error:
                layout.label(text=str(error), icon="ERROR")
            else:
                noun = "ply" if plies == 1 else "plies"
                layout.label(text=f"{plies} {noun} at {twist:g}° ({_medium_name(context.scene.clothlight.medium)})",
                             icon="INFO")
        col = layout.column(align=True)
        col.prop(weave, "spacing_jitter")
        col.prop(weave, "height_jitter")
        col.prop(weave, "ply_radius_jitter")
        layout.prop(weave, "irregularity_seed")
        col = layout.column(align=True)
        col.prop(weave, "flyaway_density_per_mm")
        col.prop(weave, "flyaway_length_mm")
        col.prop(weave, "flyaway_curl_per_mm")
        if CLOTHLIGHT_OT_add_flyaways.is_registered:
            layout.operator(CLOTHLIGHT_OT_add_flyaways.bl_idname, icon="CURVES")


def _medium_name(medium) -> str:
    """The Base Medium as the panels name it: a shipped preset's name, or the Custom File's name."""
    if medium.base != CUSTOM_BASE:
        return medium.base
    return bpy.path.display_name_from_filepath(medium.custom_path) or "no custom file"


def _draw_colour_match(layout, medium) -> None:
    """Target Colour and Match Colour (its progress while it runs), then the last match: how near it came,
    the recipe, the cloth's colour, and Apply Nearest Recipe for a colour out of reach."""
    column = layout.column(align=True)
    column.prop(medium, "target_colour")
    job = running_jobs.running_colour_match()
    if job is not None:
        row = column.row(align=True)
        row.progress(factor=job.progress, type="BAR", text=f"Matching: {job.progress:.0%}")
        row.operator("clothlight.cancel_colour_match", text="", icon="CANCEL")
        if job.stage:
            column.label(text=job.stage)
    else:
        column.operator("clothlight.match_colour", icon="EYEDROPPER")
    layout.prop(medium, "bake_after_match")
    outcome = medium.last_colour_match()
    if outcome is None:
        return
    column = layout.column(align=True)
    if outcome.reached:
        column.label(text=f"{srgb_hex(outcome.target_srgb)} matched: ΔE2000 {outcome.delta_e:.2f}", icon="CHECKMARK")
    else:
        column.label(text=f"{srgb_hex(outcome.target_srgb)} out of reach: nearest ΔE2000 {outcome.delta_e:.2f}",
                     icon="ERROR")
    for name, percent in zip(outcome.dyes, outcome.dye_percent):
        column.label(text=f"{dye_label(name)}: {percent:.3g} % of fibre weight")
    column.label(text=f"Fibre absorption: {outcome.fibre_absorption_per_mm:.3g} /mm")
    row = column.row(align=True)
    row.enabled = False
    row.prop(medium, "matched_colour")
    if not outcome.written:
        column.operator("clothlight.apply_colour_match", icon="IMPORT")
    else:
        column.label(text=f"Preset: {outcome.preset.name}", icon="FILE_TEXT")


class CLOTHLIGHT_PT_medium(_SidebarPanel, bpy.types.Panel):
    bl_label = "Yarn Medium"
    bl_parent_id = "CLOTHLIGHT_PT_main"

    def draw_header_preset(self, _context):
        CLOTHLIGHT_PT_medium_presets.draw_panel_header(self.layout)

    def draw(self, context):
        medium = context.scene.clothlight.medium
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(medium, "base")
        if medium.base == CUSTOM_BASE:
            layout.prop(medium, "custom_path")
        problem = medium.custom_problem()
        if problem:
            layout.label(text=problem, icon="ERROR")
        _draw_colour_match(layout, medium)
        if problem:
            return
        keys = medium.exposed_keys()
        col = layout.column(align=True)
        for prop in ("dye_weight_percent", "particle_diameter_nm", "particle_volume_fraction", "yarn_radius_mm"):
            if prop in keys:
                col.prop(medium, prop)
        fitted = medium.extra_overrides_text()
        if fitted:
            row = layout.row(align=True)
            row.label(text=f"Fitted: {fitted}", icon="DRIVER")
            row.operator("clothlight.clear_fitted_values", text="", icon="X")
        if "dye_weight_percent" not in keys:
            layout.label(text="This medium is undyed", icon="INFO")
        elif not takes_dye_series(medium.base_config()):
            layout.label(text="Dye Range: not for dye in random fibres (a dye change re-simulates)", icon="INFO")
        else:
            row = layout.row(heading="Dye Range")
            row.prop(medium, "use_dye_series", text="")
            sub = row.row(align=True)
            sub.active = medium.use_dye_series
            sub.prop(medium, "dye_series_low", text="")
            sub.prop(medium, "dye_series_high", text="")
            if medium.use_dye_series and not (medium.dye_series_low <= medium.dye_weight_percent
                                              <= medium.dye_series_high):
                layout.label(text="The dye lies outside the range", icon="ERROR")

        job = running_jobs.running_bake()
        if job is not None:
            row = layout.row(align=True)
            row.progress(factor=job.progress, type="BAR", text=f"Baking: {job.progress:.0%}")
            row.operator("clothlight.cancel_bake", text="", icon="CANCEL")
        else:
            reason = bake_unavailable_reason()
            layout.operator("clothlight.bake_tables", icon="RENDER_STILL")
            if reason:
                layout.label(text="Bake unavailable here: pre-baked presets only", icon="ERROR")
        layout.prop(medium, "tables_dir")
        if medium.tables_dir and medium.tables_request and medium.tables_request != medium.request().to_json():
            layout.label(text="Settings changed since the bake", icon="ERROR")
        elif not medium.tables_dir and prebaked_tables(medium.request()) is not None:
            layout.label(text="Shipped tables for these settings", icon="CHECKMARK")


class CLOTHLIGHT_PT_bake_settings(_SidebarPanel, bpy.types.Panel):
    bl_label = "Bake Settings"
    bl_parent_id = "CLOTHLIGHT_PT_medium"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        medium = context.scene.clothlight.medium
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(medium, "budget")
        layout.prop(medium, "target_error" if medium.budget == "TARGET_ERROR" else "paths_per_cell")
        layout.prop(medium, "seed")


class CLOTHLIGHT_PT_bake_grids(_SidebarPanel, bpy.types.Panel):
    bl_label = "Grids"
    bl_parent_id = "CLOTHLIGHT_PT_bake_settings"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        medium = context.scene.clothlight.medium
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        col = layout.column(align=True)
        for prop in ("n_around", "n_along", "angular_resolution", "incidence_resolution"):
            col.prop(medium, prop)


class CLOTHLIGHT_PT_medium_fit(_SidebarPanel, bpy.types.Panel):
    """Fit the medium above to a measured cloth BRDF (python -m clothlight.fit, docs/fitting.md)."""

    bl_label = "Fit to Measurement"
    bl_parent_id = "CLOTHLIGHT_PT_medium"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        fit = context.scene.clothlight.fit
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(fit, "measured_path")
        column = layout.column(heading="Free Parameters", align=True)
        column.prop(fit, "free")
        if [name for name in fit.free_names() if not name.startswith("specular_")] == ["dye_weight_percent"]:
            layout.prop(fit, "dye_series")
        column = layout.column(align=True)
        column.prop(fit, "budget")
        column.prop(fit, "time_limit")
        layout.prop(fit, "target_ratios")
        layout.prop(fit, "max_back_front")
        layout.prop(fit, "seed")
        layout.prop(fit, "out_dir")
        layout.prop(fit, "load_result")
        job = running_jobs.running_fit()
        if job is not None:
            row = layout.row(align=True)
            row.progress(factor=job.progress, type="BAR", text=f"Fitting: {job.progress:.0%}")
            row.operator("clothlight.cancel_fit", text="", icon="CANCEL")
            if job.stage:
                layout.label(text=job.stage)
        else:
            layout.operator("clothlight.fit_medium", icon="FCURVE")
            reason = fit_unavailable_reason()
            if reason:
                layout.label(text=reason, icon="ERROR")
        last = fit.last()
        if last is not None:
            column = layout.column(align=True)
            held = "" if last.get("held_out_rms") is None else f", held out {last['held_out_rms']:.3g}"
            column.label(text=f"Last fit: relative RMS {last['relative_rms']:.3g}{held}", icon="FILE_TEXT")
            column.label(text=last["preset"])
            column.operator("clothlight.load_fit", icon="IMPORT")


def _draw_material_info(layout, material) -> None:
    info = operators.material_summary(material)
    if info is None:
        return
    col = layout.column(align=True)
    col.label(text=f"{material.name}: {info['mode']} lighting", icon="MATERIAL")
    if "tables" in info:
        if info.get("missing"):
            col.label(text=f"Tables missing: {info['tables']}", icon="ERROR")
        else:
            col.label(text=f"Medium: {info.get('medium') or '—'}")
            ratios = info.get("table1")
            if ratios:
                col.label(text=f"B/R {ratios['B/R']:.3g}, G/R {ratios['G/R']:.3g} at normal incidence and view")
    if "sun" in info:
        col.label(text=f"Follows the sun '{info['sun']}'", icon="LIGHT_SUN")


class CLOTHLIGHT_PT_material(_SidebarPanel, bpy.types.Panel):
    bl_label = "Material"
    bl_parent_id = "CLOTHLIGHT_PT_main"

    def draw(self, context):
        settings = context.scene.clothlight
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(settings, "material_mode")
        if settings.material_mode == "SUN":
            layout.prop(settings, "sun")
        layout.operator("clothlight.apply_material", icon="MATERIAL")
        obj = context.active_object
        if obj is not None and obj.active_material is not None:
            _draw_material_info(layout, obj.active_material)


class CLOTHLIGHT_PT_garment(_SidebarPanel, bpy.types.Panel):
    bl_label = "Garment"
    bl_parent_id = "CLOTHLIGHT_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.clothlight
        layout = self.layout
        layout.label(text="Cloth BSDF on any mesh (paper §7)")
        job = running_jobs.running_cloth_bake()
        if job is not None:
            row = layout.row(align=True)
            row.progress(factor=job.progress, type="BAR", text=f"Baking cloth: {job.progress:.0%}")
            row.operator("clothlight.cancel_cloth_bake", text="", icon="CANCEL")
            if job.stage:
                layout.label(text=job.stage)
        else:
            layout.operator("clothlight.bake_cloth", icon="RENDER_STILL")
        layout.prop(settings, "garment_threads_per_cm")
        layout.prop(settings, "cloth_tables_dir")
        layout.prop(settings, "garment_open_weave")
        layout.prop(settings, "garment_transmission")
        layout.prop(settings, "garment_yarn_detail")
        if settings.garment_yarn_detail:
            layout.prop(settings, "garment_weave_repeats")
        layout.operator("clothlight.apply_garment_material", icon="MOD_CLOTH")
        column = layout.column(align=True)
        column.label(text="Or from a terminal:", icon="CONSOLE")
        column.label(text=BAKE_COMMAND)


class CLOTHLIGHT_PT_validation(_SidebarPanel, bpy.types.Panel):
    bl_label = "Validation"
    bl_parent_id = "CLOTHLIGHT_PT_main"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.label(text="Virtual gonioreflectometer (paper §4)")
        layout.operator("clothlight.validate", icon="GRAPH")
        folder = context.window_manager.get("clothlight_validation_dir")
        if folder:
            layout.label(text=f"Last report: {folder}", icon="FILE_TEXT")


class CLOTHLIGHT_PT_material_properties(bpy.types.Panel):
    """The ClothLight section of the Material properties, for ClothLight materials."""

    bl_label = "ClothLight"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        material = context.material
        return material is not None and material_mode(material) is not None

    def draw(self, context):
        settings = context.scene.clothlight
        layout = self.layout
        _draw_material_info(layout, context.material)
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(settings, "material_mode")
        if settings.material_mode == "SUN":
            layout.prop(settings, "sun")
        layout.prop(settings.medium, "base")
        layout.operator("clothlight.apply_material", text="Re-Apply Material", icon="FILE_REFRESH")


CLASSES = (
    CLOTHLIGHT_PT_main,
    CLOTHLIGHT_PT_sample,
    CLOTHLIGHT_PT_closeup,
    CLOTHLIGHT_PT_medium,
    CLOTHLIGHT_PT_bake_settings,
    CLOTHLIGHT_PT_bake_grids,
    CLOTHLIGHT_PT_medium_fit,
    CLOTHLIGHT_PT_material,
    CLOTHLIGHT_PT_garment,
    CLOTHLIGHT_PT_validation,
    CLOTHLIGHT_PT_material_properties,
)
