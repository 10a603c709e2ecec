"""The medium fit as a job that renders: it sees both the physics and Blender.

The optimiser, the objective and the fit's folder are bpy-free and live in :mod:`precompute.fit`;
what needs the add-on is here: :mod:`.forward`, the forward model (a medium → the cloth BRDF at the
measured views, through the cloth response Cycles renders once), :mod:`.run`, the checks and the
run the command line and the add-on share, ``python -m clothlight.fit`` (:mod:`.__main__`) and
:mod:`.worker`, the add-on's child process (:class:`clothlight.fit_job.FitJob` starts it).  Blender
is imported only when the cloth response has to be rendered.
"""
