"""The schematic eyes' dispersion formulas against their sources' tables.

Oracles: visisipy's Navarro index table (Escudero-Sanz & Navarro 1999, Table 1, as quoted in
docs reference page schematic-eyes.md §1); the definitions of n_d and the Abbe number; visisipy's
Le Grand indices at 589.3 nm; Liou–Brennan's formula vanishing at 555 nm. The Navarro formula is
written out again here, independently of the module, to show that the misprinted coefficients
(B1 = −0.040352796, A4 = +1.75835059) miss the table by far.
"""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import (arizona_medium, le_grand_medium, liou_brennan_medium,
                                      navarro_medium)

MEDIA = ("cornea", "aqueous", "lens", "vitreous")
# visisipy / Escudero-Sanz 1999 Table 1: wavelength nm -> (cornea, aqueous, lens, vitreous), as printed.
VISISIPY = {
    458.0: ("1.3828", "1.3445", "1.4292", "1.3428"),
    543.0: ("1.3777", "1.3391", "1.4222", "1.3377"),
    589.3: ("1.376", "1.3374", "1.42", "1.336"),
    632.8: ("1.3747", "1.336", "1.4183", "1.3347"),
}


def _half_last_digit(text: str) -> float:
    return 0.5 * 10.0 ** -len(text.split(".")[1])


@pytest.mark.parametrize("wavelength_nm", sorted(VISISIPY))
def test_navarro_dispersion_reproduces_visisipys_table(wavelength_nm):
    """Within half a unit of the printed last digit (+1e-6), and 2e-4 at 458 nm (the page's
    tolerance there: aqueous 1.34435 against 1.3445). Measured: lens at 589.3 nm 1.41992 against the
    printed 1.42 (8e-5), all others to the printed digits."""
    for medium, printed in zip(MEDIA, VISISIPY[wavelength_nm]):
        tolerance = 2e-4 if wavelength_nm == 458.0 else _half_last_digit(printed) + 1e-6
        assert navarro_medium(medium).index(wavelength_nm) == pytest.approx(float(printed), abs=tolerance), medium


def _navarro_by_hand(lines, wavelength_nm, b1=-0.40352796, a4=-1.75835059):
    """Navarro 1985 eq. (5) written out independently, with B1 and A4 as arguments."""
    rows = [(0.66147196, b1, -0.28046790, 0.03385979), (-4.20146383, 2.73508956, 1.50543784, -0.11593235),
            (6.29834237, -4.69409935, -1.57508650, 0.10293038), (a4, 2.36253794, 0.35011657, -0.02085782)]
    lam2 = (wavelength_nm / 1000.0) ** 2
    return sum((a + b * lam2 + c / (lam2 - 0.028) + d / (lam2 - 0.028) ** 2) * n for (a, b, c, d), n in zip(rows, lines))


CORNEA_LINES = (1.3975, 1.3807, 1.37405, 1.3668)  # Navarro 1985 Table 3: 365, 486.1, 656.3, 1014 nm


def test_the_read_coefficients_agree_with_an_independent_evaluation():
    for w in (400.0, 543.0, 700.0):
        assert navarro_medium("cornea").index(w) == pytest.approx(_navarro_by_hand(CORNEA_LINES, w), abs=1e-12)


def test_the_misprinted_coefficients_would_miss_the_table_by_far():
    """With the paper's printed B1 or A4 the cornea at 543 nm is 1.527 or 6.18, not 1.3777."""
    assert abs(_navarro_by_hand(CORNEA_LINES, 543.0, b1=-0.040352796) - 1.3777) > 0.1
    assert abs(_navarro_by_hand(CORNEA_LINES, 543.0, a4=1.75835059) - 1.3777) > 1.0


def test_navarro_weights_interpolate_the_four_reference_lines():
    """a_i(λ_j) = δ_ij to 1e-3: the formula returns each reference index at its own line."""
    lines_nm = (365.0, 486.1, 656.3, 1014.0)
    for medium, table in (("cornea", CORNEA_LINES), ("lens", (1.4492, 1.42625, 1.4175, 1.4097))):
        for w, n in zip(lines_nm, table):
            assert navarro_medium(medium).index(w) == pytest.approx(n, abs=1.5e-3)


def test_the_lens_n_f_reading_is_not_distinguished_by_visisipys_table():
    """1.42625 (ISET3d) and 1.4263 differ by ≤ 6e-5 in n at 458-633 nm, under the table's last digit."""
    for w in VISISIPY:
        with_isets = _navarro_by_hand((1.4492, 1.42625, 1.4175, 1.4097), w)
        rounded = _navarro_by_hand((1.4492, 1.4263, 1.4175, 1.4097), w)
        assert 0 < rounded - with_isets < 6e-5
        assert navarro_medium("lens").index(w) == pytest.approx(with_isets, abs=1e-12)


@pytest.mark.parametrize("medium, n_d, v_d", [("cornea", 1.377, 57.1), ("aqueous", 1.337, 61.3),
                                              ("lens", 1.42, 51.9), ("vitreous", 1.336, 61.1)])
def test_arizona_media_have_their_n_d_and_abbe_number(medium, n_d, v_d):
    """Schwiegerling 2004: n(589.3) = n_d; V_d = (n_d − 1)/(n_F − n_C) by definition (F 486.1, C 656.3)."""
    m = arizona_medium(medium)
    assert m.index(589.3) == pytest.approx(n_d, abs=1e-12)
    assert (n_d - 1) / (m.index(486.1) - m.index(656.3)) == pytest.approx(v_d, rel=1e-9)


@pytest.mark.parametrize("medium, n_589", [("cornea", 1.3771), ("aqueous", 1.3374), ("lens", 1.42), ("vitreous", 1.336)])
def test_le_grand_dispersion_gives_its_indices_at_589_nm(medium, n_589):
    """visisipy catalog/gullstrand.py indices; ISET3d's n∞ + K/(λ − 130) reproduces them to 5e-5."""
    assert le_grand_medium(medium).index(589.3) == pytest.approx(n_589, abs=5e-5)


def test_liou_brennan_shift_vanishes_at_its_reference_and_falls_with_wavelength():
    """0.0512 − 0.1455·0.555 + 0.0961·0.555² = 4.87e-5 (the formula's own residual at 555 nm);
    normal dispersion: n(400) > n(555) > n(700)."""
    m = liou_brennan_medium("aqueous", 1.336)
    assert m.index(555.0) == pytest.approx(1.336 + 4.87e-5, abs=1e-7)
    assert m.index(400.0) > m.index(555.0) > m.index(700.0)


def test_unknown_medium_and_bad_wavelength_are_one_line_errors():
    with pytest.raises(VissimInputError, match="no medium 'retina'"):
        navarro_medium("retina")
    with pytest.raises(VissimInputError, match="wavelength"):
        navarro_medium("lens").index(np.nan)


def test_the_eyes_wavelength_range_is_the_span_of_navarros_reference_lines():
    """`EYE_WAVELENGTH_RANGE_NM` (checks, which cannot import the optics) is where Navarro's dispersion is an
    interpolation: its first and last reference lines, 365 and 1014 nm (Navarro et al. 1985, eq. 5)."""
    from vissim.checks import EYE_WAVELENGTH_RANGE_NM
    from vissim.optics.eyes.dispersion import NAVARRO_LINES_UM

    assert EYE_WAVELENGTH_RANGE_NM == (1000.0 * NAVARRO_LINES_UM[0], 1000.0 * NAVARRO_LINES_UM[-1])
