"""Long steps report progress through one callback, ``progress(stage, done, total)`` (vissim.progress).

Oracles: the counts the run itself states (renders made, items, report steps); every stage's
counts rise by one from 1 to its total, and nothing is printed by the library.  Nothing is timed.
"""

import io

import pytest

from fake_bench import fake_render
from test_harness import TINY

from vissim.progress import counter, terminal_progress
from vissim.validation.engine.validate import rebuild_report
from vissim.validation.engine.runner import run_campaign


def stages(calls):
    """{stage: [done, ...]} and {stage: {total, ...}} in the order reported."""
    done, totals = {}, {}
    for stage, count, total in calls:
        done.setdefault(stage, []).append(count)
        totals.setdefault(stage, set()).add(total)
    return done, totals


@pytest.mark.slow  # a whole campaign or fit: run with -m slow
def test_a_campaign_reports_each_render_item_and_report_step_once_in_order(campaign_file, tmp_path, capsys):
    calls = []
    run_dir = tmp_path / "run"
    summary = run_campaign(campaign_file(TINY), run_dir, render=fake_render,
                           progress=lambda *call: calls.append(call))
    rebuild_report(run_dir, progress=lambda *call: calls.append(call))
    done, totals = stages(calls)
    assert totals["rendering"] == {summary.renders_made} and totals["items"] == {summary.items_total}
    for stage, counts in done.items():
        (total,) = totals[stage]
        assert counts == list(range(1, total + 1)), stage
    assert set(done) == {"rendering", "items", "figures", "report"}
    assert capsys.readouterr().out == ""  # the library reported, it did not print


def test_counter_counts_steps_and_is_silent_without_a_callback():
    calls = []
    step = counter(lambda *call: calls.append(call), "stage", 3)
    for _ in range(3):
        step()
    assert calls == [("stage", 1, 3), ("stage", 2, 3), ("stage", 3, 3)]
    counter(None, "stage", 3)()  # no callback: nothing to call, no error


def test_no_bars_are_drawn_where_standard_error_is_not_a_terminal():
    stream = io.StringIO()
    with terminal_progress(stream) as progress:
        assert progress is None
    assert stream.getvalue() == ""
