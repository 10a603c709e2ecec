"""The garment's thread count: the validation weave at another density, for the cloth gonioreflectometer.

One value for warp and weft, in threads per cm: the weave has one spacing, 10 / n mm.  The yarns stay
the validation weave's (round, 0.1 mm radius, plain; :data:`clothlight.blender.validation.rig.VALIDATION_WEAVE`);
only their spacing changes.  The default, the validation weave's own 20 threads/cm, gives no weave
at all (``GoniometerSettings.weave`` None), so its settings, cache keys and the shipped cloth tables
are those of a bake without a thread count.

A module of its own, imported by none of the measurement's modules, so that the cloth response's
cache key (which digests the code of :mod:`.measure` and all it imports) stays what it was.  Its
top level needs no Blender: the command line checks ``--threads-per-cm`` with :data:`THREADS_PER_CM`
before importing bpy.
"""

from __future__ import annotations

from ...render_bounds import Bound

#: Threads per cm, warp and weft alike.  24: the densest that the weave's clearance check lets
#: through for the validation weave's yarns and tessellation (WeaveParameters: at 25 their triangle
#: meshes would cut into the yarns they cross).  The patch planning (``goniometry.plan_regions``,
#: ``required_sample_half_size_mm``) holds at any sparser spacing, with fewer yarns in the sample;
#: 10 (1 mm spacing) is the sparsest at which the response's camera samples along a patch's side
#: (``bake.RESPONSE_SAMPLES_PER_SIDE``, 21 over two spacings) still put two across a yarn's 0.2 mm,
#: so that its edges are sampled.  tests/test_garment_density.py checks both ends.
THREADS_PER_CM = Bound("threads_per_cm", 10, 24, integer=True, unit="threads/cm")
#: The validation weave's own density (0.5 mm spacing: docs/garment.md's measurements, the shipped
#: cloth tables); tests/test_garment_density.py checks it against VALIDATION_WEAVE.
DEFAULT_THREADS_PER_CM = 20
#: Millimetres per centimetre: spacing_mm = MM_PER_CM / threads_per_cm.
MM_PER_CM = 10.0


def weave_at_thread_count(threads_per_cm: int | None):
    """The validation weave with ``threads_per_cm`` warp and weft threads per cm (spacing 10 / n mm),
    as ``GoniometerSettings.weave`` takes it: None (the validation weave itself) for None or the
    validation weave's own count.  ParameterError (naming ``threads_per_cm``, with the allowed range)
    outside :data:`THREADS_PER_CM`."""
    import dataclasses

    from ..validation.rig import VALIDATION_WEAVE

    if threads_per_cm is None:
        return None
    count = THREADS_PER_CM.check(threads_per_cm)
    spacing_mm = MM_PER_CM / count
    if spacing_mm == VALIDATION_WEAVE.spacing_mm:
        return None
    return dataclasses.replace(VALIDATION_WEAVE, spacing_mm=spacing_mm)

