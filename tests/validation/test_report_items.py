"""A report holds its campaign's items only, not others left in the run folder."""

import json

from vissim.validation.engine.report import load_results


def test_items_not_in_the_campaign_are_not_reported(tmp_path):
    # A rerun after the simulator changed gives new item keys; the old items stay on disk but
    # must not be mixed into the new report (they would double every group's count).
    for key in ("new", "old"):
        (tmp_path / "items" / key).mkdir(parents=True)
        (tmp_path / "items" / key / "result.json").write_text(json.dumps({"key": key}))
    (tmp_path / "campaign.json").write_text(json.dumps({"items": ["new"]}))
    assert [r["key"] for r in load_results(tmp_path)] == ["new"]
