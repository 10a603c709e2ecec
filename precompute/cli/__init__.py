"""Sub-commands of ``python -m precompute``; see :mod:`precompute.__main__`."""
