"""Operators of the ClothLight add-on: Build Sample, Bake Tables, Bake Cloth, Fit to Measurement, Match Colour,
Apply Material, Set Up Cycles.

Each reports errors through Blender's report system (bad input names the parameter; unexpected
failures print their traceback to the console and report one line).  Build Sample and Apply
Material edit the scene and are undoable; neither leaves unused data blocks behind.  Bake Tables,
Bake Cloth, Fit to Measurement and Match Colour run in a child process (:mod:`clothlight.jobs`,
:mod:`clothlight.fit_job`, :mod:`clothlight.colour_match_job`):
in the interface they are modal, with a progress bar in the status bar and Esc (or the panel's
Cancel button) to stop them; in background mode (``blender -b``, or Blender as a Python module)
``execute()`` runs the same job to the end.  A fit's result is loaded into the medium settings
(Load Fit, or at once with the fit settings' Load Result); a matched colour's recipe is written as a
preset file in the user folder (:func:`colour_directory`) and becomes the medium's Custom File (an
unreachable colour's nearest recipe only when applied anyway).  The validation operator,
``clothlight.validate``, lives in :mod:`.validation.operator`.
"""

from __future__ import annotations

import hashlib
import json
import pathlib
import sys
import traceback
from collections.abc import Callable

import bpy

from . import preferences
from ..colour_match_job import (ColourMatchJob, ColourMatchOutcome, ColourMatchRequest, recipe_file_name, srgb_hex,
                                write_preset)
from ..fit_job import FitJob, fit_unavailable_reason
from ..jobs import (BakeCancelled, BakeFailed, BakeJob, ClothBakeJob, JobCancelled, JobFailed,
                    bake_unavailable_reason)
from ..medium_settings import BakeRequest, is_preset_file, preset_request
from .materials import (
    GENERAL_MODE,
    SUN_MODE,
    build_yarn_material,
    material_mode,
    needs_osl,
    read_other_tables,
    remove_yarn_material,
    sync_sun,
    yarn_tables_folder,
)
from ..mesh_attributes import CLOTH_NORMAL, YARN_TANGENT
from ..prebaked import tables_for_request
from .garment.operator import NAME_SEPARATOR, apply_to_meshes, report_applied
from .properties import ParameterError, millimetre_scale
from . import running_jobs
from .running_jobs import RunningBake, RunningClothBake, RunningColourMatch, RunningFit
from .render_setup import use_cycles, use_cycles_osl_on_cpu
from .sample_object import DEFAULT_NAME, WEAVE_PROPERTY, build_sample_object
from .sun_link import SUN_PROPERTY
from ..weave import WeaveParameterError
from ..yarn_tables import yarn_tables_from_bake


def _unexpected(operator, error: Exception, what: str):
    """Report an unexpected failure in one line; its traceback goes to the console."""
    traceback.print_exception(error, file=sys.stderr)
    operator.report({"ERROR"}, f"{what} failed: {type(error).__name__}: {error} (details in the console)")
    return {"CANCELLED"}


# -- tables -------------------------------------------------------------------------------------


def tables_for(medium) -> tuple[pathlib.Path, str | None]:
    """The table folder Apply Material uses for ``medium`` settings, and a warning (or None):
    :func:`.prebaked.tables_for_request` with the panel's values."""
    return tables_for_request(medium.request(),
                              tables_dir=bpy.path.abspath(medium.tables_dir) if medium.tables_dir else None,
                              tables_request=medium.tables_request, cache_dir=preferences.cache_directory(),
                              bake_unavailable=bake_unavailable_reason())


def _short_hash(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:6]


def material_name(medium, folder: pathlib.Path, mode: str) -> str:
    """One material per set of tables and mode, so re-applying updates it everywhere it is used:
    named by the preset (and a hash of the changes, if any) the tables were baked from, or for a
    folder chosen by hand, by the medium its summary names."""
    if medium.tables_dir and not medium.tables_request:
        try:
            label = json.loads((folder / "summary.json").read_text())["medium"]["name"]
        except (OSError, ValueError, KeyError, TypeError):
            label = folder.name
        label = f"{label} {_short_hash(str(folder))}"
    else:
        request = BakeRequest.from_json(medium.tables_request) if medium.tables_dir else medium.request()
        label = pathlib.Path(request.preset).stem if is_preset_file(request.preset) else request.preset
        label = bpy.path.display_name(label)
        if request != preset_request(request.preset):
            label += " " + _short_hash(request.to_json())
    return f"ClothLight {label}" + (" Sun" if mode == SUN_MODE else "")


