"""Garment-scale material: the cloth BSDF measured on a woven sample (paper §7) and the shader
that renders any mesh with it."""
