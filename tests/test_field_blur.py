"""Field-dependent blur (`vissim.optics.blur.field_dependent`): bilinear interpolation of node PSFs (Nagy & O'Leary 1998).

Oracles, none of them an FFT: a point source blurred field-dependently is the bilinear mix of its
neighbouring nodes' PSFs, written here directly as weighted sums of the PSF arrays placed by hand
(weights from the point's position, computed here); the isoplanatic blur `blur_image` for a grid
of one repeated PSF (its own tests pin it against direct convolution); energy sums.
"""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.blur.field_dependent import PSFGrid, blur_field_dependent, node_positions_px, psf_grid
from vissim.optics.psf.compute import PSF

SHAPE = (61, 81)  # nodes 20 px apart: rows 0, 20, 40, 60; columns 0, 20, ..., 80
SPACING_PX = 20
EXACT = 1e-12  # float64 FFT round-off on unit-sum kernels


def random_grid(seed=1, size=9):
    rng = np.random.default_rng(seed)
    return psf_grid(SHAPE, SPACING_PX, lambda r, c: PSF.from_array(rng.random((size, size)), 1.0))


def point_response(grid, row, col):
    image = np.zeros(SHAPE)
    image[row, col] = 1.0
    return blur_field_dependent(image, grid, arcmin_per_px=1.0, padding="constant", background=0.0, dtype=np.float64)


def placed(psf_data, row, col):
    """``psf_data`` with its origin [N//2, N//2] on [row, col] of an image of SHAPE (the oracle's placement)."""
    out = np.zeros(SHAPE)
    n = psf_data.shape[0]
    out[row - n // 2:row - n // 2 + n, col - n // 2:col - n // 2 + n] = psf_data
    return out


def test_nodes_span_the_image_evenly_and_one_node_sits_at_the_centre_of_a_short_axis():
    assert node_positions_px(61, 20) == (0.0, 20.0, 40.0, 60.0)
    assert node_positions_px(62, 20) == pytest.approx((0.0, 61 / 4, 61 / 2, 3 * 61 / 4, 61.0))
    assert node_positions_px(15, 20) == (7.0,)


def test_a_point_on_a_node_is_blurred_by_exactly_that_nodes_psf():
    grid = random_grid()
    for i, j in ((1, 2), (0, 0), (3, 4), (2, 1)):
        row, col = int(grid.rows_px[i]), int(grid.cols_px[j])
        if 4 <= row <= SHAPE[0] - 5 and 4 <= col <= SHAPE[1] - 5:  # the whole PSF inside the image
            np.testing.assert_allclose(point_response(grid, row, col), placed(grid.psfs[i][j].data, row, col),
                                       atol=EXACT)


def test_a_point_halfway_between_two_nodes_is_blurred_by_the_mean_of_their_psfs():
    grid = random_grid(seed=2)
    mean = 0.5 * (grid.psfs[1][1].data + grid.psfs[1][2].data)  # nodes (20, 20) and (20, 40)
    np.testing.assert_allclose(point_response(grid, 20, 30), placed(mean, 20, 30), atol=EXACT)


def test_a_point_inside_a_cell_is_blurred_by_the_bilinear_mix_of_its_four_nodes():
    grid = random_grid(seed=3)
    row, col = 25, 33  # in the cell of nodes rows 20-40, columns 20-40: fractions 0.25 down, 0.65 right
    fr, fc = 0.25, 0.65
    p = [[grid.psfs[i][j].data for j in (1, 2)] for i in (1, 2)]
    mix = (1 - fr) * ((1 - fc) * p[0][0] + fc * p[0][1]) + fr * ((1 - fc) * p[1][0] + fc * p[1][1])
    np.testing.assert_allclose(point_response(grid, row, col), placed(mix, row, col), atol=EXACT)


@pytest.mark.parametrize("padding", ["constant", "edge", "reflect", "wrap"])
def test_one_psf_at_every_node_is_the_isoplanatic_blur(padding):
    psf = PSF.from_array(np.random.default_rng(4).random((11, 11)), 1.0)
    image = np.random.default_rng(5).random(SHAPE)
    grid = psf_grid(SHAPE, SPACING_PX, lambda r, c: psf)
    np.testing.assert_allclose(blur_field_dependent(image, grid, arcmin_per_px=1.0, padding=padding, dtype=np.float64),
                               blur_image(image, psf, arcmin_per_px=1.0, padding=padding, dtype=np.float64), atol=EXACT)


def test_energy_is_conserved_when_nothing_leaves_the_image():
    image = np.zeros(SHAPE)
    image[6:-6, 6:-6] = np.random.default_rng(6).random((SHAPE[0] - 12, SHAPE[1] - 12))
    out = blur_field_dependent(image, random_grid(seed=7), arcmin_per_px=1.0, background=0.0, dtype=np.float64)
    assert out.sum() == pytest.approx(image.sum(), rel=1e-12)


def test_rgb_images_take_one_grid_per_channel():
    grids = [random_grid(seed=s) for s in (9, 10, 11)]
    image = np.random.default_rng(12).random((*SHAPE, 3))
    out = blur_field_dependent(image, grids, arcmin_per_px=1.0, dtype=np.float64)
    for c in range(3):
        np.testing.assert_allclose(out[..., c], blur_field_dependent(image[..., c], grids[c], arcmin_per_px=1.0,
                                                                    dtype=np.float64), atol=EXACT)


def test_bad_grids_and_psfs_are_refused():
    psf = PSF.from_array(np.ones((5, 5)), 1.0)
    with pytest.raises(VissimInputError, match="2 x 1 nodes"):
        PSFGrid((0.0, 10.0), (0.0,), ((psf,),))
    with pytest.raises(VissimInputError, match="must increase"):
        PSFGrid((10.0, 0.0), (0.0,), ((psf,), (psf,)))
    with pytest.raises(VissimInputError, match="arcmin/px"):
        blur_field_dependent(np.zeros(SHAPE), psf_grid(SHAPE, SPACING_PX, lambda r, c: psf), arcmin_per_px=2.0)
    with pytest.raises(VissimInputError, match="spacing"):
        node_positions_px(10, 0.0)