# -- Build Sample --------------------------------------------------------------------------------


def is_sample(obj) -> bool:
    return obj is not None and obj.type == "MESH" and WEAVE_PROPERTY in obj


def _free_name(base: str) -> str:
    if base not in bpy.data.objects:
        return base
    index = 1
    while f"{base}.{index:03d}" in bpy.data.objects:
        index += 1
    return f"{base}.{index:03d}"


class CLOTHLIGHT_OT_build_sample(bpy.types.Operator):
    """Build a woven sample from the weave settings (rebuilds the active sample in place, keeping its material)"""

    bl_idname = "clothlight.build_sample"
    bl_label = "Build Sample"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        return context.scene is not None

    def execute(self, context):
        settings = context.scene.clothlight
        weave = settings.weave
        try:
            params = weave.parameters()
        except WeaveParameterError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        active = context.active_object
        rebuild = active if is_sample(active) and active.name in context.view_layer.objects else None
        try:
            obj = build_sample_object(params, name=rebuild.name if rebuild else _free_name(DEFAULT_NAME),
                                      collection=None if rebuild else context.collection)
        except WeaveParameterError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        except Exception as error:  # noqa: BLE001
            return _unexpected(self, error, "Build Sample")
        if rebuild is None:
            obj.location = context.scene.cursor.location
            scale = millimetre_scale(context.scene) if weave.real_world_size else 1.0
            obj.scale = (scale, scale, scale)
            for selected in context.selected_objects:
                selected.select_set(False)
            obj.select_set(True)
            context.view_layer.objects.active = obj
        width, height = params.sample_size_mm
        self.report({"INFO"}, f"{obj.name}: {params.warp_count} ends × {params.weft_count} picks, "
                              f"{width:g} × {height:g} mm, {len(obj.data.polygons)} triangles")
        medium_radius = settings.medium.yarn_radius_mm
        if abs(weave.yarn_thickness_mm - medium_radius) > 1e-4 or weave.cross_section != "ROUND":
            self.report({"WARNING"}, f"The yarn tables are baked for round yarns of radius {medium_radius:.3g} mm; "
                                     "this sample's yarns differ")
        return {"FINISHED"}


# -- Apply Material ------------------------------------------------------------------------------


def scene_sun(context, settings):
    if settings.sun is not None:
        return settings.sun
    return next((obj for obj in context.scene.objects if obj.type == "LIGHT" and obj.data.type == "SUN"), None)


def _targets(context):
    objects = [obj for obj in context.selected_objects if obj.type == "MESH"]
    if context.active_object is not None and context.active_object.type == "MESH" \
            and context.active_object not in objects:
        objects.append(context.active_object)
    return objects


def remove_if_unused(material) -> None:
    """Delete a ClothLight material nothing uses any more (no orphan data blocks)."""
    if material is not None and "clothlight_shader" in material and material.users == 0:
        remove_yarn_material(material)


