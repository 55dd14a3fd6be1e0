"""The bench kinds a campaign may name (``kind`` in its ``[campaign]`` table).

A bench kind is a module exposing ``BENCH``, an object of the `vissim.validation.engine.protocol.BenchKind`
protocol.  A new bench is its own folder plus one line here.
"""

from __future__ import annotations

import importlib

from vissim.errors import VissimInputError

__all__ = ["BENCH_KINDS", "DEFAULT_KIND", "bench_kind", "register_bench_kind"]

#: kind name -> the module holding its ``BENCH``.
BENCH_KINDS = {
    "dslr": "vissim.validation.dslr.kind",
    "depth": "vissim.validation.depth.kind",
    "eye": "vissim.validation.eye.kind",
}
#: The kind of a campaign file that names none (the thesis's single-plane DSLR bench).
DEFAULT_KIND = "dslr"


def register_bench_kind(name: str, module: str) -> None:
    """Add a bench kind at run time (a plug-in outside vissim, or a test's)."""
    BENCH_KINDS[name] = module


def bench_kind(name: str):
    """The `BenchKind` called ``name``; an unknown name is an input error listing the known ones."""
    if name not in BENCH_KINDS:
        raise VissimInputError(f"unknown bench kind {name!r}; known: {', '.join(sorted(BENCH_KINDS))}")
    return importlib.import_module(BENCH_KINDS[name]).BENCH
