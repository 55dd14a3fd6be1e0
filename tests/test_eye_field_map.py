"""Off-axis schematic-eye PSFs in visual angle (`field_map`, `field_mapped`) and the pupil's parallax (`sight`).

Oracles: the field map against central differences of the field rule (and 1/cos θ on the x axis);
the resampling against a Gaussian's analytic stretch; the off-axis PSF's centroid against the traced
rays' own landing points read through the retina's chief-ray map; the parallax against e sin θ / d.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye
from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront
from vissim.optics.eyes.sight import film_field_deg
from vissim.optics.eyes.traced_wavefront import field_direction, field_map, iris_from_entrance_pupil_mm, trace_to_retina
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront, field_mapped
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.eyes.retina_map import chief_ray_radii_mm


@pytest.mark.parametrize("model,field", [("navarro-1985", (20.0, 0.0)), ("navarro-1985", (12.0, -7.0)),
                                         ("liou-brennan-1997", (0.0, 0.0)), ("liou-brennan-1997", (-15.0, 5.0))])
def test_field_map_is_the_inverse_slope_of_the_field_rule(model, field):
    """J⁻¹, J = ∂(o_x, o_y)/∂(field, rad) by central differences of `field_direction` (step 1e-4 deg: error ~1e-8)."""
    eye = eye_model(model)
    h = 1e-4
    columns = []
    for axis in (0, 1):
        ends = []
        for sign in (-1.0, 1.0):
            f = list(field)
            f[axis] += sign * h
            ends.append(field_direction(eye, f)[:2])
        columns.append((ends[1] - ends[0]) / math.radians(2 * h))
    assert np.allclose(field_map(eye, field), np.linalg.inv(np.array(columns).T), rtol=0, atol=1e-6)


def test_field_map_on_the_x_axis_is_one_over_cos():
    eye = eye_model("navarro-1985")
    assert np.allclose(field_map(eye, (20.0, 0.0)), np.eye(2) / math.cos(math.radians(20.0)), rtol=0, atol=1e-12)
    assert np.array_equal(field_map(eye, (0.0, 0.0)), np.eye(2))


def test_field_mapped_stretches_a_gaussian_as_the_map_says():
    """A Gaussian of σ px through diag(1.3, 0.8) (x, y) is a Gaussian of σ 1.3 along columns, 0.8 σ along rows, the
    same energy; the identity (None) returns the array itself. Cubic interpolation of a 4 px Gaussian: error
    ~1e-4 of the peak, bounded at 1e-3."""
    n, sigma = 81, 4.0
    rows, cols = np.indices((n, n)) - n // 2
    g = np.exp(-(rows ** 2 + cols ** 2) / (2 * sigma ** 2))
    g /= g.sum()
    out = field_mapped(g, ((1.3, 0.0), (0.0, 0.8)))
    expected = np.exp(-(cols / 1.3) ** 2 / (2 * sigma ** 2) - (rows / 0.8) ** 2 / (2 * sigma ** 2))
    expected /= expected.sum()
    assert abs(out.sum() - 1.0) < 1e-4
    assert np.abs(out - expected).max() < 1e-3 * expected.max()
    assert field_mapped(g, None) is g


def test_spectral_wavefront_refuses_a_bad_field_map():
    front = Wavefront({(2, 0): 0.1}, 3.0)
    for bad in (((1.0, 0.0), (0.0, -1.0)), ((1.0, 0.0),), ((math.nan, 0.0), (0.0, 1.0))):
        with pytest.raises(Exception, match="field map"):
            SpectralWavefront((550.0,), (front,), field_map=bad)
    assert SpectralWavefront((550.0,), (front,), field_map=((1.0, 0.0), (0.0, 1.0))).field_map is None


def _ray_centroid_arcmin(eye, field, pupil_mm, wavelength):
    """The mean film angle (x, OSA; arcmin from the field) of the rays whose incoming lines cross the paraxial
    entrance-pupil plane within the pupil's disc about the chief ray's crossing: landing points read through the
    chief rays' r(θ); no wavefront, no PSF."""
    iris = iris_from_entrance_pupil_mm(eye, pupil_mm, wavelength)
    axis = np.linspace(-0.56 * iris, 0.56 * iris, 81)
    x, y = np.meshgrid(axis, axis)
    targets = np.concatenate([[[0.0, 0.0]], np.stack([x.ravel(), y.ravel()], axis=1)])
    bundle, starts = trace_to_retina(eye, targets, wavelength, field_deg=field)
    o = field_direction(eye, field)
    depth = entrance_pupil_position_mm(mean_meridian_eye(eye), wavelength)
    crossing = starts[:, :2] + np.array([-o[0], -o[1]]) / o[2] * (depth - starts[:, 2:3])
    inside = np.hypot(*(crossing - crossing[0]).T) <= 0.5 * pupil_mm
    theta = np.arange(field[0] - 1.0, field[0] + 1.0 + 1e-9, 0.01)
    radius = chief_ray_radii_mm(eye, theta, eye.reference_wavelength_nm)
    points = bundle.points_mm[inside]
    seen = np.interp(np.hypot(points[:, 0], points[:, 1]), radius, theta)
    return 60.0 * (seen.mean() - field[0])


