"""The close-up's operator: flyaway fibres grown on the active woven sample (issue 46).

Add Flyaway Fibres reads the active sample's own weave (what it was built from, its
``clothlight_weave`` record), the Weave panel's fibre settings and the Base Medium preset (the
fibres' dye, material and radius), and builds the fibres as a child of the sample
(:mod:`.flyaway_object`), replacing the ones it had.
"""

from __future__ import annotations

import pathlib

import bpy

from precompute.errors import ParameterError

from .operators import is_sample
from ..weave.record import weave_from_record
from .sample_object import WEAVE_PROPERTY


class CLOTHLIGHT_OT_add_flyaways(bpy.types.Operator):
    """Grow flyaway fibres on the active woven sample (rebuilt in place), dyed as the Base Medium"""

    bl_idname = "clothlight.add_flyaways"
    bl_label = "Add Flyaway Fibres"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        if not is_sample(context.active_object):
            cls.poll_message_set("Select a ClothLight sample (Build Sample makes one)")
            return False
        return True

    def execute(self, context):
        # imported here: the fibres' colour needs colour-science, which enabling the add-on must not import
        from .flyaway_object import build_flyaway_object

        settings = context.scene.clothlight
        sample = context.active_object
        try:
            params = weave_from_record(sample[WEAVE_PROPERTY])
            preset = settings.medium.base_preset()  # a shipped preset's name or the Custom File's path
            fibres = build_flyaway_object(sample, params, settings.weave.closeup_settings(), preset)
        except ParameterError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        count = 0 if fibres is None else len(fibres.data.curves)
        self.report({"INFO"}, f"{sample.name}: {count} flyaway fibres of {pathlib.Path(preset).stem}")
        return {"FINISHED"}


CLASSES = (CLOTHLIGHT_OT_add_flyaways,)
