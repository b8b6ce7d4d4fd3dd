"""Checks of the package's numeric arguments, before they reach the extension (whose conversion to
an unsigned integer would raise a bare ``OverflowError`` for a negative number)."""

from __future__ import annotations

import numbers


def whole(name: str, value, low: int = 1) -> int:
    """``value`` as an int; a negative number is a ValueError (what is not a whole number a
    TypeError) naming the argument, the value and what it takes (≥ ``low``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be a whole number ≥ {low}, not {type(value).__name__} {value!r}")
    # Zero and numbers above the range reach the extension, whose message names the range.
    if value < 0:
        raise ValueError(f"{name}={value}: give a whole number ≥ {low}")
    return int(value)
