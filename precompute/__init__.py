"""ClothLight precomputation: yarn optics → Monte-Carlo transport → baked BRDF tables.

Importable and testable without Blender.  Implements Lobalzo & Voloboy,
"Physically Based Lighting Model for Cloth and its Validation", GraphiCon 2008.
"""

__version__ = "0.1.0"
