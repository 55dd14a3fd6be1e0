"""The power models: magnification tied to power through the bench, and never through its lenses."""

import numpy as np
import pytest

from vissim.bench.dslr.bench import DslrBench
from vissim.fit.power_model import power_model
from vissim.optics.rx.trial_lens import TrialLens


@pytest.mark.parametrize("name", ["bench", "free", "none"])
def test_a_bench_with_lenses_gives_the_same_model_as_without(name):
    with_lens = power_model(name, DslrBench(lenses=(TrialLens(-2.0),)))
    without = power_model(name, DslrBench())
    nuisances = (0.0,) * len(without.nuisance_names)
    a, b = with_lens.optics((1.0, 0.2, -0.3), nuisances), without.optics((1.0, 0.2, -0.3), nuisances)
    assert np.allclose(a.defocus, b.defocus) and np.allclose(a.magnification, b.magnification)


def test_the_bench_model_magnifies_for_plus_and_minifies_for_minus():
    model = power_model("bench", DslrBench())
    plus, minus = model.optics((2.0, 0.0, 0.0)), model.optics((-2.0, 0.0, 0.0))
    # vergence theory for the thick +2 D crown lens at 10 mm: +1.9925 D, magnification 1.0219 (render provenance)
    assert plus.effective_power[0, 0] == pytest.approx(1.9925, abs=1e-4)
    assert plus.magnification[0, 0] == pytest.approx(1.0219, abs=1e-4)
    assert minus.effective_power[0, 0] < 0 and minus.magnification[0, 0] < 1.0
