"""The virtual gonioreflectometer (paper §4, §6): rig, measurement, measured data, report."""
