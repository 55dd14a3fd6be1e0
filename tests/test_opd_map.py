"""OPD maps in the PSF core: a sampled wavefront gives the PSF of the wavefront it samples."""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.pupil.opd_map import OpdMap
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront

FRONT = Wavefront.from_prescription(Prescription.parse("-1.00 -0.50 x 30"), 3.6) + Wavefront(
    {(3, 1): 0.1, (3, -3): 0.06, (4, 0): 0.05}, 3.6
)


@pytest.fixture(scope="module")
def sampled():
    return OpdMap.sample(FRONT, 65)


def test_grid_orientation_and_the_spline_reproduce_the_wavefront(sampled):
    # The map's row 0 is +y, column 0 is -x (docs/conventions.md); a bicubic spline through 65^2
    # samples of a 4th-order polynomial is exact to 1e-6 µm inside the pupil.
    r = np.sqrt(np.linspace(0, 1, 30))[:, None] * 1.8
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)[None, :]
    x, y = r * np.cos(t), r * np.sin(t)
    np.testing.assert_allclose(sampled.opd_um(x, y), FRONT.opd_um(x, y), atol=1e-6)
    np.testing.assert_allclose(sampled.slopes_mrad(x, y), FRONT.slopes_mrad(x, y), atol=1e-4)
    assert sampled.samples_um[0, 32] == pytest.approx(FRONT.opd_um(0.0, 1.8))
    assert sampled.samples_um[32, 0] == pytest.approx(FRONT.opd_um(-1.8, 0.0))


@pytest.mark.parametrize("mode, method, tolerance", [("wave", "mft", 1e-5), ("wave", "fft", 1e-5), ("geometric", None, 1e-3)])
def test_psf_of_the_map_is_the_psf_of_the_wavefront(sampled, mode, method, tolerance):
    # The core evaluates both at the same quadrature points: the wave PSFs agree to 1e-5 of the
    # peak.  The ray PSFs use the same seeded rays, landing by the spline's slopes (1e-4 mrad
    # from the polynomial's), so a few rays cross pixel edges: measured 3e-4 of the peak, 1e-3 allowed.
    kwargs = dict(arcmin_per_px=0.25, size_px=173, mode=mode, method=method)
    a, b = compute_psf(sampled, **kwargs), compute_psf(FRONT, **kwargs)
    assert np.max(np.abs(a.data - b.data)) <= tolerance * b.data.max()
    assert a.as_json()["wavefront"]["kind"] == "opd_map"


def test_chromatic_defocus_is_added_to_a_map(sampled):
    kwargs = dict(wavelength_nm=[480, 550, 640], lca_reference_nm=550, arcmin_per_px=0.25, size_px=173)
    a, b = compute_psf(sampled, **kwargs), compute_psf(FRONT, **kwargs)
    assert np.max(np.abs(a.data - b.data)) <= 1e-5 * b.data.max()


def test_zernike_fit_recovers_the_coefficients(sampled):
    fit = sampled.zernike_fit(6)
    for key, value in FRONT.coefficients_um.items():
        assert fit.coefficients_um.get(key, 0.0) == pytest.approx(value, abs=1e-6)


def test_bad_maps_are_refused():
    with pytest.raises(VissimInputError, match="square"):
        OpdMap(np.zeros((4, 5)), 3.0)
    with pytest.raises(VissimInputError, match="finite"):
        OpdMap(np.full((8, 8), np.nan), 3.0)
    with pytest.raises(VissimInputError, match="positive mm"):
        OpdMap(np.zeros((8, 8)), -1.0)


@pytest.mark.parametrize("derivative", [(0, 0), (1, 0), (0, 1)])
def test_the_cell_polynomials_are_fitpacks_spline(derivative):
    # Oracle: FITPACK's own evaluation (RectBivariateSpline.ev) of the same spline, at random points, at knots and
    # beyond the grid (both clamp to it); agreement to round-off.
    from scipy.interpolate import RectBivariateSpline

    from vissim.optics.pupil.spline_cells import CellPolynomials

    rng = np.random.default_rng(5)
    axis = np.linspace(-1.8, 1.8, 33)
    spline = RectBivariateSpline(axis, axis, rng.standard_normal((33, 33)))
    x = np.concatenate([rng.uniform(-1.8, 1.8, 5000), axis, [-2.5, 2.5, 1.8, -1.8]])
    y = np.concatenate([rng.uniform(-1.8, 1.8, 5000), axis[::-1], [0.3, -2.5, 1.8, -1.8]])
    cells = CellPolynomials.of(spline.partial_derivative(*derivative) if any(derivative) else spline)
    expected = spline.ev(x, y, dx=derivative[0], dy=derivative[1])
    np.testing.assert_allclose(cells(x, y), expected, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_array_equal(cells(x[:5000].reshape(-1, 2), y[:5000].reshape(-1, 2)).ravel(), cells(x, y)[:5000])
