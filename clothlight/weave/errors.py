"""Errors for bad weave input: they name the parameter, its value and what is allowed."""

from __future__ import annotations


class WeaveParameterError(ValueError):
    """A weave parameter is outside its allowed range or malformed (never silently fixed)."""

    def __init__(self, name: str, value: object, allowed: str):
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"{name} = {value!r} is invalid: allowed {allowed}")
