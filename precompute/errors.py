"""Errors raised for bad input anywhere in ``precompute``.

Every check on user input raises :class:`ParameterError`, whose message names
the parameter, the value it got and the range it allows.  The command line maps
it to exit code 2; nothing is ever clamped silently.
"""

from __future__ import annotations


class ParameterError(ValueError):
    """A parameter is outside its allowed range or malformed.

    Parameters
    ----------
    name
        Dotted name of the parameter, as the user would write it
        (``"particles[0].diameter_nm"``).
    value
        The offending value.
    allowed
        Human-readable description of what is allowed (``"> 0"``,
        ``"(0, 0.74)"``, ``"monotonically increasing"``).
    """

    def __init__(self, name: str, value: object, allowed: str):
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"{name} = {value!r} is invalid: allowed {allowed}")
