"""Provenance records: which vissim, Python and NumPy made an output, when, and from what.

A provenance record is a plain JSON-safe dict; it travels inside EXR headers and in
``<file>.json`` sidecars next to PNG/TIFF files (see `vissim.imageio`).
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import enum
import json
import math
import platform
import sys
from collections.abc import Mapping
from pathlib import PurePath
from typing import Any

from vissim import __version__
from vissim.errors import VissimInputError

__all__ = ["from_json", "json_safe", "make_provenance", "to_json"]


def json_safe(value: Any) -> Any:
    """Return ``value`` converted to plain JSON types.

    NumPy scalars and arrays become Python numbers and (nested) lists, paths become
    strings, dataclass instances become dicts, enums their values, tuples and sets lists.
    Non-finite floats become the strings ``"nan"``, ``"inf"`` and ``"-inf"`` (JSON has no
    such numbers).  Anything else unknown is recorded by its ``repr``.
    """
    kind = type(value)
    if kind is str or kind is int or kind is bool or value is None:  # the plain types first: records are mostly these
        return value
    if kind is dict:
        return {k if type(k) is str else str(k): json_safe(v) for k, v in value.items()}
    if kind is list:
        return [json_safe(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return json_safe({f.name: getattr(value, f.name) for f in dataclasses.fields(value)})
    np = sys.modules.get("numpy")  # a NumPy value exists only where NumPy is loaded: none is imported here
    if np is not None and isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if np is not None and isinstance(value, np.generic):
        return json_safe(value.item())
    if isinstance(value, (int, str)):  # their subclasses (the plain types returned above): IntEnum, a str Enum
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else ("nan" if math.isnan(value) else ("inf" if value > 0 else "-inf"))
    if isinstance(value, enum.Enum):
        return json_safe(value.value)
    if isinstance(value, PurePath):
        return str(value)
    if isinstance(value, (_dt.datetime, _dt.date)):
        return value.isoformat()
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        items = sorted(value, key=repr) if isinstance(value, (set, frozenset)) else value
        return [json_safe(v) for v in items]
    return repr(value)


def make_provenance(**inputs: Any) -> dict[str, Any]:
    """Return a provenance record for an output made from ``inputs``.

    Keys: ``vissim_version``, ``python``, ``numpy``, ``created_utc`` (ISO 8601, UTC) and
    ``inputs`` (the keyword arguments, made JSON-safe by `json_safe`).
    """
    import numpy  # the numerical code is paid when a record is made, not when a command's help is built

    return {
        "vissim_version": __version__,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "inputs": json_safe(inputs),
    }


def to_json(prov: Mapping[str, Any], *, compact: bool = False) -> str:
    """Serialise a provenance record, sorted keys: indented for people to read (sidecars), or ``compact`` (one
    line, by the C encoder: twice as fast) where only programs read it (EXR headers)."""
    if compact:
        return json.dumps(json_safe(prov), separators=(",", ":"), sort_keys=True, allow_nan=False)
    return json.dumps(json_safe(prov), indent=2, sort_keys=True, allow_nan=False)


def from_json(s: str) -> dict[str, Any]:
    """Parse a provenance record written by `to_json`."""
    try:
        prov = json.loads(s)
    except json.JSONDecodeError as exc:
        raise VissimInputError(f"provenance is not valid JSON: {exc}") from exc
    if not isinstance(prov, dict):
        raise VissimInputError(f"provenance must be a JSON object, got {type(prov).__name__}")
    return prov
