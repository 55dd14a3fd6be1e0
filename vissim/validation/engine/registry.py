"""The bench kinds a campaign may name (``kind`` in its ``[campaign]`` table).

A bench kind is a module exposing ``BENCH``, an object of the `vissim.validation.engine.protocol.BenchKind`
protocol.  Every kind, vissim's own and a plug-in outside it, is added by one `register_bench_kind`
line; vissim's own are registered at the foot of this module.
"""

from __future__ import annotations

import importlib

from vissim.errors import VissimInputError

__all__ = ["BENCH_KINDS", "DEFAULT_KIND", "bench_kind", "bench_kind_names", "register_bench_kind"]

#: kind name -> the module holding its ``BENCH`` (filled by `register_bench_kind` only).
BENCH_KINDS: dict[str, str] = {}
#: The kind of a campaign file that names none (the thesis's single-plane DSLR bench).
DEFAULT_KIND = "dslr"


def register_bench_kind(name: str, module: str) -> None:
    """Add the bench kind ``name``, whose ``BENCH`` is in ``module`` (imported when a campaign names it)."""
    BENCH_KINDS[name] = module


def bench_kind_names() -> list[str]:
    """The registered kinds' names, sorted."""
    return sorted(BENCH_KINDS)


def bench_kind(name: str):
    """The `BenchKind` called ``name``; an unknown name is an input error listing the known ones."""
    if name not in BENCH_KINDS:
        raise VissimInputError(f"unknown bench kind {name!r}; known: {', '.join(bench_kind_names())}")
    return importlib.import_module(BENCH_KINDS[name]).BENCH


register_bench_kind("dslr", "vissim.validation.dslr.kind")
register_bench_kind("depth", "vissim.validation.depth.kind")
register_bench_kind("eye", "vissim.validation.eye.kind")
register_bench_kind("population", "vissim.validation.population.kind")
