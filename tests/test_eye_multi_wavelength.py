"""One trace for many wavelengths: `trace_eye_wavefronts` equals `trace_eye_wavefront` at each wavelength alone.

The rays of every wavelength travel together, each with its own media indices; the pupil search runs for all of
them in the same traces.  Nothing but the indices differs, so the fronts must agree to round-off.  The issue's
bound is 1e-4 waves RMS of the difference; the test holds them to it over the pupil (the Zernike difference
in quadrature, piston included), on axis, at 40 degrees with a 6 mm pupil, with an iris given, through a lens, and
through a GRIN lens (Liou-Brennan).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.optics.eyes.models import EYE_MODELS
from vissim.optics.rx.trial_lens import TrialLensSetup
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront, trace_eye_wavefronts

WAVELENGTHS_NM = (450.0, 555.0, 589.3, 700.0)
BOUND_WAVES = 1e-4


def _rms_waves(one, other) -> float:
    keys = set(one.zernike_um) | set(other.zernike_um)
    difference_um = math.sqrt(sum((one.zernike_um.get(k, 0.0) - other.zernike_um.get(k, 0.0)) ** 2 for k in keys))
    return difference_um / (one.wavelength_nm * 1e-3)


@pytest.mark.parametrize("model, field, pupil", [("navarro-1985", (0.0, 0.0), {"pupil_mm": 4.0}),
                                                 ("navarro-1985", (40.0, 0.0), {"pupil_mm": 6.0}),
                                                 ("escudero-sanz-1999", (10.0, -5.0), {"iris_mm": 5.0}),
                                                 ("liou-brennan-1997", (0.0, 0.0), {"pupil_mm": 3.0})])
def test_one_trace_equals_each_wavelength_alone(model, field, pupil):
    eye = EYE_MODELS[model](0.0)
    together = trace_eye_wavefronts(eye, WAVELENGTHS_NM, field, samples=17, **pupil)
    for front in together:
        alone = trace_eye_wavefront(eye, front.wavelength_nm, field, samples=17, **pupil)
        assert _rms_waves(front, alone) < BOUND_WAVES
        assert front.entrance_pupil_mm == pytest.approx(alone.entrance_pupil_mm, abs=1e-9)
        assert front.iris_mm == pytest.approx(alone.iris_mm, abs=1e-9)
        assert np.allclose(front.image_point_mm, alone.image_point_mm, atol=1e-9, rtol=0.0)
    # the wavelengths differ: the test would not pass by tracing one wavelength for all
    assert abs(together[0].zernike_um[(2, 0)] - together[-1].zernike_um[(2, 0)]) > 0.1


def test_one_trace_through_a_lens_equals_each_alone():
    """A -3 D x 90 crown-glass trial lens, realistically thick, 12 mm in front: its dispersion joins the media's."""
    from vissim.bench.atv.tube import atv_trial_lens

    eye = EYE_MODELS["navarro-1985"](0.0)
    lenses = TrialLensSetup((atv_trial_lens(-3.0, -1.0, 90.0),), 12.0, math.inf)
    together = trace_eye_wavefronts(eye, WAVELENGTHS_NM, (5.0, 0.0), pupil_mm=4.0, samples=17, lenses=lenses)
    for front in together:
        alone = trace_eye_wavefront(eye, front.wavelength_nm, (5.0, 0.0), pupil_mm=4.0, samples=17, lenses=lenses)
        assert _rms_waves(front, alone) < BOUND_WAVES
