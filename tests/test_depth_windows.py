"""A depth layer's window blur and its pull-push upsampling, against independent oracles.

Oracles:
* ``numpy.pad``, for the window's padding: its mode on a side at the image's border, zeros on a
  side inside the image;
* a direct spatial convolution in float64 of the planes so padded, for the window's blur (float32
  round-off: 1e-5 of the planes' range);
* `convolve_padded`, the full padded grid's transform pair: the pruned transforms must give its
  numbers bit for bit (the claim `_pruned_convolution` makes); the same whole-grid path as a GPU
  backend runs it, with NumPy here, to 1e-6;
* the definition of cell-centred x2 bilinear upsampling: 3/4 of a fine sample's own coarse sample
  and 1/4 of the next one out, edges clamped (exact in float32).
"""

import numpy as np
import pytest
import scipy.fft
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.optics.blur.convolve import padded_shape, padding_width_px
from vissim.optics.blur.device import convolve_padded
from vissim.optics.depth.pullpush import upsample2
from vissim.optics.depth.windows import DEPTH_PADDING_MODES, _padded, blur_window
from vissim.optics.psf.compute import PSF
from vissim.optics.runtime.array_backend import ArrayBackend

NUMPY_MODES = {"edge": "edge", "reflect": "symmetric"}  # how numpy.pad spells each depth padding
TOUCHES = [(a, b, c, d) for a in (False, True) for b in (False, True) for c in (False, True) for d in (False, True)]


def numpy_padded(array, widths, padding, touches):
    """The oracle: numpy.pad on the last two axes, then zeros on each side that does not touch the border."""
    (top, bottom), (left, right) = widths
    padded = np.pad(array, ((0, 0), (top, bottom), (left, right)), mode=NUMPY_MODES[padding])
    rows, cols = padded.shape[1:]
    for touching, part in zip(touches, (np.s_[:, :top], np.s_[:, rows - bottom :], np.s_[:, :, :left],
                                        np.s_[:, :, cols - right :])):
        if not touching:
            padded[part] = 0.0
    return padded


@settings(max_examples=200, deadline=None)
@given(rows=st.integers(1, 6), cols=st.integers(1, 6), widths=st.tuples(*[st.integers(0, 9)] * 4),
       padding=st.sampled_from(DEPTH_PADDING_MODES), touches=st.sampled_from(TOUCHES), seed=st.integers(0, 99))
def test_window_padding_is_numpy_pad_with_zeros_inside_the_image(rows, cols, widths, padding, touches, seed):
    planes = np.random.default_rng(seed).random((2, rows, cols), dtype=np.float32)
    top, bottom, left, right = widths
    ours = _padded(_padded(planes, -2, (top, bottom), padding, touches[:2]), -1, (left, right), padding, touches[2:])
    np.testing.assert_array_equal(ours, numpy_padded(planes, ((top, bottom), (left, right)), padding, touches))


def direct_convolution(padded: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Linear convolution of (C, H, W) with an odd kernel centred at [N//2, N//2], float64, 'same' size."""
    n = kernel.shape[0]
    half = n // 2
    out = np.zeros(padded.shape, np.float64)
    source = np.pad(padded.astype(np.float64), ((0, 0), (half, half), (half, half)))
    for i in range(n):
        for j in range(n):
            out += kernel[i, j] * source[:, 2 * half - i : 2 * half - i + padded.shape[1],
                                         2 * half - j : 2 * half - j + padded.shape[2]]
    return out


@pytest.mark.parametrize("padding", DEPTH_PADDING_MODES)
@pytest.mark.parametrize("touches", [(False, False, True, True), (True, False, False, True), (True, True, True, True),
                                     (False, False, False, False)])
@pytest.mark.parametrize("size", [(23, 40), (5, 31)])  # the second: fewer rows than the padding
def test_window_blur_is_the_padded_planes_convolved(padding, touches, size):
    rng = np.random.default_rng(7)
    kernel = rng.random((9, 9))
    kernel /= kernel.sum()
    psf = PSF.from_array(kernel, 1.0, wavelength_nm=550.0, pupil_diameter_mm=4.0)
    planes = rng.random((4, *size), dtype=np.float32)
    blurred, shape = blur_window(planes, psf, padding, touches, threads=1)

    offset = padding_width_px(9)
    assert shape == padded_shape(size, 9)
    widths = ((offset, shape[0] - size[0] - offset), (offset, shape[1] - size[1] - offset))
    padded = numpy_padded(planes, widths, padding, touches)
    expected = direct_convolution(padded, kernel)[:, offset : offset + size[0], offset : offset + size[1]]
    np.testing.assert_allclose(blurred, expected, atol=1e-5)
    full = convolve_padded(padded, psf, threads=1)[:, offset : offset + size[0], offset : offset + size[1]]
    np.testing.assert_array_equal(blurred, full)  # the pruned transforms: the full grid's numbers, bit for bit


@pytest.mark.parametrize("padding", DEPTH_PADDING_MODES)
def test_the_full_grid_path_a_gpu_takes_gives_the_same_blur(padding):
    # A backend that is not the CPU's (here NumPy under another name, so it runs without a GPU) takes the
    # whole padded grid to convolve_padded; the CPU's pruned transforms must agree with it to round-off.
    rng = np.random.default_rng(11)
    kernel = rng.random((7, 7))
    kernel /= kernel.sum()
    psf = PSF.from_array(kernel, 1.0, wavelength_nm=550.0, pupil_diameter_mm=4.0)
    planes = rng.random((4, 19, 33), dtype=np.float32)
    full_grid = ArrayBackend("numpy-full-grid", np, scipy.fft)
    for touches in TOUCHES:
        ours, shape = blur_window(planes, psf, padding, touches, threads=1)
        theirs, their_shape = blur_window(planes, psf, padding, touches, full_grid)
        assert shape == their_shape
        np.testing.assert_allclose(ours, theirs, atol=1e-6)


def bilinear_oracle(coarse: np.ndarray, shape) -> np.ndarray:
    """x2 cell-centred bilinear upsampling by its definition, one axis then the other, in float32."""
    out = coarse
    for axis, size in ((1, shape[0]), (2, shape[1])):
        n = out.shape[axis]
        samples = []
        for f in range(size):
            own = f // 2
            other = min(max(own - 1 if f % 2 == 0 else own + 1, 0), n - 1)
            samples.append(np.float32(0.75) * np.take(out, own, axis=axis)
                           + np.float32(0.25) * np.take(out, other, axis=axis))
        out = np.stack(samples, axis=axis)
    return out


@settings(max_examples=60, deadline=None)
@given(rows=st.integers(1, 7), cols=st.integers(1, 7), odd=st.tuples(st.booleans(), st.booleans()),
       seed=st.integers(0, 99))
def test_upsampling_is_cell_centred_bilinear(rows, cols, odd, seed):
    coarse = np.random.default_rng(seed).random((3, rows, cols), dtype=np.float32)
    shape = (2 * rows - (odd[0] and rows > 1), 2 * cols - (odd[1] and cols > 1))
    np.testing.assert_array_equal(upsample2(coarse, shape), bilinear_oracle(coarse, shape))
