"""Published human MTF fits (vissim.optics.eyes.measured.published) against their stated values.

Oracles: the values quoted in ../shared/reference/human-optics.md for Watson 2013 (read from the paper's
abstract and ISETBio's humanAchromaticOTF.m), and the double-exponential form with the A, B, C written here
from that file's tables (Artal & Navarro 1994; Navarro, Artal & Williams 1993).
"""

import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.published import artal_navarro_1994_mtf, navarro_1993_mtf, watson_2013_mtf

F = [5.0, 10.0, 20.0, 30.0]


@pytest.mark.parametrize("pupil, stated", [(3.0, [0.816, 0.563, 0.282, 0.164]), (4.0, [0.713, 0.427, 0.197, 0.115])])
def test_watson_2013_gives_its_stated_values(pupil, stated):
    np.testing.assert_allclose(watson_2013_mtf(F, pupil), stated, atol=6e-4)


def test_watson_2013_is_one_at_zero_and_never_above_the_square_root_of_diffraction():
    f = np.linspace(0, 120, 241)
    m = watson_2013_mtf(f, 4.0)
    assert m[0] == pytest.approx(1.0)
    cutoff = 4.0 * math.pi * 1e6 / (555.0 * 180.0)
    s = np.minimum(f / cutoff, 1.0)
    diffraction = (2 / math.pi) * (np.arccos(s) - s * np.sqrt(1 - s * s))
    assert np.all(m <= np.sqrt(diffraction) + 1e-12) and np.all(np.diff(m) <= 1e-12)


@pytest.mark.parametrize("fit, argument, abc", [(artal_navarro_1994_mtf, 3.0, (0.16, 0.05, 0.28)),
                                                (artal_navarro_1994_mtf, 6.0, (0.31, 0.06, 0.20)),
                                                (navarro_1993_mtf, 20.0, (0.328, 0.038, 0.14)),
                                                (navarro_1993_mtf, 40.0, (0.82, 0.064, 0.09))])
def test_the_double_pass_fits_are_their_tables(fit, argument, abc):
    a, b, c = abc
    f = np.array(F)
    np.testing.assert_allclose(fit(f, argument), (1 - c) * np.exp(-a * f) + c * np.exp(-b * f), rtol=1e-12)
    assert fit([0.0], argument)[0] == pytest.approx(1.0)


@pytest.mark.parametrize("call, words", [(lambda: watson_2013_mtf(F, 7.0), "2-6 mm pupils, got 7.0 mm"),
                                         (lambda: artal_navarro_1994_mtf(F, 5.0), "tabulate pupils of 2.5, 3, 4"),
                                         (lambda: navarro_1993_mtf(F, 15.0), "eccentricities of 0, 5, 10"),
                                         (lambda: watson_2013_mtf([-1.0], 3.0), "cycles/deg >= 0")])
def test_what_a_fit_does_not_cover_is_refused(call, words):
    with pytest.raises(VissimInputError, match=words):
        call()
