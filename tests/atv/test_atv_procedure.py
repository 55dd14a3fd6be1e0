"""The Listing 5.1 procedure (phase 1 quasi-random, phase 2 bisection) and the observers."""

import math

import numpy as np
import pytest

from vissim.atv.interactive import ProcedureAborted, PromptObserver, make_person_observer
from vissim.atv.procedure import (
    Observer,
    ProcedureConfig,
    PsychometricFunction,
    SimulatedObserver,
    run_procedure,
)
from vissim.errors import VissimInputError

THRESHOLDS = [0.004, 0.0553, 0.0669, 0.1, 0.2, 0.3966, 0.75, 0.95]  # 0.0553..0.3966: values printed in Appendix A


@pytest.mark.parametrize("threshold", THRESHOLDS)
@pytest.mark.parametrize("seed", [0, 1, 7, 2015])
def test_ideal_observer_threshold_recovered_within_half_the_resolution(threshold, seed):
    config = ProcedureConfig(resolution_code=0.001)
    result = run_procedure(SimulatedObserver.ideal(threshold), config, seed=seed)
    # An observer that sees exactly x >= T keeps T inside the final interval (lower, upper].
    assert result.lower_code < threshold <= result.upper_code
    assert result.upper_code - result.lower_code <= config.resolution_code
    assert abs(result.threshold_code - threshold) <= config.resolution_code / 2


@pytest.mark.parametrize("resolution", [0.01, 0.004, 1 / 255])
def test_resolution_sets_the_final_width(resolution):
    result = run_procedure(SimulatedObserver.ideal(0.3), ProcedureConfig(resolution_code=resolution), seed=3)
    assert result.upper_code - result.lower_code <= resolution
    assert result.upper_code - result.lower_code > resolution / 2  # no wasted presentations


def test_phase_one_shows_multiples_of_a_tenth_strictly_inside_and_ends_at_width_a_tenth():
    result = run_procedure(SimulatedObserver.ideal(0.437), seed=11)
    phase1 = [p.intensity_code for p in result.presentations if p.phase == 1]
    assert phase1 and all(abs(x * 10 - round(x * 10)) < 1e-12 and 0.0 < x < 1.0 for x in phase1)
    lo, hi = result.phase1_interval_code
    assert hi - lo == pytest.approx(0.1) and lo == pytest.approx(0.4)
    assert len([p for p in result.presentations if p.phase == 2]) == ProcedureConfig().phase2_steps == 7


def test_same_seed_same_run_and_different_seeds_differ():
    def run(seed):
        obs = SimulatedObserver(PsychometricFunction(0.2, slope=6.0, guess_rate=0.02, lapse_rate=0.02), seed=seed)
        return run_procedure(obs, seed=seed)

    assert run(5).presentations == run(5).presentations
    assert len({tuple(p.intensity_code for p in run(s).presentations) for s in range(6)}) > 1


def test_noisy_observer_threshold_is_recovered_on_average():
    # Weibull exponent 20 in code values, no guesses or lapses: 300 runs, the median relative error
    # of the bisection estimate is within 2 % and 90 % of runs land within 10 % (measured spread ~4 %).
    errors = []
    for seed in range(300):
        obs = SimulatedObserver(PsychometricFunction(0.1, slope=20.0), seed=seed)
        errors.append(run_procedure(obs, seed=seed).threshold_code / 0.1 - 1.0)
    errors = np.array(errors)
    assert abs(np.median(errors)) < 0.02
    assert np.mean(np.abs(errors) < 0.10) > 0.9


