"""A depth layer's window blur, its extension and upsampling, and the compositor, against independent oracles.

Oracles:
* ``numpy.pad``, for a window's padding (`pad_window`): its mode on a side at the image's border, zeros on
  a side inside the image;
* a direct spatial convolution in float64 of the planes so padded, for the window's blur (float32
  round-off: 1e-5 of the planes' range);
* `convolve_padded`, the full padded grid's transform pair: the pruned transforms must give its
  numbers bit for bit (the claim `convolve_window` makes for the CPU), as does the whole-grid path
  a GPU backend takes (run with NumPy here);
* the definition of cell-centred x2 bilinear upsampling: 3/4 of a fine sample's own coarse sample
  and 1/4 of the next one out, edges clamped (exact in float32).
"""

import numpy as np
import pytest
import scipy.fft
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import pad_window, padded_shape, padding_width_px
from vissim.optics.blur.device import convolve_padded, convolve_window
from vissim.optics.depth.composite import Compositor, LayerScene
from vissim.optics.depth.depth_map import matte_indices
from vissim.optics.depth.pullpush import upsample2
from vissim.optics.depth.windows import DEPTH_PADDING_MODES, extended_layer
from vissim.optics.psf.compute import PSF
from vissim.optics.runtime.array_backend import CPU as CPU_BACKEND
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
    ours = pad_window(planes, ((top, bottom), (left, right)), padding, touches)
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


@pytest.mark.parametrize("padding", ["constant", "wrap", "symmetric"])
def test_a_window_padded_any_other_way_is_refused(padding):
    """Only padding whose rows copy the window's (edge, reflect) keeps the pruned transforms exact."""
    psf = PSF.from_array(np.full((3, 3), 1 / 9), 1.0, wavelength_nm=550.0, pupil_diameter_mm=4.0)
    with pytest.raises(VissimInputError, match=f"edge, reflect; got '{padding}'"):
        convolve_window(np.ones((4, 5, 6), np.float32), psf, padding, (True,) * 4)


@pytest.mark.parametrize("padding", DEPTH_PADDING_MODES)
@pytest.mark.parametrize("touches", [(False, False, True, True), (True, False, False, True), (True, True, True, True),
                                     (False, False, False, False)])
@pytest.mark.parametrize("size", [(23, 40), (3, 31)])  # the second: fewer rows than the padding (5, 7)
def test_window_blur_is_the_padded_planes_convolved(padding, touches, size):
    rng = np.random.default_rng(7)
    kernel = rng.random((9, 9))
    kernel /= kernel.sum()
    psf = PSF.from_array(kernel, 1.0, wavelength_nm=550.0, pupil_diameter_mm=4.0)
    planes = rng.random((4, *size), dtype=np.float32)
    blurred, shape = convolve_window(planes, psf, padding, touches, threads=1)

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
    # whole padded grid to convolve_padded; the CPU's pruned transforms must give its numbers, bit for bit.
    rng = np.random.default_rng(11)
    kernel = rng.random((7, 7))
    kernel /= kernel.sum()
    psf = PSF.from_array(kernel, 1.0, wavelength_nm=550.0, pupil_diameter_mm=4.0)
    planes = rng.random((4, 19, 33), dtype=np.float32)
    full_grid = ArrayBackend("numpy-full-grid", np, scipy.fft)
    for touches in TOUCHES:
        ours, shape = convolve_window(planes, psf, padding, touches, threads=1)
        theirs, their_shape = convolve_window(planes, psf, padding, touches, full_grid)
        assert shape == their_shape
        np.testing.assert_array_equal(ours, theirs)


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


