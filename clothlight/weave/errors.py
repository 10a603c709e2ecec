"""Errors for bad weave input: they name the parameter, its value and what is allowed."""

from __future__ import annotations


from precompute.errors import ParameterError


class WeaveParameterError(ParameterError):
    """A weave parameter is outside its allowed range or malformed (never silently fixed).

    A :class:`precompute.errors.ParameterError` (one error hierarchy: every command line exits
    with code 2 on it), kept as its own type so callers can tell weave input from the rest."""
