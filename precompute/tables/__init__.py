"""The yarn tables: what a bake writes and every reader — the shader, the fit, the add-on — reads.

:mod:`.grids` holds the equal-solid-angle direction grids the transport tallies on and the shader
looks up; :mod:`.layout` how the tables are laid out as images and read back (docs/table-spec.md);
:mod:`.exr` the self-describing OpenEXR files; :mod:`.folder` a folder of tables checked as a whole;
:mod:`.color` spectral → scene-linear RGB; :mod:`.closure_fit` the BRDF as a mixture of Cycles
closures (``lobes.exr``), with :mod:`.cycles_closures` the NumPy twins of those closures; and
:mod:`.plots` what to look at before trusting a bake.  The format is one place: a change to it
changes these modules and ``osl/clothlight.h``, held together by the tests docs/architecture.md names.
"""