def test_psychometric_function_is_one_half_at_threshold_with_equal_guess_and_lapse():
    f = PsychometricFunction(0.3, slope=3.5, guess_rate=0.05, lapse_rate=0.05)
    assert f.probability_seen(0.3) == pytest.approx(0.5)
    assert f.probability_seen(0.0) == pytest.approx(0.05) and f.probability_seen(100.0) == pytest.approx(0.95)
    p = f.probability_seen(np.linspace(0, 1, 11))
    assert np.all(np.diff(p) >= 0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"threshold": -0.1}, "threshold must be a positive display code value"),
        ({"threshold": 0.1, "slope": 0}, "psychometric slope must be > 0"),
        ({"threshold": 0.1, "lapse_rate": 0.6}, r"lapse_rate must be at least 0 and less than 0.5"),
    ],
)
def test_psychometric_function_validates(kwargs, message):
    with pytest.raises(VissimInputError, match=message):
        PsychometricFunction(**kwargs)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"resolution_code": 0.2}, "phase-2 resolution must be within"),
        ({"phase1_step_code": 0.3}, "phase-1 step must divide the range"),
        ({"minimum_code": 0.5, "maximum_code": 0.5}, "intensity range must satisfy"),
        ({"method": "staircase"}, "phase-2 method must be 'bisection'"),
    ],
)
def test_procedure_config_validates(kwargs, message):
    with pytest.raises(VissimInputError, match=message):
        ProcedureConfig(**kwargs)


def test_invisible_stimulus_ends_at_the_top_and_is_flagged():
    result = run_procedure(SimulatedObserver.ideal(5.0), seed=0)
    assert result.never_seen and result.upper_code == pytest.approx(1.0)


def test_prompt_observer_runs_the_procedure_headless_with_an_injected_input():
    # A scripted person with threshold 0.25: answers from the intensity in the prompt.
    prompts = []

    def ask(prompt):
        prompts.append(prompt)
        value = float(prompt.split("code value ")[1].split(";")[0])
        return "y" if value >= 0.25 else "n"

    observer = PromptObserver(ask)
    assert isinstance(observer, Observer)
    result = run_procedure(observer, seed=4)
    assert abs(result.threshold_code - 0.25) <= 0.001
    assert len(prompts) == len(result.presentations)


def test_prompt_observer_reasks_on_unreadable_answers_and_aborts_on_quit():
    answers = iter(["maybe", "", "Y", "q"])
    observer = PromptObserver(lambda prompt: next(answers))
    assert observer.seen(0.5) is True
    with pytest.raises(ProcedureAborted, match="quit"):
        observer.seen(0.4)


def test_prompt_observer_aborts_at_end_of_input():
    def ask(prompt):
        raise EOFError

    with pytest.raises(ProcedureAborted, match="input ended"):
        PromptObserver(ask).seen(0.5)


def test_person_observer_falls_back_to_the_terminal_without_a_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert isinstance(make_person_observer("auto", ask=lambda p: "y"), PromptObserver)
    with pytest.raises(VissimInputError, match="no display"):
        make_person_observer("window")


def test_ideal_observer_is_deterministic_even_without_a_seed():
    obs = SimulatedObserver(PsychometricFunction(0.2, slope=math.inf), seed=None)
    assert obs.seen(0.2) and not obs.seen(0.1999)


@pytest.mark.filterwarnings("ignore:.*non-interactive.*:UserWarning")
def test_window_observer_lights_one_pixel_and_reads_the_keys(monkeypatch):
    # Headless: the Agg backend stands in for the window; key presses are injected through pause().
    from types import SimpleNamespace

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vissim.atv.interactive import WindowObserver

    observer = WindowObserver(size_px=11, pyplot=plt)
    keys = iter(["x", "y", "n", "q"])  # an unrelated key is ignored
    monkeypatch.setattr(plt, "pause", lambda seconds: observer._on_key(SimpleNamespace(key=next(keys))))
    try:
        assert observer.seen(0.3) is True
        frame = observer._frame
        assert frame[5, 5].tolist() == [0.3, 0.3, 0.3] and frame.sum() == pytest.approx(0.9)  # one grey pixel
        assert observer.seen(0.2) is False
        with pytest.raises(ProcedureAborted):
            observer.seen(0.1)
    finally:
        observer.close()


def test_a_huge_slope_is_the_step_function_limit_without_overflow_warnings():
    # (x/t)^s overflows to inf for s = 1e300 above threshold: P(seen) = 1 - 2^-inf = 1 exactly
    steep = PsychometricFunction(0.1, slope=1e300)
    assert steep.probability_seen(0.2) == 1.0 and steep.probability_seen(0.05) == 0.0
