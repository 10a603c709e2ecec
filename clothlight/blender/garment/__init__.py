"""The garment material in Blender: ``measure`` (the generalised gonioreflectometer's renders),
``detail`` (close-up weave renders), ``bake`` (measurement → cached cloth tables), ``material`` (the
garment shader's node tree), ``drape`` (a test garment), ``operator``.  The goniometry and the table
format are Blender-free, in :mod:`clothlight.garment`."""