class CLOTHLIGHT_OT_apply_material(bpy.types.Operator):
    """Give the selected ClothLight samples the yarn material made from the baked tables of the medium settings"""

    bl_idname = "clothlight.apply_material"
    bl_label = "Apply Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not any(CLOTH_NORMAL in obj.data.attributes for obj in _targets(context)):
            cls.poll_message_set("Select a ClothLight sample (a mesh with the yarn attributes)")
            return False
        return True

    def execute(self, context):
        settings = context.scene.clothlight
        medium = settings.medium
        mode = SUN_MODE if settings.material_mode == "SUN" else GENERAL_MODE
        targets = [obj for obj in _targets(context)
                   if CLOTH_NORMAL in obj.data.attributes and YARN_TANGENT in obj.data.attributes]
        if not targets:
            self.report({"ERROR"}, "No ClothLight sample selected: the yarn material needs the "
                                   f"'{CLOTH_NORMAL}' and '{YARN_TANGENT}' attributes of a built sample")
            return {"CANCELLED"}
        sun = scene_sun(context, settings) if mode == SUN_MODE else None
        if mode == SUN_MODE and sun is None:
            self.report({"ERROR"}, "Sun mode needs a sun lamp: add one or pick it in the Material panel")
            return {"CANCELLED"}
        try:
            folder, warning = tables_for(medium)
            tables = yarn_tables_from_bake(folder)
            name = material_name(medium, folder, mode)
            # Script nodes compile only when the scene renders with Cycles and OSL.
            render_note = (use_cycles_osl_on_cpu if needs_osl(tables, mode) else use_cycles)(context.scene)
            material = build_yarn_material(tables, name, mode=mode)
        except (LookupError, FileNotFoundError, ValueError, ParameterError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        except Exception as error:  # noqa: BLE001
            return _unexpected(self, error, "Apply Material")
        if sun is not None:
            material[SUN_PROPERTY] = sun
            sync_sun(material, sun)
        elif SUN_PROPERTY in material:
            del material[SUN_PROPERTY]
        replaced = set()
        for obj in targets:
            slots = obj.data.materials
            if not len(slots):
                slots.append(material)
            for index in range(len(slots)):
                if slots[index] is not material:
                    replaced.add(slots[index])
                    slots[index] = material
        for old in replaced:
            remove_if_unused(old)
        if warning:
            self.report({"WARNING"}, warning)
        if "already set" not in render_note:
            self.report({"INFO"}, render_note.split(". ")[0])
        self.report({"INFO"}, f"{material.name} on {len(targets)} object(s), tables {folder}")
        return {"FINISHED"}


# -- Bake Tables ---------------------------------------------------------------------------------


def _job_for(context, request: BakeRequest) -> BakeJob:
    prefs = preferences.preferences(context)
    threads = prefs.threads if prefs is not None and prefs.threads > 0 else None
    return BakeJob(request, cache_dir=preferences.cache_directory(context), threads=threads,
                   scheduler=prefs.scheduler.strip() if prefs is not None else None,
                   numba_cache_dir=preferences.numba_cache_directory(),
                   bytecode_cache_dir=preferences.bytecode_cache_directory())


def _ratios_text(outcome) -> str:
    ratios = outcome.table1_ratios
    if not ratios:
        return ""
    return (f"; B/R {ratios['B/R']:.3g}, G/R {ratios['G/R']:.3g} at normal incidence and view "
            "(the paper's real red cotton: 0.08, 0.011)")


def _redraw_panels(context) -> None:
    """Redraw where the bake's progress shows (panels do not redraw on their own)."""
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type in {"VIEW_3D", "PROPERTIES"}:
                area.tag_redraw()


def _recolour_materials(medium, request: BakeRequest, folder: pathlib.Path) -> int:
    """After a bake of a dye series that changed only the dye: point the yarn materials that read the
    previous tables at the new ones (the dye recolours them live).  Returns how many."""
    if request.dye_series is None or not (medium.tables_dir and medium.tables_request):
        return 0
    try:
        if not request.same_but_dye(BakeRequest.from_json(medium.tables_request)):
            return 0
    except (ValueError, TypeError, KeyError):
        return 0
    previous = str(pathlib.Path(bpy.path.abspath(medium.tables_dir)))
    readers = [m for m in bpy.data.materials if m.node_tree is not None and yarn_tables_folder(m) == previous]
    if readers:
        tables = yarn_tables_from_bake(folder)
        for material in readers:
            read_other_tables(material, tables)
    return len(readers)


# -- a child job in the interface: timer, status bar, Esc ---------------------------------------


def _start_job_modal(operator, context, holder, job, what: str) -> set:
    """Start ``job``'s child, make it ``holder``'s running job and poll it on a timer (``operator.modal``)."""
    try:
        job.start()
    except (JobFailed, OSError) as error:
        operator.report({"ERROR"}, f"{what} could not start: {error}")
        return {"CANCELLED"}
    holder.job, holder.scene_name = job, context.scene.name
    operator._workspace = context.workspace
    wm = context.window_manager
    operator._timer = wm.event_timer_add(0.2, window=context.window)
    wm.modal_handler_add(operator)
    operator._show(context)
    return {"RUNNING_MODAL"}


def _show_job(operator, context, job, text) -> None:
    """``job``'s progress bar in the status bar, labelled ``text()`` (asked at every redraw), with Esc."""

    def draw_status(header, _context):
        row = header.layout.row(align=True)
        row.progress(factor=job.progress, type="BAR", text=text())
        row.label(text="Esc to cancel", icon="EVENT_ESC")

    operator._workspace.status_text_set(draw_status)
    _redraw_panels(context)


def _modal_job(operator, context, event, holder) -> set:
    """One event of a running child job: Esc asks it to stop, a timer tick polls it; when it is over,
    the status bar is cleared and ``operator._finish`` reports."""
    job = holder.job
    if event.type == "ESC" and event.value == "PRESS":
        job.cancel()
        return {"RUNNING_MODAL"}
    if event.type != "TIMER":  # any timer's tick will do: polling the child is cheap
        return {"PASS_THROUGH"}
    if not job.poll():
        operator._show(context)
        return {"PASS_THROUGH"}
    context.window_manager.event_timer_remove(operator._timer)
    operator._workspace.status_text_set(None)
    holder.job = None
    scene = bpy.data.scenes.get(holder.scene_name) or context.scene
    result = operator._finish(scene, job)
    _redraw_panels(context)
    return result


def _end_job(operator, holder) -> None:
    """Blender ends a modal operator (file load, quit): stop its child too."""
    if holder.job is not None:
        holder.job.cancel()
        holder.job = None
    operator._workspace.status_text_set(None)


class _ChildJobOperator:
    """What an operator running a child job (Bake Tables, Fit to Measurement) does around its own
    ``_start(context)`` (the job, or None after a report) and ``_finish(scene, job)``: in background
    mode it waits, printing the progress; in the interface it polls the child on a timer, with a
    progress bar in the status bar that ``_status(job)`` labels, and Esc cancels.  ``_running`` holds
    the one running job, ``_what`` names it; none starts while one runs or where
    ``_unavailable_reason()`` says why not."""

    _running: type
    _what: str
    _unavailable_reason: Callable[[], str | None]  # why the job cannot run here (a missing library), or None

    @classmethod
    def poll(cls, context):
        if cls._running.job is not None:
            cls.poll_message_set(f"A {cls._what.lower()} is running")
            return False
        reason = cls._unavailable_reason()
        if reason:
            cls.poll_message_set(reason)
            return False
        return context.scene is not None

    def execute(self, context):
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        shown = [-1]

        def progress(fraction):
            percent = int(fraction * 100)
            if percent // 10 != shown[0] // 10:
                shown[0] = percent
                print(f"{self._status(job)}: {percent} %", flush=True)

        try:
            job.wait(on_progress=progress)
        except (JobFailed, JobCancelled):
            pass  # job.error says which; _finish reports it
        return self._finish(context.scene, job)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        return self._start_modal(context)

    def _start_modal(self, context):
        """Start the child and the timer that polls it; ``modal()`` takes it from there."""
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        return _start_job_modal(self, context, self._running, job, self._what)

    def _show(self, context) -> None:
        job = self._running.job

        def text() -> str:
            return f"Cancelling: {job.progress:.0%}" if job.cancelling else f"{self._status(job)}: {job.progress:.0%}"

        _show_job(self, context, job, text)

    def modal(self, context, event):
        return _modal_job(self, context, event, self._running)

    def cancel(self, context):
        _end_job(self, self._running)


class _CancelJobOperator:
    """Cancel the one running job that ``_running`` holds (its Cancel button)."""

    _running: type
    bl_options = {"INTERNAL"}

    @classmethod
    def poll(cls, context):
        return cls._running.job is not None

    def execute(self, context):
        self._running.job.cancel()
        return {"FINISHED"}


class CLOTHLIGHT_OT_bake_tables(_ChildJobOperator, bpy.types.Operator):
    """Bake the yarn's BRDF tables from the medium settings (Monte-Carlo light transport in a background
    process; cached, so an unchanged medium is instant). Esc cancels"""

    bl_idname = "clothlight.bake_tables"
    bl_label = "Bake Tables"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context) -> BakeJob | None:
        try:
            request = context.scene.clothlight.medium.request()
            job = _job_for(context, request)
        except (ParameterError, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return None
        return job

    def _finish(self, scene, job: BakeJob):
        if isinstance(job.error, BakeCancelled):
            self.report({"WARNING"}, str(job.error))
            return {"CANCELLED"}
        if isinstance(job.error, BakeFailed):
            if not job.error.bad_input and job.error.log:
                print(job.error.log, file=sys.stderr)
            self.report({"ERROR"}, f"Bake failed: {job.error}")
            return {"CANCELLED"}
        outcome = job.outcome
        medium = scene.clothlight.medium
        recoloured = _recolour_materials(medium, job.request, outcome.folder)
        medium.tables_dir = str(outcome.folder)
        medium.tables_request = job.request.to_json()
        how = "found in the cache" if outcome.cache_hit else f"baked in {outcome.seconds:.0f} s"
        if recoloured:
            how += f", {recoloured} material{'s' if recoloured > 1 else ''} recoloured"
        self.report({"INFO"}, f"Tables {how}: {outcome.folder}{_ratios_text(outcome)}")
        return {"FINISHED"}

    _running = RunningBake
    _what = "Bake"
    _unavailable_reason = staticmethod(bake_unavailable_reason)

    def _status(self, job) -> str:
        return "Baking ClothLight tables"


class CLOTHLIGHT_OT_cancel_bake(_CancelJobOperator, bpy.types.Operator):
    """Stop the running bake; no table is written"""

    bl_idname = "clothlight.cancel_bake"
    bl_label = "Cancel Bake"
    _running = RunningBake


# -- Bake Cloth ----------------------------------------------------------------------------------


class CLOTHLIGHT_OT_bake_cloth(_ChildJobOperator, bpy.types.Operator):
    """Bake the garment's cloth BSDF from the medium's yarn tables (the woven sample measured in a virtual
    gonioreflectometer, in a background process; cached). Garment Material then uses it. Esc cancels"""

    bl_idname = "clothlight.bake_cloth"
    bl_label = "Bake Cloth"
    bl_options = {"REGISTER", "UNDO"}

    apply_to: bpy.props.StringProperty(
        name="Apply To", options={"HIDDEN", "SKIP_SAVE"},
        description="Meshes to give the garment material once the cloth is baked (Apply Garment Material), "
                    "one name a line")

    def _start(self, context) -> ClothBakeJob | None:
        try:
            folder, warning = tables_for(context.scene.clothlight.medium)
        except LookupError as error:
            self.report({"ERROR"}, str(error))
            return None
        if warning:
            self.report({"WARNING"}, warning)
        return ClothBakeJob(folder, cache_dir=preferences.cache_directory(context), blender=bpy.app.binary_path,
                            settings={"threads_per_cm": context.scene.clothlight.garment_threads_per_cm},
                            numba_cache_dir=preferences.numba_cache_directory(),
                            bytecode_cache_dir=preferences.bytecode_cache_directory())

    def _finish(self, scene, job: ClothBakeJob):
        if isinstance(job.error, JobCancelled):
            self.report({"WARNING"}, str(job.error))
            return {"CANCELLED"}
        if isinstance(job.error, JobFailed):
            if not job.error.bad_input and job.error.log:
                print(job.error.log, file=sys.stderr)
            self.report({"ERROR"}, f"Cloth bake failed: {job.error}")
            return {"CANCELLED"}
        scene.clothlight.cloth_tables_dir = str(job.outcome.folder)
        how = "measured" if job.outcome.rendered else "found in the cache"
        self.report({"INFO"}, f"Cloth tables {how}: {job.outcome.folder}")
        meshes = [scene.objects[name] for name in self.apply_to.split(NAME_SEPARATOR) if name in scene.objects]
        if meshes:
            try:
                return report_applied(self, *apply_to_meshes(bpy.context, meshes, job.outcome.folder))
            except (FileNotFoundError, ValueError, KeyError) as error:
                self.report({"ERROR"}, f"Cloth bake: {error}")
                return {"CANCELLED"}
        return {"FINISHED"}

    _running = RunningClothBake
    _what = "Cloth bake"
    _unavailable_reason = staticmethod(bake_unavailable_reason)

    def _status(self, job) -> str:
        return "Baking the ClothLight cloth" + (f", {job.stage}" if job.stage else "")


class CLOTHLIGHT_OT_cancel_cloth_bake(_CancelJobOperator, bpy.types.Operator):
    """Stop the running cloth bake; no cloth table is written"""

    bl_idname = "clothlight.cancel_cloth_bake"
    bl_label = "Cancel Cloth Bake"
    _running = RunningClothBake


# -- Fit to Measurement --------------------------------------------------------------------------


def _fit_job_for(context, request) -> FitJob:
    prefs = preferences.preferences(context)
    threads = prefs.threads if prefs is not None and prefs.threads > 0 else None
    return FitJob(request, cache_dir=preferences.cache_directory(context), threads=threads,
                  scheduler=prefs.scheduler.strip() if prefs is not None else None,
                  blender=bpy.app.binary_path, numba_cache_dir=preferences.numba_cache_directory(),
                  bytecode_cache_dir=preferences.bytecode_cache_directory())


def load_fit(medium, last: dict) -> None:
    """Set the medium settings to a fit's result (``last``: :meth:`ClothLightFitSettings.last`): its
    base medium and fitted values, the exposed ones shown in the panel, the rest kept as fitted values."""
    medium.set_values(last["base"], [tuple(pair) for pair in last["overrides"]])


def _fit_summary(outcome) -> str:
    held = "" if outcome.held_out_rms is None else f", held out {outcome.held_out_rms:.3g}"
    values = ", ".join(f"{name} {value:.4g}" for name, value in outcome.parameters.items())
    return f"relative RMS {outcome.relative_rms:.3g}{held}; {values}"


class CLOTHLIGHT_OT_fit_medium(_ChildJobOperator, bpy.types.Operator):
    """Fit the medium's free parameters to a measured cloth BRDF (python -m clothlight.fit: CMA-ES over the
    rendered cloth response, in a background process; docs/fitting.md). Esc cancels: nothing is written"""

    bl_idname = "clothlight.fit_medium"
    bl_label = "Fit to Measurement"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context) -> FitJob | None:
        settings = context.scene.clothlight
        try:
            request = settings.fit.request(settings.medium, preferences.fit_directory()).check()
            job = _fit_job_for(context, request)
        except (ParameterError, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return None
        return job

    def _finish(self, scene, job: FitJob):
        if isinstance(job.error, JobCancelled):
            self.report({"WARNING"}, str(job.error))
            return {"CANCELLED"}
        if isinstance(job.error, JobFailed):
            if not job.error.bad_input and job.error.log:
                print(job.error.log, file=sys.stderr)
            self.report({"ERROR"}, f"Fit failed: {job.error}")
            return {"CANCELLED"}
        outcome = job.outcome
        settings = scene.clothlight
        last = {"folder": str(outcome.folder), "preset": str(outcome.preset), "relative_rms": outcome.relative_rms,
                "held_out_rms": outcome.held_out_rms, "base": job.request.medium.preset,
                "overrides": [list(pair) for pair in dict((*job.request.medium.overrides, *outcome.overrides)).items()]}
        settings.fit.last_result = json.dumps(last)
        loaded = ""
        if settings.fit.load_result:
            load_fit(settings.medium, last)
            loaded = "; the fitted values are in the panel"
        for hit in outcome.bound_hits:
            self.report({"WARNING"}, hit)
        self.report({"INFO"}, f"Fitted in {outcome.seconds:.0f} s: {_fit_summary(outcome)}{loaded}. "
                              f"Preset: {outcome.preset}")
        return {"FINISHED"}

    _running = RunningFit
    _what = "Fit"
    _unavailable_reason = staticmethod(fit_unavailable_reason)

    def _status(self, job) -> str:
        return "Fitting the ClothLight medium" + (f", {job.stage}" if job.stage else "")


class CLOTHLIGHT_OT_cancel_fit(_CancelJobOperator, bpy.types.Operator):
    """Stop the running fit; nothing is written"""

    bl_idname = "clothlight.cancel_fit"
    bl_label = "Cancel Fit"
    _running = RunningFit


class CLOTHLIGHT_OT_load_fit(bpy.types.Operator):
    """Set the medium's values to the last fit's (its fitted preset): Bake Tables then bakes the fitted medium"""

    bl_idname = "clothlight.load_fit"
    bl_label = "Load Fitted Values"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None or context.scene.clothlight.fit.last() is None:
            cls.poll_message_set("No fit yet")
            return False
        return True

    def execute(self, context):
        settings = context.scene.clothlight
        last = settings.fit.last()
        try:
            load_fit(settings.medium, last)
        except (KeyError, TypeError, ValueError, ParameterError) as error:
            self.report({"ERROR"}, f"The last fit's values cannot be loaded: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Medium set to the fit in {last['folder']}")
        return {"FINISHED"}


class CLOTHLIGHT_OT_clear_fitted_values(bpy.types.Operator):
    """Forget the fitted values the panel does not show: the base medium's own values again"""

    bl_idname = "clothlight.clear_fitted_values"
    bl_label = "Clear Fitted Values"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and bool(context.scene.clothlight.medium.fitted_overrides)

    def execute(self, context):
        context.scene.clothlight.medium.fitted_overrides = ""
        return {"FINISHED"}


# -- Match Colour --------------------------------------------------------------------------------


def colour_directory() -> str:
    """Where Match Colour writes its recipes: ``colours/`` in the extension's user folder, never the
    extension's own (in development, in the user cache folder)."""
    if preferences.EXTENSION_PACKAGE:
        return bpy.utils.extension_path_user(preferences.EXTENSION_PACKAGE, path="colours", create=True)
    from precompute.cache.entries import default_cache_dir

    return str(default_cache_dir() / "colours")


def _colour_job_for(context, request: ColourMatchRequest) -> ColourMatchJob:
    prefs = preferences.preferences(context)
    threads = prefs.threads if prefs is not None and prefs.threads > 0 else None
    return ColourMatchJob(request, cache_dir=preferences.cache_directory(context), threads=threads,
                          blender=bpy.app.binary_path, numba_cache_dir=preferences.numba_cache_directory(),
                          bytecode_cache_dir=preferences.bytecode_cache_directory())


def apply_colour_recipe(scene, outcome: ColourMatchOutcome) -> str:
    """Make the written recipe of ``outcome`` the scene's medium (its Custom File, values and bake
    settings loaded from it) and, with Bake After Match in the interface, bake it once no bake runs.
    Returns a note for the report ("" when nothing was scheduled)."""
    medium = scene.clothlight.medium
    medium.set_base(str(outcome.preset))
    medium.load_preset(medium.base_preset())  # the file may have been rewritten at the same path
    if medium.bake_after_match and not bpy.app.background:
        running_jobs.schedule_bake(scene.name)
        return "; baking its tables"
    return ""


def colour_match_summary(outcome: ColourMatchOutcome) -> str:
    """A match in one line: the colour, how near the recipe comes, the recipe."""
    near = f"ΔE2000 {outcome.delta_e:.2f}"
    if outcome.reached:
        return f"{srgb_hex(outcome.target_srgb)} matched, {near}: {outcome.recipe_text()}"
    return (f"{srgb_hex(outcome.target_srgb)} is out of the dyes' reach on this yarn: the nearest recipe "
            f"({outcome.recipe_text()}) is {near} away")


class CLOTHLIGHT_OT_match_colour(_ChildJobOperator, bpy.types.Operator):
    """Solve the red, blue and yellow dye and the fibre's absorption that give the Base Medium's yarn the Target
    Colour (lit and seen along the normal, sheen excluded), write the recipe as a preset file and make it the
    medium (in a background process: minutes the first time for a yarn, then seconds). Esc cancels"""

    bl_idname = "clothlight.match_colour"
    bl_label = "Match Colour"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context) -> ColourMatchJob | None:
        medium = context.scene.clothlight.medium
        try:
            yarn = medium.request()
            target = tuple(float(v) for v in medium.target_colour)
            out = pathlib.Path(colour_directory()) / recipe_file_name(yarn, target)
            request = ColourMatchRequest(target=target, medium=yarn, out=str(out)).check()
            job = _colour_job_for(context, request)
        except (ParameterError, ValueError, OSError) as error:
            self.report({"ERROR"}, str(error))
            return None
        return job

    def _finish(self, scene, job: ColourMatchJob):
        if isinstance(job.error, JobCancelled):
            self.report({"WARNING"}, str(job.error))
            return {"CANCELLED"}
        if isinstance(job.error, JobFailed):
            if not job.error.bad_input and job.error.log:
                print(job.error.log, file=sys.stderr)
            self.report({"ERROR"}, f"Match Colour failed: {job.error}")
            return {"CANCELLED"}
        outcome = job.outcome
        medium = scene.clothlight.medium
        medium.colour_match = outcome.to_json()
        medium.matched_colour = outcome.cloth_srgb
        if not outcome.written:
            self.report({"WARNING"}, f"{colour_match_summary(outcome)}. Nothing was written: Apply Nearest Recipe "
                                     "writes it and makes it the medium")
            return {"FINISHED"}
        try:
            note = apply_colour_recipe(scene, outcome)
        except ParameterError as error:
            self.report({"ERROR"}, f"The recipe cannot be loaded: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"{colour_match_summary(outcome)}{note}. Preset: {outcome.preset}")
        return {"FINISHED"}

    _running = RunningColourMatch
    _what = "Colour match"
    _unavailable_reason = staticmethod(bake_unavailable_reason)

    def _status(self, job) -> str:
        return "Matching the colour" + (f", {job.stage}" if job.stage else "")


class CLOTHLIGHT_OT_cancel_colour_match(_CancelJobOperator, bpy.types.Operator):
    """Stop the running colour match; nothing is written"""

    bl_idname = "clothlight.cancel_colour_match"
    bl_label = "Cancel Colour Match"
    _running = RunningColourMatch


class CLOTHLIGHT_OT_apply_colour_match(bpy.types.Operator):
    """Write the last colour match's nearest recipe, which does not reach the Target Colour, and make it the
    medium anyway"""

    bl_idname = "clothlight.apply_colour_match"
    bl_label = "Apply Nearest Recipe"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        outcome = context.scene.clothlight.medium.last_colour_match() if context.scene is not None else None
        if outcome is None or outcome.written:
            cls.poll_message_set("No colour match with an unapplied recipe")
            return False
        return True

    def execute(self, context):
        medium = context.scene.clothlight.medium
        outcome = medium.last_colour_match()
        try:
            write_preset(outcome.text, outcome.preset)
            outcome.written = True
            medium.colour_match = outcome.to_json()
            note = apply_colour_recipe(context.scene, outcome)
        except (OSError, ParameterError) as error:
            self.report({"ERROR"}, f"The nearest recipe cannot be applied: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Nearest recipe applied, ΔE2000 {outcome.delta_e:.2f} from "
                              f"{srgb_hex(outcome.target_srgb)}{note}. Preset: {outcome.preset}")
        return {"FINISHED"}


# -- Set Up Cycles -------------------------------------------------------------------------------


class CLOTHLIGHT_OT_setup_render(bpy.types.Operator):
    """Switch the scene to Cycles with Open Shading Language on the CPU, as ClothLight materials need"""

    bl_idname = "clothlight.setup_render"
    bl_label = "Set Up Cycles for ClothLight"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        self.report({"INFO"}, use_cycles_osl_on_cpu(context.scene))
        return {"FINISHED"}


def material_summary(material) -> dict | None:
    """What the panels show about a ClothLight material: shader, mode, tables and sun."""
    mode = material_mode(material) if material is not None else None
    if mode is None:
        return None
    info = {"shader": material.get("clothlight_shader", ""),
            "mode": "Sun (exact)" if mode == SUN_MODE else "General"}
    folder = yarn_tables_folder(material)
    if folder is not None:
        folder = pathlib.Path(bpy.path.abspath(folder))
        info["tables"] = str(folder)
        try:
            summary = json.loads((folder / "summary.json").read_text())
            info["medium"] = summary.get("medium", {}).get("name", "")
            info["table1"] = summary.get("table1_ratios_normal", {})
        except (OSError, ValueError):
            info["missing"] = True
    sun = material.get(SUN_PROPERTY)
    if sun is not None:
        info["sun"] = sun.name
    return info


CLASSES = (
    CLOTHLIGHT_OT_build_sample,
    CLOTHLIGHT_OT_bake_tables,
    CLOTHLIGHT_OT_cancel_bake,
    CLOTHLIGHT_OT_bake_cloth,
    CLOTHLIGHT_OT_cancel_cloth_bake,
    CLOTHLIGHT_OT_fit_medium,
    CLOTHLIGHT_OT_cancel_fit,
    CLOTHLIGHT_OT_load_fit,
    CLOTHLIGHT_OT_clear_fitted_values,
    CLOTHLIGHT_OT_match_colour,
    CLOTHLIGHT_OT_cancel_colour_match,
    CLOTHLIGHT_OT_apply_colour_match,
    CLOTHLIGHT_OT_apply_material,
    CLOTHLIGHT_OT_setup_render,
)
