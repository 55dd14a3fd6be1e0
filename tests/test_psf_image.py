"""PSF images (``normalise="total"``): computed for any field, summing to the energy the field holds.

Blur kernels (the default, ``normalise="field"``) keep the refusal of a field leaving more than
1 % outside (``tests/test_psf.py::test_field_too_small_for_the_blur_is_an_error``).
"""

import logging
import math

import numpy as np
import pytest
from scipy import integrate
from scipy.special import j0, j1

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.psf.metrics import encircled_energy
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import ARCMIN_PER_RAD

WAVELENGTH_NM = 550.0


def airy_energy_in_rectangle(x0, x1, y0, y1, lambda_over_d):
    """Fraction of an Airy pattern inside [x0, x1] x [y0, y1] (arcmin, containing the centre).

    Radially symmetric, so it is the mean over directions of the encircled energy out to the
    rectangle's edge, EE(r) = 1 - J0^2(pi r) - J1^2(pi r), r in lambda/D (Born & Wolf 8.5.2);
    one quadrature over the angle, sharing no code with the PSF.
    """
    def reach(phi):
        c, s = math.cos(phi), math.sin(phi)
        rx = x1 / c if c > 0 else (x0 / c if c < 0 else math.inf)
        ry = y1 / s if s > 0 else (y0 / s if s < 0 else math.inf)
        return min(rx, ry) / lambda_over_d

    def encircled(phi):
        v = math.pi * reach(phi)
        return 1.0 - j0(v) ** 2 - j1(v) ** 2

    corners = sorted({math.atan2(y, x) % (2 * math.pi) for x in (x0, x1) for y in (y0, y1)})
    total, _ = integrate.quad(encircled, 0.0, 2 * math.pi, points=corners, limit=500, epsabs=1e-12)
    return total / (2 * math.pi)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("size_px, arcmin_per_px, pupil_mm", [(256, 0.05, 3.0), (255, 0.05, 3.0), (101, 0.1, 2.0)])
def test_a_psf_image_of_any_field_sums_to_the_airy_energy_that_field_holds(size_px, arcmin_per_px, pupil_mm, dtype):
    # The user's case first: 256 px at 0.05'/px through 3 mm leaves 1.8 % outside, refused as a kernel.
    psf = compute_psf(Wavefront.zero(pupil_mm), arcmin_per_px=arcmin_per_px, size_px=size_px, normalise="total",
                      dtype=dtype)
    assert psf.normalisation == "total" and psf.as_json()["normalisation"] == "total"
    # Its sum is the energy it records (to the dtype's round-off over the field).
    assert float(psf.data.sum(dtype=np.float64)) == pytest.approx(psf.energy_in_field, rel=1e-5 if dtype == np.float32 else 1e-12)
    # Pixel edges: the origin at [N//2, N//2], so an even field reaches half a pixel further left/up.
    centre = size_px // 2
    low, high = (-centre - 0.5) * arcmin_per_px, (size_px - centre - 0.5) * arcmin_per_px
    oracle = airy_energy_in_rectangle(low, high, low, high, WAVELENGTH_NM * 1e-6 / pupil_mm * ARCMIN_PER_RAD)
    assert oracle < 0.99  # the field really is one a kernel would be refused
    # Measured: within 4e-5 (the matrix transform's folded skirt); the bound by construction is 2e-3.
    assert psf.energy_in_field == pytest.approx(oracle, abs=1e-4)


def test_a_small_defocused_image_is_the_centre_of_a_large_one():
    # Oracle: a 255 px field holding 99.95 % of a -4 D, 6 mm PSF (blur radius 41'), on its own
    # internal grid, summed over the central 32 px: the 32 px image's pixels and sum.
    front = Wavefront.from_prescription(Prescription(-4.0), 6.0)
    small = compute_psf(front, arcmin_per_px=1.0, size_px=32, normalise="total", dtype=np.float64)
    large = compute_psf(front, arcmin_per_px=1.0, size_px=255, normalise="total", dtype=np.float64)
    window = large.data[127 - 16:127 + 16, 127 - 16:127 + 16]
    assert large.energy_in_field > 0.999 and small.energy_in_field < 0.25
    assert small.energy_in_field == pytest.approx(float(window.sum()), abs=1e-6)
    np.testing.assert_allclose(small.data, window, atol=1e-4 * window.max())


def test_more_than_one_percent_outside_is_one_warning_and_less_none(caplog):
    front = Wavefront.zero(3.0)
    with caplog.at_level(logging.WARNING, logger="vissim.optics.psf.compute"):
        compute_psf(front, arcmin_per_px=0.05, size_px=256, normalise="total")
    assert len(caplog.records) == 1 and "1.8 % of the PSF's energy falls outside the 256 px field" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="vissim.optics.psf.compute"):
        held = compute_psf(front, arcmin_per_px=0.25, size_px=256, normalise="total")
    assert held.energy_in_field > 0.99 and not caplog.records


def test_the_image_and_the_kernel_differ_only_by_the_energy_in_field():
    front = Wavefront.from_prescription(Prescription(-1.0), 3.0)
    kernel = compute_psf(front, arcmin_per_px=0.5, size_px=64, dtype=np.float64)
    image = compute_psf(front, arcmin_per_px=0.5, size_px=64, dtype=np.float64, normalise="total")
    assert kernel.normalisation == "field" and kernel.data.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(image.data, kernel.data * kernel.energy_in_field, rtol=1e-12, atol=1e-15)
    # Metrics read either: the encircled energy of the total is the same number.
    assert encircled_energy(image, 2.0) == pytest.approx(encircled_energy(kernel, 2.0), rel=1e-12)
    assert encircled_energy(image, 2.0, of_total=False) == pytest.approx(encircled_energy(kernel, 2.0, of_total=False),
                                                                        rel=1e-12)


def test_a_psf_image_is_refused_as_a_blur_kernel():
    image = compute_psf(Wavefront.zero(3.0), arcmin_per_px=1.0, size_px=33, normalise="total")
    with pytest.raises(VissimInputError, match="no blur kernel"):
        blur_image(np.ones((40, 40), np.float32), image, arcmin_per_px=1.0)


def test_an_unknown_normalisation_is_refused():
    with pytest.raises(VissimInputError, match="normalise must be one of field, total"):
        compute_psf(Wavefront.zero(3.0), arcmin_per_px=1.0, size_px=33, normalise="peak")
