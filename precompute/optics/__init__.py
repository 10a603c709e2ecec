"""A yarn medium and its optics, before any Monte-Carlo: what light meets inside and on a yarn.

:mod:`.medium` describes the yarn (host, particles, voids, dye; paper §3.2, §6.2) with units and
reads the shipped TOML presets (``precompute/presets/``); :mod:`.mie` (paper §3.3) and :mod:`.dye`
give each species' scattering and absorption, :mod:`.phase` the tabulated phase functions, and
:mod:`.coefficients` combines them into the per-wavelength μs, μa, g and phase function the
transport consumes.  Closed-form pieces that need no paths live here too: :mod:`.ballistic`, the
light that crosses the yarn unscattered, and :mod:`.cook_torrance`, the cloth's specular term.
:mod:`.plots` draws a medium's optics, and :mod:`.measured_sample` reads the weave a preset was
fitted on (its ``[sample]`` table).  Nothing here imports numba.
"""
