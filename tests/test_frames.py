"""The image frame against the TABO/OSA frame: (col, row) = (-x, -y) (docs/conventions.md)."""

from vissim.optics.pupil.grid import pupil_grid
from vissim.units import image_colrow_to_osa_xy, osa_xy_to_image_colrow


def test_a_cell_right_of_and_below_the_pupil_centre_is_osa_minus_x_and_minus_y():
    """The examiner's +x (the subject's left) is the observer's left, and +y (up) is a lower row.
    Exact: the map only negates, so a flipped sign in either axis fails every line."""
    assert osa_xy_to_image_colrow(1.5, 2.5) == (-1.5, -2.5)
    assert image_colrow_to_osa_xy(-1.5, -2.5) == (1.5, 2.5)
    grid = pupil_grid(0.25, 3.0)
    h = grid.half
    assert (grid.centre_x_mm[h, h + 1], grid.centre_y_mm[h, h + 1]) == (-0.25, 0.0)  # one column right
    assert (grid.centre_x_mm[h + 1, h], grid.centre_y_mm[h + 1, h]) == (0.0, -0.25)  # one row down


def test_an_xy_matrix_acts_on_image_offsets_as_on_osa_offsets():
    """m (x, y) mapped to the image equals the image-frame matrix applied to the mapped (row, col).
    Exact to round-off for any matrix; fails if a sign or the axis swap is wrong."""
    import numpy as np

    from vissim.units import xy_matrix_to_image_rowcol

    m = np.array([[1.1, 0.3], [-0.2, 0.9]])
    xy = np.array([0.7, -1.3])
    col, row = osa_xy_to_image_colrow(*(m @ xy))
    rowcol = xy_matrix_to_image_rowcol(m) @ np.array(osa_xy_to_image_colrow(*xy))[::-1]
    np.testing.assert_allclose(rowcol, [row, col], atol=1e-15)
