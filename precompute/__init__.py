"""ClothLight precomputation: yarn optics → Monte-Carlo transport → baked BRDF tables.

Importable and testable without Blender, and importing nothing of the add-on.  Implements Lobalzo &
Voloboy, "Physically Based Lighting Model for Cloth and its Validation", GraphiCon 2008.  Its
packages, bottom up: :mod:`.optics` (the medium and its optics), :mod:`.tables` (the table format)
and :mod:`.slab`, :mod:`.transport` (the Monte-Carlo paths), then :mod:`.bake`, which runs them
into tables, :mod:`.fit` (the fit's optimiser) and :mod:`.reference` (a brute-force check), and
:mod:`.cli` (``python -m precompute``); under all of them the common ground: errors, exit codes,
bounds, output checks, :mod:`.cache` and :mod:`.distributed` (docs/architecture.md, "Layers").
"""

__version__ = "0.1.0"
