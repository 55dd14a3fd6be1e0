"""The CIE 1924 photopic luminous efficiency V(λ) and the named spectra (`vissim.spectra`).

Source of the quoted values: CIE 018:2019 / ISO 23539:2005, the V(λ) table at 5 nm (the same numbers
as the CIE 1931 2° observer's ȳ(λ); CVRL, "CIE 1924 photopic V(λ)", cvrl.org). The integral over the
CIE's 1 nm table, 360-830 nm, is 106.857 nm (∫ V dλ; K_m = 683 lm/W times it is the lumens of 1 W/nm
of equal-energy light).
"""

import math

import pytest

from vissim.errors import VissimInputError
from vissim.spectra import (PHOTOPIC_TABLE_START_NM, PHOTOPIC_TABLE_STEP_NM, PHOTOPIC_V_5NM, named_spectrum,
                            photopic_v, photopic_weights)

#: ∫ V(λ) dλ over the CIE's 1 nm table (360-830 nm), nm.
V_INTEGRAL_NM = 106.857


@pytest.mark.parametrize(("wavelength_nm", "v"), [(380, 0.000039), (450, 0.038), (500, 0.323), (507.5, None),
                                                  (510, 0.503), (550, 0.99495), (555, 1.0), (600, 0.631),
                                                  (650, 0.107), (700, 0.004102), (780, 0.000015)])
def test_the_table_holds_the_cie_values(wavelength_nm, v):
    if v is None:  # between entries: the straight line through its neighbours (0.4073 at 505, 0.503 at 510)
        v = 0.5 * (0.4073 + 0.503)
    assert photopic_v(wavelength_nm) == pytest.approx(v, rel=1e-12, abs=1e-15)


def test_the_table_spans_380_to_780_nm_every_5_nm_and_peaks_at_555_nm():
    assert (PHOTOPIC_TABLE_START_NM, PHOTOPIC_TABLE_STEP_NM, len(PHOTOPIC_V_5NM)) == (380.0, 5.0, 81)
    assert PHOTOPIC_V_5NM.index(max(PHOTOPIC_V_5NM)) == (555 - 380) // 5
    assert photopic_v(554.0) < 1.0 and photopic_v(556.0) < 1.0


def test_the_5_nm_sum_is_the_published_integral():
    # The 5 nm table summed with 5 nm steps over 380-780 nm: 106.8566; the 1 nm table's 106.857 within 1e-3 nm
    # (its tails beyond 380-780 nm hold 1e-4 nm, and its 1 nm steps interpolate the 5 nm ones).
    assert sum(PHOTOPIC_V_5NM) * PHOTOPIC_TABLE_STEP_NM == pytest.approx(V_INTEGRAL_NM, abs=1e-3)


def test_the_photopic_spectrum_samples_v_every_10_nm_from_400_to_700_nm():
    wavelengths, weights = named_spectrum("photopic")
    assert wavelengths == tuple(400.0 + 10.0 * k for k in range(31))
    assert weights == photopic_weights(wavelengths)
    # The sampled sum holds all but 0.04 % of the integral: its tails beyond 400-700 nm are that small.
    assert sum(weights) * 10.0 == pytest.approx(V_INTEGRAL_NM, rel=1e-3)
    halved, halved_weights = named_spectrum("photopic", step_nm=5.0)
    assert len(halved) == 61 and sum(halved_weights) * 5.0 == pytest.approx(V_INTEGRAL_NM, rel=1e-3)


def test_the_equal_energy_spectrum_weights_every_wavelength_alike():
    wavelengths, weights = named_spectrum("equal-energy")
    assert len(wavelengths) == 31 and set(weights) == {1.0}


@pytest.mark.parametrize("wavelength_nm", [379.9, 780.1, math.nan, "green"])
def test_v_refuses_wavelengths_outside_its_table(wavelength_nm):
    with pytest.raises(VissimInputError, match="nm"):
        photopic_v(wavelength_nm)


def test_unknown_spectra_and_uneven_steps_are_refused():
    with pytest.raises(VissimInputError, match="scotopic"):
        named_spectrum("scotopic")
    with pytest.raises(VissimInputError, match="7 nm"):
        named_spectrum("photopic", step_nm=7.0)


def test_the_table_imports_without_numpy():
    """The renderer's response reads the same table: importing it costs no numerical library."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import vissim

    root = str(Path(vissim.__file__).resolve().parents[1])  # this checkout, whatever the interpreter has installed
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    code = "import sys, vissim.spectra; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env=env).stdout.strip()
    assert out == "False"
