"""What a bench kind provides the engine, and what the engine hands it.

A bench kind (registered in `vissim.validation.engine.registry`) reads its part of a campaign
file, builds each configuration once (its viewing setup and scene: a `Built`), lists the
renders an item needs, computes an item from them, and contributes its report's rows and
sections.  The engine does everything else: the file's head, keys, the run folder, renders on
workers or a cluster, reuse, progress and the report's files.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Protocol

import numpy as np

from vissim.validation.engine.keys import item_key
from vissim.validation.engine.records import Item, Row

__all__ = ["BenchKind", "Campaign", "ItemPlan", "ReportParts"]


@dataclass(frozen=True)
class ItemPlan:
    """What one item needs: renders to make (role -> spec) and images already given (role -> pixels)."""

    renders: dict[str, Any] = field(default_factory=dict)
    given: dict[str, np.ndarray] = field(default_factory=dict)
    given_provenance: dict[str, Any] = field(default_factory=dict)
    source: dict[str, Any] = field(default_factory=dict)  # where the item's truth comes from


@dataclass(frozen=True)
class ReportParts:
    """A bench kind's part of the report: its title, metric rows (each a `Row`), Markdown tables and figures."""

    title: str
    rows: tuple[Row, ...]  # given as dicts or Rows; kept as Rows
    tables_md: str
    figures: dict  # name -> vissim.validation.engine.figures.Figure

    def __post_init__(self):
        object.__setattr__(self, "rows", tuple(Row.of(row) for row in self.rows))


@dataclass(frozen=True)
class Campaign:
    """A loaded campaign: its kind, head, settings and configurations, each built once (``built``)."""

    kind: str
    name: str
    description: str
    settings: Any
    configurations: tuple
    built: tuple = ()  # one per configuration: what `BenchKind.build` made of it
    source: str = ""
    manifest: str | None = None
    workers: int = 1  # where the run spreads its work (the engine's renders; a kind's items that spread their own)
    scheduler: str | None = None

    def item_key(self, configuration) -> str:
        """Stable key of one item's inputs: equal inputs, equal key (results are reused)."""
        return item_key(self.settings, configuration.key_inputs())

    def record(self, keys: list[str]) -> dict:
        """What ``campaign.json`` holds: the kind, head, settings, item keys and configurations."""
        from vissim.provenance import json_safe

        return {"kind": self.kind, "name": self.name, "description": self.description, "source": self.source,
                "manifest": self.manifest, "settings": json_safe(self.settings), "items": keys,
                "configurations": [c.as_json() for c in self.configurations]}


class BenchKind(Protocol):
    """A bench kind: the plug-in behind ``kind = NAME`` in a campaign file."""

    name: str
    #: The campaign file's tables of configurations this kind reads (e.g. ``("item", "sweep")``).
    tables: tuple[str, ...]
    #: Whether its items may be computed on threads at once (False: a kind whose items run their own processes).
    items_on_threads: bool

    def read(self, doc: dict, head: dict, path: Path) -> tuple[Any, tuple, str | None]:
        """(settings, configurations, manifest path or None) from the file's ``[campaign]`` ``head`` and tables."""

    def build(self, configuration, settings) -> Any:
        """The configuration's viewing setup and scene, built once for renders, items and checks."""

    def check_memory(self, campaign: Campaign) -> None:
        """Refuse a campaign an item of which this machine cannot hold."""

    def plan_items(self, campaign: Campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
        """Each item's `ItemPlan` (key -> plan) for the ``todo`` (key, configuration index), and skip messages."""

    def render(self, spec) -> Any:
        """Make one render on this machine (picklable: workers and Dask call it)."""

    def compute_item(self, key: str, campaign: Campaign, index: int, images: dict, plan: ItemPlan,
                     render_provenance: dict, item_dir: Path) -> dict:
        """Simulate and compare one item from its images; write its files and ``result.json`` (last)."""

    def input_files(self, configurations: list[dict]) -> list[Path]:
        """The files beside the campaign file that its configurations read (from ``campaign.json``'s records)."""

    def report(self, results: list[Item], run_dir: Path, record: dict,
               progress: Callable[[], None] | None) -> ReportParts:
        """The report's rows, tables and figures for these finished items."""

    def summary_lines(self, rows: tuple[Row, ...]) -> list[str]:
        """The terminal summary of a run: a few lines from the report's rows."""
