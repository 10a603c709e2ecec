"""The bake, the cloth bake, the fit and the colour match the interface is running, and the bake a dye change (or
a matched colour) schedules.

Held here, apart from the operators that start them, so that the settings (a dye change with Dye
Range on schedules a bake: :mod:`.properties`), the operators and the panels (their progress) all
read one state, and import it one way.
"""

from __future__ import annotations

import bpy

from ..colour_match_job import ColourMatchJob
from ..fit_job import FitJob
from ..jobs import BakeJob, ClothBakeJob


class RunningBake:
    """The one bake the interface is running (None when idle); the panel draws its progress."""

    job: BakeJob | None = None
    scene_name: str = ""


def running_bake() -> BakeJob | None:
    return RunningBake.job


#: Seconds after the last dye change before a recolouring bake starts (a slider drag changes it often).
RECOLOUR_DELAY_SECONDS = 0.4


def schedule_recolour(scene_name: str) -> None:
    """Start Bake Tables for ``scene_name`` once the dye stops changing and no bake runs (a timer)."""

    def start():
        if RunningBake.job is not None:
            return RECOLOUR_DELAY_SECONDS  # the latest dye bakes after the running one
        scene = bpy.data.scenes.get(scene_name)
        window = bpy.context.window_manager.windows[0] if bpy.context.window_manager.windows else None
        if scene is None or window is None:
            return None
        with bpy.context.temp_override(window=window, scene=scene):
            bpy.ops.clothlight.bake_tables("INVOKE_DEFAULT")
        return None

    ScheduledRecolour.cancel()
    ScheduledRecolour.start = start
    bpy.app.timers.register(start, first_interval=RECOLOUR_DELAY_SECONDS)


def schedule_bake(scene_name: str) -> None:
    """Start Bake Tables for ``scene_name`` soon, once no bake runs (a matched colour's recipe): as
    :func:`schedule_recolour`."""
    schedule_recolour(scene_name)


class ScheduledRecolour:
    """The pending recolouring bake's timer function (None when none is pending)."""

    start = None

    @classmethod
    def cancel(cls) -> None:
        if cls.start is not None and bpy.app.timers.is_registered(cls.start):
            bpy.app.timers.unregister(cls.start)
        cls.start = None


class RunningFit:
    """The one fit the interface is running (None when idle); the panel draws its progress."""

    job: FitJob | None = None
    scene_name: str = ""


def running_fit() -> FitJob | None:
    return RunningFit.job


class RunningClothBake:
    """The one cloth bake the interface is running (None when idle); the Garment panel draws its progress."""

    job: ClothBakeJob | None = None
    scene_name: str = ""


def running_cloth_bake() -> ClothBakeJob | None:
    return RunningClothBake.job


class RunningColourMatch:
    """The one colour match the interface is running (None when idle); the Yarn Medium panel draws its progress."""

    job: ColourMatchJob | None = None
    scene_name: str = ""


def running_colour_match() -> ColourMatchJob | None:
    return RunningColourMatch.job


def stop_all() -> None:
    """Cancel the pending recolouring bake and every running job (the add-on is being disabled)."""
    ScheduledRecolour.cancel()
    for holder in (RunningBake, RunningClothBake, RunningFit, RunningColourMatch):
        if holder.job is not None:
            holder.job.cancel()
            holder.job = None