def test_off_axis_psf_centroid_follows_the_traced_rays():
    """Navarro, 4 mm, 589.3 nm, 20° on x: the wave PSF's centroid (the front's mean slope, coma's included, through
    the field map)
    within 0.05 arcmin (the 65-ray grid's and the order-8 fit's residue, measured 0.01-0.03) of the rays' own
    mean film angle; without the map it falls short by about (1 - cos 20°) of it (0.2 arcmin)."""
    eye = eye_model("navarro-1985")
    field = (20.0, 0.0)
    truth = _ray_centroid_arcmin(eye, field, 4.0, 589.3)
    spectral = eye_spectral_wavefront(build_eye("navarro-1985", pupil_diameter_mm=4.0), wavelengths_nm=[589.3], field_deg=field)
    step = 0.5

    def centroid_x(front):
        data = compute_psf(front, arcmin_per_px=step, size_px=121, mode="wave", dtype=np.float64).data
        cols = np.arange(data.shape[1]) - data.shape[1] // 2
        return -step * float((data.sum(axis=0) * cols).sum() / data.sum())  # columns to the right: -x

    # the map's effect, (1 - cos 20°) |truth|, must stand well above the 0.05 arcmin tolerance for the test to tell
    missing = (1.0 - math.cos(math.radians(field[0]))) * abs(truth)
    assert truth < 0.0 and missing > 0.15  # coma moves the centroid towards the axis (-x), by several arcmin
    assert abs(centroid_x(spectral) - truth) < 0.05
    unmapped = SpectralWavefront(spectral.wavelengths_nm, spectral.fronts)
    assert abs(centroid_x(unmapped) - truth) > 0.5 * missing


def test_film_sees_a_near_point_from_the_entrance_pupil():
    """A point 6 m away at 20° from the vertex is seen nearer the axis by e sin θ / d (e the entrance pupil's
    depth), within 2 %; at 1 km the parallax is under 0.005 arcmin."""
    eye = eye_model("navarro-1985")
    e = entrance_pupil_position_mm(mean_meridian_eye(eye), eye.reference_wavelength_nm)
    for distance_mm, expected in ((6000.0, e * math.sin(math.radians(20.0)) / 6000.0), (1e6, 0.0)):
        o = field_direction(eye, (20.0, 0.0))
        point = distance_mm * np.array([o[0], o[1], -o[2]])
        seen = film_field_deg(eye, point, 4.0)
        parallax = math.radians(20.0 - seen[0])
        assert abs(parallax - expected) <= max(0.02 * expected, math.radians(0.005 / 60.0))
        assert abs(seen[1]) < 1e-9


def test_depth_eye_warns_off_axis_where_its_psfs_miss_the_field_map(caplog):
    """The depth blur's eye cannot carry the field map: at 20° it says the eye's PSFs are 6.4 % (1/cos 20° − 1) wider;
    on the axis it says nothing."""
    from vissim.optics.eyes.depth_eye import traced_depth_eye

    with caplog.at_level("WARNING"):
        eye = build_eye("navarro-1985", pupil_diameter_mm=3.0, rx="-1.00")
        traced_depth_eye(eye, wavelength_nm=555.0)
        assert not caplog.records
        traced_depth_eye(eye, wavelength_nm=555.0, field_deg=(20.0, 0.0))
    assert len(caplog.records) == 1 and "6.4 %" in caplog.records[0].getMessage()
