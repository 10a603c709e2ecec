"""The add-on's operator for the virtual gonioreflectometer: progress and cancel in the UI.

In the UI the operator is modal: a window-manager timer advances :meth:`ValidationRun.steps` by
one render per tick, the status bar and the window manager's progress show how far it is, and Esc
cancels (the rig is removed).  In background mode timers never fire and ``INVOKE_DEFAULT`` runs
``execute()``, which runs the same steps synchronously.  Either way the results end in the
output folder; the sweep plot is loaded as an image ("ClothLight Validation") for the Image
Editor and its folder kept in ``window_manager["clothlight_validation_dir"]``.

The sample is averaged over the azimuths its tables' bake records (a preset's ``[sample]
azimuths_deg``), as ``python -m clothlight.validate --tables`` does by default; tables that record
none measure it at one turn.  The operator has no property of its own for them (the command line's
``--sample-azimuths`` chooses others).

The sweep itself (:mod:`.run`: the garment material, the table reader, OpenEXR, numba's grids) is
imported when a sweep starts, not when the add-on is enabled.
"""

from __future__ import annotations

import pathlib
import sys
import tempfile
from typing import TYPE_CHECKING

import bpy

from ...mesh_attributes import CLOTH_NORMAL
from ...render_bounds import VALIDATION_RESOLUTION, VALIDATION_SAMPLES
from ...validation.framing import (
    DEFAULT_INCIDENCES_DEG,
    DEFAULT_VIEWS_DEG,
    MATERIALS,
    YARN_MATERIALS,
    sweep_sample_azimuths,
    tables_sample_weave,
)
from .rig import DEFAULT_RESOLUTION, DEFAULT_SAMPLES, RigSettings

if TYPE_CHECKING:
    from .run import ValidationRun

from precompute.errors import InputError, ParameterError
#: Errors that are the user's input, reported without a traceback: a bad setting, weave, measurement or
#: bake folder (each an InputError, whose module need not be imported when the add-on registers).
INPUT_ERRORS = (InputError,)
PLOT_IMAGE = "ClothLight Validation"


def parse_angles(text: str, name: str) -> tuple[float, ...]:
    """Angles in degrees from a list separated by spaces or commas ("0 30 45 60"), or ParameterError."""
    try:
        return tuple(float(word) for word in text.replace(",", " ").split())
    except ValueError:
        raise ParameterError(name, text, "numbers in degrees separated by spaces or commas") from None


def sample_in_context(context):
    """The active object when it is a ClothLight sample (a mesh with the cloth-normal attribute), else None."""
    obj = context.active_object
    if obj is not None and obj.type == "MESH" and CLOTH_NORMAL in obj.data.attributes:
        return obj
    return None


def _angle_text(angles) -> str:
    return " ".join(f"{a:g}" for a in angles)


