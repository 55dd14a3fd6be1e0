"""The PSF's field: the energy-outside estimate, the refusal, and the suggested size.

The oracle for each case is the computed PSF itself on a large field (its accuracy is pinned
by ``tests/test_psf_accuracy.py``), cropped to smaller squares: the energy outside a square is
then measured, not estimated.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import j1

from vissim.errors import FieldTooSmallError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.psf.field_size import airy_tail, energy_outside_field, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront

WAVELENGTH_NM = 550.0


def defocus(waves, pupil_mm):
    diopters = 2 * waves * WAVELENGTH_NM * 1e-6 / (pupil_mm / 2) ** 2 * 1e3  # W020 = P r^2 / 2
    return Wavefront.from_prescription(Prescription(-diopters), pupil_mm)


CASES = {
    "airy": Wavefront.zero(3.0),
    "defocus 1 wave": defocus(1, 4.0),
    "defocus 4 waves": defocus(4, 4.0),
    "defocus 16 waves": defocus(16, 4.0),
    "astigmatism": Wavefront({(2, -2): 0.3}, 4.0),
    "coma": Wavefront({(3, 1): 0.3, (2, 0): 0.2}, 5.0),
    "-1.00 -0.50 x 30": Wavefront.from_prescription(Prescription.parse("-1.00 -0.50 x 30"), 3.6),
}
STEP = 0.25


@pytest.fixture(scope="module")
def measured():
    """Each case's energy outside centred odd squares, from one PSF on a large field."""
    out = {}
    for name, front in CASES.items():
        size = suggested_size_px(front, STEP) * 2 + 1
        psf = compute_psf(front, arcmin_per_px=STEP, size_px=size)
        absolute = psf.data * psf.energy_in_field
        c = size // 2
        sizes = np.arange(9, size, 2)
        outside = np.array([1.0 - absolute[c - n // 2: c + n // 2 + 1, c - n // 2: c + n // 2 + 1].sum() for n in sizes])
        out[name] = (front, dict(zip(sizes.tolist(), outside.tolist())))
    return out


def test_airy_tail_is_the_integrated_airy_pattern():
    # 1 - EE(r) by quadrature of the Airy intensity (2 J1(v)/v)^2, v = pi r (Born & Wolf 8.5.2):
    # EE(v) = int_0^v 2 J1(t)^2 / t dt.  Tolerance 1e-5 absolute (the table's interpolation).
    for r in (0.3, 1.22, 2.0, 7.5, 20.0, 63.0):
        v = math.pi * r
        energy, _ = quad(lambda t: 2 * j1(t) ** 2 / t, 0, v, limit=400)
        assert float(airy_tail(np.array(r))) == pytest.approx(1 - energy, abs=1e-5), r


def test_airy_tail_at_its_limits():
    # Nothing lies within a radius <= 0, all of it within an infinite one; beyond the table, the asymptote
    # 2 / (pi^2 r) (Born & Wolf's large-v limit); NaN stays NaN.
    r = np.array([-3.0, -0.0, 0.0, np.inf, -np.inf, 100.0, np.nan])
    tail = airy_tail(r)
    np.testing.assert_array_equal(tail[:5], [1.0, 1.0, 1.0, 0.0, 1.0])
    assert tail[5] == pytest.approx(2.0 / (math.pi**2 * 100.0), rel=1e-12)
    assert np.isnan(tail[6])


@pytest.mark.parametrize("name", list(CASES))
def test_estimates_bracket_the_measured_energy_outside(measured, name):
    # Near the 1 % limit (0.5-2 % outside) the conservative estimate, which sizes fields, is
    # 0.9-2.2x the measured fraction (docs/conventions.md).  The plain estimate, which refuses
    # before computing when above 1.5 %, is never above 1.3x the measured fraction (0.3-5 %
    # outside), so that early refusal is never unfair.
    front, outside = measured[name]
    for size, fraction in outside.items():
        args = (front, front.pupil_diameter_mm, [WAVELENGTH_NM], [1.0], STEP, size)
        if 0.005 <= fraction <= 0.02:
            conservative = energy_outside_field(*args)
            assert 0.9 * fraction <= conservative <= 2.2 * fraction, (size, fraction, conservative)
        if 0.003 <= fraction <= 0.05:
            plain = energy_outside_field(*args, conservative=False)
            assert plain <= 1.3 * fraction, (size, fraction, plain)


@pytest.mark.parametrize("name", ["airy", "defocus 4 waves", "-1.00 -0.50 x 30"])
def test_refusal_follows_the_measured_energy(measured, name):
    # Issue 12: refuse only when more than 1 % would fall outside (a 0.05 % band for the energy
    # the pupil sampling folds back, at most 0.2 %, docs/conventions.md), and name a size that
    # does hold 99 %.
    front, outside = measured[name]
    for size, fraction in outside.items():
        if abs(fraction - 0.01) < 0.0005 or not 0.002 < fraction < 0.04:
            continue
        if fraction < 0.01:
            compute_psf(front, arcmin_per_px=STEP, size_px=size)
            continue
        with pytest.raises(FieldTooSmallError, match="at least") as refused:
            compute_psf(front, arcmin_per_px=STEP, size_px=size)
        named = int(str(refused.value).split("at least ")[1].split(" px")[0])
        assert outside.get(named, 0.0) <= 0.01, (size, named)


@pytest.mark.parametrize("name", list(CASES))
def test_suggested_size_holds_99_percent(measured, name):
    front, outside = measured[name]
    size = suggested_size_px(front, STEP)
    assert size % 2 == 1 and outside[size] <= 0.01

