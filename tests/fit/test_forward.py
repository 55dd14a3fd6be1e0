"""The fit's forward model against vissim's PSF core: orientation, blur size, shift sign.

Oracle: :func:`vissim.optics.psf.compute.compute_psf` in geometric mode, a histogram of traced rays
through the same wavefront (pinned for orientation by ``tests/test_psf.py``), convolved by
:func:`vissim.optics.blur.convolve.blur_image`.  The forward model uses the analytic transfer function of
the uniform ellipse instead; the two share only the prescription -> defocus convention.
"""

import numpy as np
import pytest

from vissim.charts import optotype_tile
from vissim.fit.forward import ForwardModel, _jinc
from vissim.optics.blur.convolve import blur_image
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.blur.resample import magnify
from vissim.optics.pupil.wavefront import Wavefront
import scipy.special


def _letter():
    return optotype_tile("K", 1.0, arcmin_per_px=1.0, size_px=(96, 96)).pixels.astype(np.float64)


@pytest.mark.parametrize("rx", ["-2.00 DS", "plano -2.00 x 30", "+1.00 -1.50 x 120"])
def test_analytic_geometric_blur_matches_the_ray_traced_psf(rx):
    reference = _letter()
    prescription = Prescription.parse(rx)
    defocus = -np.asarray(prescription.power_matrix())  # the camera's excess power is -Rx
    psf = compute_psf(Wavefront.from_prescription(prescription, 3.6), arcmin_per_px=1.0, size_px=61,
                      mode="geometric", pixel="sample")
    oracle = blur_image(reference, psf, arcmin_per_px=1.0, padding="edge")
    model = ForwardModel(reference, 1.0, 3.6, mode="geometric", max_power_diopters=4.0).predict(defocus)
    # measured 1.6e-3 (ray-histogram noise of the oracle, 250k-4M rays); a 30 deg axis read as
    # 150 deg (mirror) or 120 deg (sign) differs by > 0.1
    assert np.max(np.abs(model - oracle)[10:-10, 10:-10]) < 5e-3


def test_a_mirrored_axis_would_not_match():
    reference = _letter()
    right = ForwardModel(reference, 1.0, 3.6, max_power_diopters=4.0)
    d30 = -np.asarray(Prescription.parse("plano -2.00 x 30").power_matrix())
    d150 = -np.asarray(Prescription.parse("plano -2.00 x 150").power_matrix())
    assert np.max(np.abs(right.predict(d30) - right.predict(d150))) > 0.1


def test_positive_shift_moves_the_content_down_and_right():
    reference = _letter()
    model = ForwardModel(reference, 1.0, 3.6, max_power_diopters=2.0)
    d = np.eye(2) * 0.5
    still, moved = model.predict(d), model.predict(d, shift_rc=(2.0, 3.0))
    assert np.max(np.abs(moved[20:-20, 20:-20] - still[18:-22, 17:-23])) < 1e-9


def test_magnification_is_the_campaigns_about_the_tile_centre():
    """Without blur the model magnifies as :func:`vissim.optics.blur.resample.magnify` (same spline, same centre)."""
    reference = _letter()
    model = ForwardModel(reference, 1.0, 3.6, max_power_diopters=2.0)
    matrix = np.array([[1.05, 0.01], [0.01, 0.97]])
    assert np.max(np.abs(model.predict(np.zeros((2, 2)), matrix) - magnify(reference, matrix))[8:-8, 8:-8]) < 1e-5


def test_tabulated_jinc_matches_the_bessel_function():
    x = np.linspace(0.0, 300.0, 200_001)
    exact = np.ones_like(x)
    exact[1:] = 2.0 * scipy.special.j1(x[1:]) / x[1:]
    assert np.max(np.abs(_jinc(x) - exact)) < 2e-7


def test_cached_spectra_give_what_a_fresh_model_gives_and_shift_steps_reuse_them(monkeypatch):
    """The blurred spectrum is cached by optics only: a shift-only call builds no transfer, and an
    interleaved sequence (other defocus, magnification, pupil, shift) equals fresh models to the bit."""
    reference = _letter()
    model = ForwardModel(reference, 1.0, 3.6, max_power_diopters=2.0)
    builds = []
    transfer = model._geometric_transfer
    monkeypatch.setattr(model, "_geometric_transfer", lambda *a: builds.append(1) or transfer(*a))
    d1, d2 = np.eye(2) * 0.5, np.array([[0.8, 0.2], [0.2, -0.3]])
    m = np.array([[1.02, 0.0], [0.0, 0.99]])
    calls = [(d1, np.eye(2), (0.0, 0.0), None), (d1, np.eye(2), (0.3, -0.7), None), (d2, np.eye(2), (0.3, -0.7), None),
             (d2, m, (0.3, -0.7), None), (d2, m, (0.3, -0.7), 3.0), (d1, np.eye(2), (1.1, 0.2), None)]
    for defocus, magnification, shift, pupil in calls:
        fresh = ForwardModel(reference, 1.0, 3.6, max_power_diopters=2.0)
        expected = fresh.predict(defocus, magnification, shift, pupil)
        assert np.array_equal(model.predict(defocus, magnification, shift, pupil), expected)
    assert len(builds) == 4  # d1; d2; d2 magnified; d2 magnified at 3 mm (the shift-only calls reuse)
