"""A new bench kind needs its own folder and one registration line: the engine does the rest.

The toy bench (tests/validation/toy_bench, nothing of it inside vissim) is registered with one
line and run end to end through `vissim validate`'s own function: loading, keys, renders, items,
reuse and the report.  Oracle: its simulation is its render without noise, so it scores the
noise floor + 3 dB (MSE sigma^2 against 2 sigma^2), to the noise of 1024 pixels (+-0.3 dB).
"""

import pytest

from vissim.errors import VissimInputError
from vissim.validation.engine import registry
from vissim.validation.engine.validate import validate

CAMPAIGN = """
[campaign]
kind = "toy"
name = "toy"
[[disc]]
name = "sharp"
sigma_px = 0.5
[[disc]]
name = "soft"
sigma_px = 3.0
"""


@pytest.fixture
def toy_kind(monkeypatch):
    monkeypatch.setattr(registry, "BENCH_KINDS", dict(registry.BENCH_KINDS))  # dropped after the test
    registry.register_bench_kind("toy", "toy_bench.kind")  # the one registration line
    yield


def test_a_bench_in_its_own_folder_runs_through_the_engine(toy_kind, tmp_path):
    path = tmp_path / "toy.toml"
    path.write_text(CAMPAIGN)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.kind == "toy" and done.summary.items_total == 2 and done.summary.renders_made == 4
    for line in done.lines[1:3]:
        margin = float(line.split(": ")[1].split(" dB")[0])
        assert margin == pytest.approx(3.0, abs=0.3), line
    assert "| sharp |" in (tmp_path / "run" / "tables.md").read_text()
    again = validate(path, tmp_path / "run", show_progress=False)
    assert again.summary.items_reused == 2 and again.summary.renders_made == 0


def test_a_run_says_where_its_time_went(toy_kind, tmp_path):
    """timings.json and the summary's "time:" line: the renders, each item computed (slowest first) and the
    report; a resumed run that computes nothing has no items to time."""
    import json

    path = tmp_path / "toy.toml"
    path.write_text(CAMPAIGN)
    done = validate(path, tmp_path / "run", show_progress=False)
    timings = json.loads((tmp_path / "run" / "timings.json").read_text())
    seconds = [item["seconds"] for item in timings["items"]]
    assert len(seconds) == 2 and seconds == sorted(seconds, reverse=True) and all(s >= 0 for s in seconds)
    assert timings["renders_seconds"] > 0 and timings["report_seconds"] > 0
    # the items' wall time: at least the slowest item's, at most their sum (they run at once, one per core)
    assert max(seconds) <= timings["items_seconds"] <= sum(seconds) + 0.05
    line = next(line for line in done.lines if line.startswith("time: "))
    assert {item["name"] for item in timings["items"]} == {"sharp", "soft"}
    assert "slowest items: " + timings["items"][0]["name"] in line
    again = validate(path, tmp_path / "run", show_progress=False)
    assert json.loads((tmp_path / "run" / "timings.json").read_text())["items"] == []
    assert "slowest items" not in next(line for line in again.lines if line.startswith("time: "))


def test_its_tables_are_checked_like_any_kind(toy_kind, tmp_path):
    path = tmp_path / "toy.toml"
    path.write_text(CAMPAIGN.replace("sigma_px = 3.0", "sigma_px = 30.0"))
    with pytest.raises(VissimInputError, match=r"disc\[1\].sigma_px"):
        validate(path, tmp_path / "run", show_progress=False)
    path.write_text(CAMPAIGN + "[[item]]\nletter = 'K'\n")
    with pytest.raises(VissimInputError, match="add kind = \"dslr\""):
        validate(path, tmp_path / "run", show_progress=False)


def test_an_item_that_fails_is_named_and_its_renders_kept(toy_kind, tmp_path, monkeypatch):
    """A refusal from inside an item (a simulation the campaign's values make impossible) names the configuration
    and its key, and leaves the renders for the next run; no lock is left."""
    from toy_bench import kind as toy

    def refuse(self, key, campaign, index, *rest):
        raise VissimInputError("4 rays miss the cornea back")

    monkeypatch.setattr(toy.ToyKind, "compute_item", refuse)
    path = tmp_path / "toy.toml"
    path.write_text(CAMPAIGN)
    with pytest.raises(VissimInputError, match=r"toy.toml: configuration 'sharp' \(item \w+\): 4 rays miss the "
                                               r"cornea back; its renders are kept"):
        validate(path, tmp_path / "run", show_progress=False)
    assert len(list((tmp_path / "run" / "renders").iterdir())) == 4
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == ["campaign.json", "renders"]
