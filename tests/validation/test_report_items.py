"""A report holds its campaign's items only, not others left in the run folder."""

import dataclasses
import json

import pytest

from vissim.validation.engine.protocol import ReportParts
from vissim.validation.engine.records import Item, Row
from vissim.validation.engine.report import load_results


def test_items_not_in_the_campaign_are_not_reported(tmp_path):
    # A rerun after the simulator changed gives new item keys; the old items stay on disk but
    # must not be mixed into the new report (they would double every group's count).
    for key in ("new", "old"):
        (tmp_path / "items" / key).mkdir(parents=True)
        (tmp_path / "items" / key / "result.json").write_text(json.dumps({"key": key}))
    (tmp_path / "campaign.json").write_text(json.dumps({"items": ["new"]}))
    assert [r["key"] for r in load_results(tmp_path)] == ["new"]


def test_the_report_reads_frozen_items_and_hands_on_frozen_rows(tmp_path):
    """The engine's records: an `Item` per finished item, a `Row` per report row; neither can be changed."""
    (tmp_path / "items" / "k").mkdir(parents=True)
    record = {"key": "k", "configuration": {"name": "renamed later"}, "value": 1.5}
    (tmp_path / "items" / "k" / "result.json").write_text(json.dumps(record))
    (tmp_path / "campaign.json").write_text(json.dumps({"items": ["k"], "configurations": [{"name": "now"}]}))
    [item] = load_results(tmp_path)
    assert isinstance(item, Item) and item.key == "k" and item.configuration["name"] == "now"
    assert item.as_json() == {**record, "configuration": {"name": "now"}}
    with pytest.raises(TypeError):
        item["value"] = 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        item.key = "other"
    parts = ReportParts("t", [{"configuration": "now", "value": 1.5}], "", {})
    [row] = parts.rows
    assert isinstance(row, Row) and list(row) == ["configuration", "value"] and row == {"configuration": "now", "value": 1.5}
    with pytest.raises(TypeError):
        row["value"] = 2.0