# -- a layer's extension, and the compositor --------------------------------------------------
def small_scene(seed: int):
    """A 26 x 30 ramp of proximities with a nearer block: its tent matte over an evenly spaced plan."""
    rng = np.random.default_rng(seed)
    proximity = np.linspace(0.2, 1.0, 26)[:, None] + 0.02 * rng.random((26, 30))
    proximity[8:17, 5:19] = 2.6
    layer_diopters = np.linspace(0.2, 2.6, 13)
    lower, frac = matte_indices(proximity, layer_diopters)
    upper = np.minimum(lower + 1, layer_diopters.size - 1)
    colour = rng.random((3, 26, 30), dtype=np.float32)
    return colour, lower.astype(np.intp), upper.astype(np.intp), frac.astype(np.float32), layer_diopters


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 20), k=st.integers(0, 11), keep=st.tuples(st.integers(0, 25), st.integers(1, 26)))
def test_an_extension_kept_to_some_rows_equals_the_whole_one_there(seed, k, keep):
    # extended_layer(keep=...) pushes only the rows the caller keeps (odd first and last rows included); on
    # those rows it must equal the extension of the whole window, bit for bit.
    colour, lower, upper, frac, layer_diopters = small_scene(seed)
    first, end = min(keep), max(keep)
    if first == end:
        end += 1
    on_layer = ((lower == k) & (frac < 1)) | ((upper == k) & (frac > 0))
    rows = np.flatnonzero(on_layer.any(axis=1))
    if rows.size == 0:
        return
    band = (int(rows[0]), int(rows[-1]) + 1)
    whole = extended_layer(colour, lower, upper, frac, layer_diopters, k, 0.3, rows=band).copy()
    kept = extended_layer(colour, lower, upper, frac, layer_diopters, k, 0.3, rows=band, keep=(first, end))
    np.testing.assert_array_equal(kept[:, first:end], whole[:, first:end])


def composited_by_hand(layers, layer_diopters, threshold_diopters, shape):
    """The compositing formula of `vissim.optics.depth.depth_map` term by term, in float64 on the whole frame:
    T_k = clip(1 - sum_j w_jk A_j, 0, 1), w rising from 0 to 1 as the proximity gap goes from 1x to 2x the
    threshold; numerator += T_k P_k, denominator += T_k A_k, nearest first."""
    numerator, denominator = np.zeros((3, *shape)), np.zeros(shape)
    added = []
    for k, (r0, r1, c0, c1), planes in layers:
        whole = np.zeros((4, *shape))
        whole[:, r0:r1, c0:c1] = planes
        hidden = sum(min(max((layer_diopters[j] - layer_diopters[k]) / threshold_diopters - 1.0, 0.0), 1.0) * cover
                     for j, cover in added)
        transmitted = np.clip(1.0 - hidden, 0.0, 1.0)
        numerator += transmitted * whole[:3]
        denominator += transmitted * whole[3]
        added.append((k, whole[3]))
    return numerator, denominator


@pytest.mark.parametrize("seed", range(4))
def test_the_compositor_adds_each_layer_through_what_nearer_layers_let_through(seed):
    # Nearer layers fully covering the top and bottom rows of farther windows: the compositor leaves those rows
    # out, and must still give the formula's sums.
    rng = np.random.default_rng(seed)
    shape, layer_diopters, threshold = (24, 28), np.linspace(0.0, 3.0, 7), 0.6
    scene = LayerScene(np.zeros((3, *shape), np.float32), np.zeros(shape, np.intp), np.zeros(shape, np.intp),
                       np.zeros(shape, np.float32), layer_diopters, threshold, {}, {}, None, "edge", CPU_BACKEND, None)
    compositor = Compositor(scene, layer_diopters[0])
    layers = []
    for k in range(6, -1, -1):  # near to far
        r0, c0 = int(rng.integers(0, 8)), int(rng.integers(0, 8))
        r1, c1 = int(rng.integers(r0 + 4, shape[0] + 1)), int(rng.integers(c0 + 4, shape[1] + 1))
        planes = rng.random((4, r1 - r0, c1 - c0), dtype=np.float32)
        if k >= 4:  # near layers: opaque bands across the frame's top and bottom rows
            planes[3, : (r1 - r0) // 3] = 1.0
            planes[3, -((r1 - r0) // 3) :] = 1.0
        layers.append((k, (r0, r1, c0, c1), planes))
        compositor.add(k, (r0, r1, c0, c1), planes.copy(), (0, 0))
    numerator, denominator = composited_by_hand(layers, layer_diopters, threshold, shape)
    # float32 sums of 7 layers of values in [0, 1], against float64: each term's round-off is at most 6e-8
    # (2^-24), so under 1e-6 in all; 2e-6 leaves room for the transmission's own round-off.
    np.testing.assert_allclose(compositor.numerator, numerator, atol=2e-6)
    np.testing.assert_allclose(compositor.denominator, denominator, atol=2e-6)
