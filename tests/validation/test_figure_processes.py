"""A report's figures shared with a helper process: the same figures, in order, whoever drew them."""

import multiprocessing
import os

import pytest

import vissim.validation.engine.figure_processes as figure_processes
from vissim.validation.engine.figure_processes import draw_figures, figure_helper


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
    monkeypatch.setattr(figure_processes, "available_cores", lambda: 2)


def test_shared_figures_are_the_ones_drawn_here_in_order(two_cores):
    advanced = []
    drawn = draw_figures([(square, (x,)) for x in range(9)], lambda: advanced.append(1))
    assert drawn == [x * x for x in range(9)]
    assert len(advanced) == 9  # every figure counted once, wherever it was drawn


def test_a_started_helper_serves_the_figures_and_ends_with_the_block(two_cores):
    with figure_helper("math"):
        assert figure_processes._STARTED
        assert draw_figures([(square, (x,)) for x in range(6)]) == [x * x for x in range(6)]
    assert not figure_processes._STARTED


def test_a_figure_that_fails_fails_the_report(two_cores):
    with pytest.raises(ValueError, match="cannot be drawn"):
        draw_figures([(square, (1,)), (square, (2,)), (refuse, (3,)), (square, (4,)), (refuse, (5,))])


def test_a_dead_helper_leaves_its_figures_to_this_process(two_cores, caplog):
    drawn = draw_figures([(square_here_only, (x,)) for x in range(8)])
    assert drawn == [x * x for x in range(8)]
    assert "figure helper process stopped" in caplog.text
