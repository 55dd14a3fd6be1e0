"""What a command prints: its text lines, or with ``--json`` one JSON object (light: no numerical imports, so a
command's parser can take ``--json`` without them)."""

from __future__ import annotations

import argparse

__all__ = ["JSON_HELP", "add_json_arg", "print_result", "print_json"]

#: ``--json``'s help, the same on every command that computes numbers.
JSON_HELP = "print one JSON object instead of the text lines: the numbers, the files written and their provenance"


def add_json_arg(parser) -> None:
    """``--json`` (`JSON_HELP`)."""
    parser.add_argument("--json", action="store_true", help=JSON_HELP)


def print_result(args: argparse.Namespace, lines: list[str], record: dict | None = None, written=(),
                 provenance: dict | None = None) -> None:
    """The command's text ``lines``, or with ``--json`` one JSON object: ``record`` (the numbers the lines say),
    ``written`` (the files, as paths) and ``provenance`` (what the files record)."""
    if not getattr(args, "json", False):
        for line in lines:
            print(line)
        return
    print_json(record or {}, written, provenance)


def print_json(record: dict, written=(), provenance: dict | None = None) -> None:
    """``--json``'s one object: ``record``, ``written`` (the files, as paths) and, when given, ``provenance``;
    NumPy values as plain numbers and non-finite ones as strings (`vissim.provenance.json_safe`)."""
    import json

    from vissim.provenance import json_safe

    out = {**record, "written": [str(p) for p in written]}
    if provenance is not None:
        out["provenance"] = provenance
    print(json.dumps(json_safe(out), indent=2, allow_nan=False))
