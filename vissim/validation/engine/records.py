"""The records the engine hands between the runner, the bench kinds and the report: `Item` and `Row`.

An `Item` is one finished item as its ``result.json`` holds it; a `Row` is one row of the report
(a line of ``metrics.csv``, an entry of ``metrics.json``'s rows), its columns in order.  Both are
frozen and read as mappings (``item["configuration"]``, ``row["simulation"]``), so a kind's report
code reads them as it reads the JSON they come from, and nothing after the engine can change them.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

__all__ = ["Item", "Row"]


@dataclass(frozen=True, eq=False)
class Item(Mapping[str, Any]):
    """One finished item: its ``key`` and its ``result.json`` record (``record``, read-only)."""

    key: str
    record: Mapping[str, Any]

    @classmethod
    def from_json(cls, record: dict) -> Item:
        """The item of a ``result.json`` record (a dict holding at least ``key``)."""
        return cls(record["key"], MappingProxyType(dict(record)))

    @property
    def configuration(self) -> Mapping[str, Any]:
        """The item's configuration as its campaign names it (``name``, and the kind's fields)."""
        return self.record["configuration"]

    def as_json(self) -> dict:
        """The ``result.json`` record, for JSON."""
        return dict(self.record)

    def __reduce__(self):  # pickled as its record (a read-only mapping does not pickle): for a figure process
        return _item, (self.key, dict(self.record))

    def __getitem__(self, field: str) -> Any:
        return self.record[field]

    def __iter__(self) -> Iterator[str]:
        return iter(self.record)

    def __len__(self) -> int:
        return len(self.record)


@dataclass(frozen=True, eq=False)
class Row(Mapping[str, Any]):
    """One row of the report: column -> value (``cells``, read-only, in the columns' order)."""

    cells: Mapping[str, Any]

    @classmethod
    def of(cls, cells: Mapping[str, Any]) -> Row:
        """A row of ``cells`` (a kind's dict, or a `Row`, kept as it is)."""
        return cells if isinstance(cells, Row) else cls(MappingProxyType(dict(cells)))

    def __reduce__(self):
        return Row.of, (dict(self.cells),)

    def __getitem__(self, column: str) -> Any:
        return self.cells[column]

    def __iter__(self) -> Iterator[str]:
        return iter(self.cells)

    def __len__(self) -> int:
        return len(self.cells)


def _item(key: str, record: dict) -> Item:
    return Item(key, MappingProxyType(record))
