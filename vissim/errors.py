"""The one exception type vissim raises for bad input.

A `VissimInputError` carries a single human-readable line that names the bad
value and its unit.  The command line catches it and prints that line; it never shows a
traceback for bad input.
"""

from __future__ import annotations


class VissimError(Exception):
    """Base class of every error vissim raises on purpose."""


class VissimInputError(VissimError, ValueError):
    """Bad input: a malformed prescription, an out-of-range value, an unreadable file."""


class VissimTypeError(VissimInputError, TypeError):
    """An argument of the wrong type (a str where a Wavefront is expected); the line says what is accepted."""


class FieldTooSmallError(VissimInputError):
    """A requested PSF field cannot hold the blur without truncating or wrapping it."""
