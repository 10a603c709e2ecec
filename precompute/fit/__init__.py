"""Fitting a yarn medium to a measured cloth BRDF (docs/fitting.md): the bpy-free part.

:mod:`.measured_data` reads measured cloth BRDFs (CSV, RGB or spectral); :mod:`.parameters` the
free parameters, their bounds and scales; :mod:`.objective` the fit and held-out views and the
misfit; :mod:`.optimise` CMA-ES with the accuracy schedule (:func:`~.optimise.fit_medium`, over any
:class:`~.optimise.ForwardModel`); :mod:`.baseline` the paper's Lambert + Cook–Torrance fitted to
the same views; :mod:`.report` the output folder.  The forward model renders the woven sample, so
it and the command line live with the add-on: :mod:`clothlight.fit`, ``python -m clothlight.fit``.
"""
