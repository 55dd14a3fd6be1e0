"""The one campaign loader: a ``[campaign]`` head naming its bench kind, and that kind's tables.

The head holds ``name``, ``description`` and ``kind`` (a name of
`vissim.validation.engine.registry.bench_kind_names`; ``"dslr"`` when absent) and the kind's
settings; the kind reads its settings and its configuration tables (`BenchKind.read`) and builds
each configuration once (`BenchKind.build`).  Every field is checked with a message naming the
file, the field and its unit.
"""

from __future__ import annotations

from pathlib import Path

from vissim.checks import path_arg
from vissim.errors import VissimInputError
from vissim.validation.engine.fields import (UnknownFieldError, description_text, field_error, name_text,
                                             read_campaign_toml, table, text)
from vissim.validation.engine.protocol import Campaign
from vissim.validation.engine.registry import DEFAULT_KIND, bench_kind, bench_kind_names

__all__ = ["load_campaign", "campaign_kind"]


def campaign_kind(doc: dict, source: str) -> str:
    """The bench kind a campaign document names (``[campaign] kind``), checked against its tables."""
    head = table(doc.get("campaign", {}), source, "[campaign]")
    name = text(head.get("kind", DEFAULT_KIND), source, "campaign.kind")
    if name not in bench_kind_names():
        raise field_error(source, "campaign.kind", f"unknown bench kind {name!r}; known: {', '.join(bench_kind_names())}")
    allowed = {"campaign", *bench_kind(name).tables}
    unknown = sorted(set(doc) - allowed)
    if unknown:
        owners = sorted(k for k in bench_kind_names() if k != name and set(unknown) <= {"campaign", *bench_kind(k).tables})
        hint = f" (tables of kind {owners[0]!r}: add kind = \"{owners[0]}\" to [campaign])" if owners else ""
        raise field_error(source, "top level", f"unknown {'table' if len(unknown) == 1 else 'tables'} {unknown} for a {name} campaign{hint}; "
                                               f"use [campaign] and {', '.join(f'[[{t}]]' for t in bench_kind(name).tables)}")
    return name


def load_campaign(path: str | Path, *, check_memory: bool = True) -> Campaign:
    """Read and validate a campaign TOML file of any bench kind; build each configuration once.

    Parameters
    ----------
    path : str or Path
        The campaign TOML file (fields: docs' File formats page).
    check_memory : bool
        Estimate each item's memory and refuse a campaign this machine cannot hold.

    Returns
    -------
    Campaign
        The validated campaign: kind, settings, configurations and what each was built into.

    Raises
    ------
    VissimInputError
        A field is missing, unknown or out of range (the message names the file and field).

    Examples
    --------
    >>> import vissim
    >>> campaign = vissim.load_campaign("campaign.toml")  # doctest: +SKIP
    """
    path = path_arg(path, "load_campaign's path")
    source = str(path)
    doc = read_campaign_toml(path)
    kind_name = campaign_kind(doc, source)
    kind = bench_kind(kind_name)
    head = dict(table(doc.get("campaign", {}), source, "[campaign]"))
    head.pop("kind", None)
    title = name_text(head.pop("name"), source, "campaign.name") if "name" in head else path.stem
    description = description_text(head.pop("description"), source, "campaign.description") \
        if "description" in head else ""
    try:
        settings, configurations, manifest = kind.read(doc, head, path)
    except UnknownFieldError as error:
        if "kind" in table(doc.get("campaign", {}), source, "[campaign]"):
            raise  # a key the default kind does not know may mean another kind was meant; a kind given was meant
        others = " or ".join(f'"{name}"' for name in bench_kind_names() if name != kind_name)
        raise VissimInputError(f"{error} (no [campaign] kind is given, so the file was read as a {kind_name} "
                               f"campaign: add kind = {others} for another)") from None
    if not configurations:
        raise field_error(source, "top level", f"no configurations: add {' or '.join(f'[[{t}]]' for t in kind.tables)} "
                                               "tables")
    try:
        built = tuple(kind.build(c, settings) for c in configurations)
    except VissimInputError as exc:
        raise VissimInputError(f"{source}: {exc}") from None
    campaign = Campaign(kind_name, title, description, settings, tuple(configurations), built, source, manifest)
    if check_memory:
        kind.check_memory(campaign)
    return campaign
