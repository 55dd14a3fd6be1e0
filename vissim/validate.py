"""Validation of scalar inputs: one clear error naming the bad value and its unit."""

from __future__ import annotations

import math

from vissim.errors import VissimInputError

__all__ = ["finite_number", "positive_number"]


def finite_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float; NaN (and infinity unless ``allow_inf``) refused."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be a number in {unit}, got {value!r}") from None
    if math.isnan(number) or (math.isinf(number) and not allow_inf):
        raise VissimInputError(f"{name} must be finite (in {unit}), got {value!r}")
    return number


def positive_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """A finite (or, with ``allow_inf``, infinite) number > 0."""
    number = finite_number(value, name, unit, allow_inf=allow_inf)
    if number <= 0.0:
        raise VissimInputError(f"{name} must be a positive number of {unit}, got {value!r}")
    return number
