"""A report's figures shared with a helper process: the same figures, in order, whoever drew them."""

import multiprocessing
import os

import pytest

import vissim.validation.engine.helper_process as helper_process
from vissim.validation.engine.helper_process import campaign_helper, draw_figures


def square(x):
    return x * x


def square_here_only(x):
    """Kills the helper process the first time it is asked to draw (the helper dies, as when killed for memory)."""
    if multiprocessing.parent_process() is not None:
        os._exit(1)
    return x * x


def refuse(x):
    raise ValueError(f"figure {x} cannot be drawn")


@pytest.fixture
def two_cores(monkeypatch):
    monkeypatch.setattr(helper_process, "available_cores", lambda: helper_process.HELPER_CORES)


def test_shared_figures_are_the_ones_drawn_here_in_order(two_cores):
    advanced = []
    drawn = draw_figures([(square, (x,)) for x in range(9)], lambda: advanced.append(1))
    assert drawn == [x * x for x in range(9)]
    assert len(advanced) == 9  # every figure counted once, wherever it was drawn


def test_a_started_helper_serves_the_figures_and_ends_with_the_block(two_cores):
    with campaign_helper("math"):
        assert helper_process.started_helper() is not None
        assert draw_figures([(square, (x,)) for x in range(6)]) == [x * x for x in range(6)]
    assert helper_process.started_helper() is None


def test_a_figure_that_fails_fails_the_report(two_cores):
    with pytest.raises(ValueError, match="cannot be drawn"):
        draw_figures([(square, (1,)), (square, (2,)), (refuse, (3,)), (square, (4,)), (refuse, (5,))])


def test_a_dead_helper_leaves_its_figures_to_this_process(two_cores, caplog):
    drawn = draw_figures([(square_here_only, (x,)) for x in range(8)])
    assert drawn == [x * x for x in range(8)]
    assert "helper process stopped" in caplog.text


def test_a_refusal_inside_the_block_stops_the_helper_at_once(two_cores, tmp_path, monkeypatch):
    # The helper imports a module that would take a minute; a refusal meanwhile terminates it (SIGTERM) rather
    # than waiting for the import.
    (tmp_path / "minute_long_import.py").write_text("import time\ntime.sleep(60)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(RuntimeError, match="refused"):
        with campaign_helper("minute_long_import"):
            processes = [helper_process.started_helper().process]
            raise RuntimeError("refused")
    assert [process.exitcode for process in processes] == [-15]


def test_the_blocks_end_stops_the_helper_rather_than_waiting_for_its_teardown(two_cores):
    # Its work handed back, the helper has nothing left: it is stopped (SIGTERM), not left to tear its interpreter
    # down while this process waits; exit code -15, not 0.
    with campaign_helper("json"):
        assert draw_figures([(square, (x,)) for x in range(4)]) == [0, 1, 4, 9]
        processes = [helper_process.started_helper().process]
    assert [process.exitcode for process in processes] == [-15]


def test_no_helper_beside_more_cores_than_it_was_measured_for(monkeypatch):
    # On more than HELPER_CORES cores a campaign's items run on one thread a core, as before the helper.
    monkeypatch.setattr(helper_process, "available_cores", lambda: helper_process.HELPER_CORES + 2)
    with campaign_helper("json"):
        assert helper_process.started_helper() is None