class CLOTHLIGHT_OT_validate(bpy.types.Operator):
    """Measure the active ClothLight sample (or the woven sample its tables name) in a virtual gonioreflectometer:
    cloth BRDF against view angle per incidence, for the yarn material and the paper's baseline, with plots
    and a report"""

    bl_idname = "clothlight.validate"
    bl_label = "Validate in Gonioreflectometer"
    bl_options = {"REGISTER"}

    out_dir: bpy.props.StringProperty(
        name="Output Folder", subtype="DIR_PATH", default="//clothlight_validation",
        description="Folder for report.md, results.json, plots, swatches and renders. "
                    "'//' is the .blend's folder (the system's temporary folder for an unsaved file)")
    materials: bpy.props.EnumProperty(
        name="Materials", options={"ENUM_FLAG"}, default={"YARN", "BASELINE"},
        items=[("YARN", "Yarn", "ClothLight's yarn material from baked tables"),
               ("YARN_GENERAL", "Yarn, General Lighting",
                "The yarn material's general-lighting closure mixture under the rig's sun, direct light only"),
               ("YARN_SCENE", "Yarn in a Scene",
                "The general-lighting yarn material with full path tracing: light between yarns "
                "(compared with Yarn, General Lighting when both run)"),
               ("BASELINE", "Baseline", "The paper's baseline: Lambert (0.6/π, 0, 0) + Cook–Torrance m = 0.8")])
    tables_dir: bpy.props.StringProperty(
        name="Tables", subtype="DIR_PATH", default="",
        description="Bake folder of the yarn material. Empty: the tables of the sample's yarn material")
    measured_csv: bpy.props.StringProperty(
        name="Measurement", subtype="FILE_PATH", default="",
        description="Measured BRDF CSV to compare with (optional)")
    incidences: bpy.props.StringProperty(
        name="Incidences", default=_angle_text(DEFAULT_INCIDENCES_DEG), description="Sun zeniths θi, degrees")
    views: bpy.props.StringProperty(
        name="Views", default=_angle_text(DEFAULT_VIEWS_DEG),
        description="View zeniths θv, degrees; negative on the light's side")
    # Limits from clothlight/render_bounds.py, as the command line and RigSettings check them.
    resolution: bpy.props.IntProperty(name="Resolution", default=DEFAULT_RESOLUTION,
                                      **VALIDATION_RESOLUTION.limits(), soft_max=512,
                                      description="Pixels along the framed patch's side")
    samples: bpy.props.IntProperty(name="Samples", default=DEFAULT_SAMPLES, **VALIDATION_SAMPLES.limits(),
                                   soft_max=256, description="Cycles samples per pixel")
    swatches: bpy.props.BoolProperty(name="Colour Swatches", default=True,
                                     description="Also render the sample lit from the front and from behind")

    def _output_folder(self) -> pathlib.Path:
        if self.out_dir.startswith("//") and not bpy.data.filepath:
            return pathlib.Path(tempfile.gettempdir()) / self.out_dir[2:]
        return pathlib.Path(bpy.path.abspath(self.out_dir))

    def _prepare(self, context) -> ValidationRun:
        from .run import ValidationRun, tables_of_sample

        sample = sample_in_context(context)
        materials = tuple(kind for kind in MATERIALS if kind.upper() in self.materials)
        tables = bpy.path.abspath(self.tables_dir) if self.tables_dir else None
        # the sample's azimuths from the tables named, else from those a yarn sweep reads (the sample's material's)
        recorded_in = tables
        if recorded_in is None and sample is not None and set(YARN_MATERIALS) & set(materials):
            recorded_in = tables_of_sample(sample)
        if recorded_in is not None and not pathlib.Path(recorded_in).is_dir():
            raise ParameterError("tables_dir", recorded_in, "an existing bake folder")
        if sample is None and tables is not None:
            sample = tables_sample_weave(tables)  # the weave the tables were fitted on, as the command line builds
        settings = RigSettings(incidences_deg=parse_angles(self.incidences, "incidences"),
                               views_deg=parse_angles(self.views, "views"),
                               resolution=self.resolution, samples=self.samples,
                               sample_azimuths_deg=sweep_sample_azimuths(None, recorded_in))
        return ValidationRun(sample, self._output_folder(), materials=materials, tables_dir=tables,
                             measured_csv=bpy.path.abspath(self.measured_csv) if self.measured_csv else None,
                             settings=settings, swatches=self.swatches)

    def execute(self, context):
        try:
            run = self._prepare(context)
        except INPUT_ERRORS as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, run.total)
        try:
            for step in run.steps():
                wm.progress_update(step.done)
                if bpy.app.background:
                    print(f"\r[{step.done}/{step.total}] {step.what:<48}", end="", file=sys.stderr, flush=True)
        except INPUT_ERRORS as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        return self._finish(context, run)

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        try:
            self._run = self._prepare(context)
        except INPUT_ERRORS as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._steps = self._run.steps()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.05, window=context.window)
        wm.progress_begin(0, self._run.total)
        context.workspace.status_text_set(f"ClothLight validation: starting {self._run.total} renders (Esc cancels)")
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._stop(context)
            self.report({"WARNING"}, "Validation cancelled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            step = next(self._steps)
        except StopIteration:
            self._stop(context)
            return self._finish(context, self._run)
        except Exception as error:  # noqa: BLE001 - a modal operator reports a failed step and ends the run
            self._stop(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        context.window_manager.progress_update(step.done)
        context.workspace.status_text_set(f"ClothLight validation [{step.done}/{step.total}] {step.what} (Esc cancels)")
        return {"RUNNING_MODAL"}

    def _stop(self, context) -> None:
        """End the UI side of a modal run; closing the steps removes the rig if it is still there."""
        self._steps.close()
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def _finish(self, context, run: ValidationRun):
        results = run.results
        context.window_manager["clothlight_validation_dir"] = str(run.out_dir)
        if results["files"]["plots"]:
            image = bpy.data.images.get(PLOT_IMAGE)
            path = str(run.out_dir / results["files"]["plots"][0])
            if image is None:
                image = bpy.data.images.load(path)
                image.name = PLOT_IMAGE
            else:
                image.filepath = path
                image.reload()
        ratios = "; ".join(f"{kind} B/R {e['table1']['B/R']:.3g}, G/R {e['table1']['G/R']:.3g}"
                           for kind, e in results["materials"].items() if e["table1"])
        report = run.out_dir / results["files"]["report"]
        self.report({"INFO"}, f"Validation report: {report}" + (f" ({ratios})" if ratios else ""))
        return {"FINISHED"}


CLASSES = (CLOTHLIGHT_OT_validate,)
