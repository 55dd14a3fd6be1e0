"""`magnify`: an image resampled through a spectacle magnification, against the analytic image.

Oracle: a Gaussian spot g(r) sampled on the pixel grid; magnified by M about the tile's centre it is g(M^-1 r),
with TABO/OSA's x = -(column offset), y = -(row offset) (docs/conventions.md, "Pupil coordinates").  Flipping
both axes commutes with a linear magnification, so the oracle pins which axis is which and their relative sign (a
single axis flipped, or the two swapped, fails), not the common sign.  A cubic spline reproduces a spot 6 px wide
to about 1e-5 of its peak.
"""

import numpy as np
import pytest

from vissim.optics.blur.resample import magnify

ROWS, COLS, SIGMA_PX = 101, 121, 6.0
SPLINE_TOLERANCE = 5e-5  # of the peak: cubic-spline interpolation of a 6 px Gaussian errs by 1e-5


@pytest.mark.parametrize("matrix_xy", [
    [[1.06, 0.0], [0.0, 1.06]],  # a plus lens: the same along x and y
    [[1.0, 0.0], [0.0, 0.94]],  # a cylinder at axis 180: only y
    [[1.03, 0.02], [0.02, 0.99]],  # an oblique cylinder: not along the image's axes
    [[1.02, 0.03], [-0.01, 0.98]],  # not symmetric: a transposed matrix would show
])
def test_magnify_matches_the_magnified_spot(matrix_xy):
    rows, cols = np.mgrid[0:ROWS, 0:COLS].astype(float)
    x, y = -(cols - (COLS - 1) / 2), -(rows - (ROWS - 1) / 2)
    centre_xy = np.array([7.0, 4.0])
    spot = np.exp(-((x - centre_xy[0]) ** 2 + (y - centre_xy[1]) ** 2) / (2 * SIGMA_PX**2))
    inverse = np.linalg.inv(np.asarray(matrix_xy))
    u, v = inverse[0, 0] * x + inverse[0, 1] * y, inverse[1, 0] * x + inverse[1, 1] * y
    expected = np.exp(-((u - centre_xy[0]) ** 2 + (v - centre_xy[1]) ** 2) / (2 * SIGMA_PX**2))
    seen = magnify(spot.astype(np.float32), matrix_xy, background=0.0)
    assert seen.dtype == np.float32 and seen.shape == spot.shape
    assert np.max(np.abs(seen - expected)) < SPLINE_TOLERANCE


def test_a_scaling_along_the_image_axes_equals_the_general_transform():
    """The axis-aligned case takes SciPy's separable zoom; a matrix a hair off diagonal takes the general
    transform: the two agree to float32 round-off."""
    rng = np.random.default_rng(3)
    image = rng.random((ROWS, COLS)).astype(np.float32)
    along_axes = magnify(image, [[1.04, 0.0], [0.0, 0.97]], background=0.5)
    general = magnify(image, [[1.04, 1e-15], [0.0, 0.97]], background=0.5)
    assert np.max(np.abs(along_axes - general)) <= 1e-6
