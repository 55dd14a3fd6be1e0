"""What every bench kind's configuration tables share: a sweep's combinations and one name per configuration.

A ``[[sweep]]`` table gives lists of values; its configurations are every combination
(`sweep_combinations`).  Two configurations with one name are refused (`refuse_duplicate_names`):
a report shows one row per name and would hide the other.  Each bench kind reads and names its
own configurations and calls these two.
"""

from __future__ import annotations

import itertools
from typing import Callable, Iterable

from vissim.validation.engine.fields import field_error

__all__ = ["sweep_combinations", "refuse_duplicate_names", "SWEEP_NAME_HINT"]

#: What to do about two configurations with one name, when a sweep may have generated them.
SWEEP_NAME_HINT = ("give each its own name (a sweep's generated names round lens powers to 0.01 D and LogMAR to 0.1: "
                   "make such values differ by more, or list them as named items)")


def sweep_combinations(axes: dict[str, list], source: str = "campaign", where: str = "sweep") -> list[dict]:
    """Every combination of the ``axes``' values (axis name -> values), the last axis varying fastest; an empty axis,
    which would leave the sweep no configuration, refused naming ``where`` in ``source``."""
    for name, values in axes.items():
        if len(values) == 0:
            raise field_error(source, f"{where}.{name}", "an empty list sweeps nothing (the sweep would make no "
                                                          "configuration): give at least one value, or leave it out")
    names = list(axes)
    return [dict(zip(names, values)) for values in itertools.product(*axes.values())]


def refuse_duplicate_names(source: str, entries: Iterable[tuple[str, object]], describe: Callable[[object], str],
                           hint: str = SWEEP_NAME_HINT) -> None:
    """Refuse two configurations with one name, in one line naming both places, the name and what each compares.

    ``entries`` are ``(where, configuration)`` pairs (``where``: its place in the file, e.g. ``item[0]``);
    ``describe(configuration)`` says what it compares; ``hint`` says what to do.
    """
    seen: dict[str, tuple[str, object]] = {}
    for where, config in entries:
        if config.name in seen:
            first_where, first = seen[config.name]
            raise field_error(source, f"{first_where} and {where}",
                              f"two configurations named {config.name!r} ({describe(first)}; {describe(config)}); {hint}")
        seen[config.name] = (where, config)
