"""Linear-light FFT blur: identity, linearity, mean, centring, padding."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import PSF, compute_psf
from vissim.optics.pupil.wavefront import Wavefront


def delta(size=33, step=1.0):
    data = np.zeros((size, size))
    data[size // 2, size // 2] = 1.0
    return PSF.from_array(data, step)


@pytest.fixture(scope="module")
def defocus_psf():
    # float64: these tests pin the blur's float64 arithmetic to 1e-9
    return compute_psf(Wavefront.from_prescription(Prescription(-2.0), 3.0), arcmin_per_px=1.0, size_px=46,
                       dtype=np.float64)


def random_image(seed=0, shape=(64, 80)):
    return np.random.default_rng(seed).random(shape).astype(np.float32)


@pytest.mark.parametrize("padding", ["constant", "edge", "reflect", "wrap"])
def test_delta_psf_leaves_the_image_unchanged(padding):
    image = random_image()
    np.testing.assert_allclose(blur_image(image, delta(), arcmin_per_px=1.0, padding=padding), image, atol=1e-6)


def test_even_sized_psf_does_not_shift_the_image(defocus_psf):
    # A point at the image centre stays centred: the PSF origin [N//2, N//2] maps to [0, 0].
    image = np.zeros((96, 96), np.float32)
    image[48, 48] = 1.0
    out = blur_image(image, defocus_psf, arcmin_per_px=1.0, padding="constant", background=0.0, dtype=np.float64)
    # The output is the PSF itself, its origin [23, 23] on the point at [48, 48]: no shift.
    np.testing.assert_allclose(out[25:71, 25:71], defocus_psf.data, atol=1e-9)
    assert out.sum() == pytest.approx(1.0, abs=1e-9)


def test_constant_image_stays_constant(defocus_psf):
    image = np.full((50, 70), 0.37, np.float32)
    for padding in ("constant", "edge", "reflect", "wrap"):
        np.testing.assert_allclose(blur_image(image, defocus_psf, arcmin_per_px=1.0, padding=padding), 0.37, atol=1e-6)


images = arrays(np.float64, (24, 24), elements=st.floats(0, 1))


@settings(max_examples=25, deadline=None)
@given(images, images, st.floats(-3, 3), st.floats(-3, 3))
def test_blur_is_linear(a, b, alpha, beta):
    psf = delta(9)
    psf = PSF.from_array(np.outer(np.hanning(9), np.hanning(9)) + 0.01, 1.0)
    kw = dict(arcmin_per_px=1.0, padding="constant", background=0.0, dtype=np.float64)
    left = blur_image(alpha * a + beta * b, psf, **kw)
    right = alpha * blur_image(a, psf, **kw) + beta * blur_image(b, psf, **kw)
    np.testing.assert_allclose(left, right, atol=1e-9)


@settings(max_examples=25, deadline=None)
@given(images)
def test_wrap_padding_preserves_the_mean_exactly(image):
    psf = PSF.from_array(np.outer(np.hanning(9), np.hanning(9)) + 0.01, 1.0)
    out = blur_image(image, psf, arcmin_per_px=1.0, padding="wrap", dtype=np.float64)
    assert out.mean() == pytest.approx(image.mean(), abs=1e-12)


def test_mean_preserved_when_the_content_is_away_from_the_border(defocus_psf):
    # A chart-like image: content inside a uniform border wider than the PSF radius.
    image = np.full((96, 96), 0.9, np.float32)
    image[30:66, 40:50] = 0.04
    for padding in ("constant", "edge", "reflect"):
        out = blur_image(image, defocus_psf, arcmin_per_px=1.0, padding=padding, dtype=np.float64)
        assert out.mean() == pytest.approx(image.astype(np.float64).mean(), rel=1e-9)


def test_paddings_differ_only_near_the_border(defocus_psf):
    image = random_image(1, (80, 80))
    a = blur_image(image, defocus_psf, arcmin_per_px=1.0, padding="reflect", dtype=np.float64)
    b = blur_image(image, defocus_psf, arcmin_per_px=1.0, padding="edge", dtype=np.float64)
    reach = defocus_psf.data.shape[0] // 2 + 1
    np.testing.assert_allclose(a[reach:-reach, reach:-reach], b[reach:-reach, reach:-reach], atol=1e-9)
    assert np.max(np.abs(a - b)) > 1e-4


def test_per_channel_psfs_and_float32_default(defocus_psf):
    rgb = np.stack([random_image(s) for s in range(3)], axis=-1)
    out = blur_image(rgb, [delta(), defocus_psf, delta()], arcmin_per_px=1.0)
    assert out.dtype == np.float32 and out.shape == rgb.shape
    np.testing.assert_allclose(out[..., 0], rgb[..., 0], atol=1e-6)
    assert not np.allclose(out[..., 1], rgb[..., 1], atol=1e-3)


def test_sampling_mismatch_is_an_error(defocus_psf):
    with pytest.raises(VissimInputError, match="arcmin/px"):
        blur_image(random_image(), defocus_psf, arcmin_per_px=0.5)


def test_bad_images_are_refused():
    with pytest.raises(VissimInputError, match="NaN"):
        blur_image(np.full((8, 8), np.nan), delta(3), arcmin_per_px=1.0)
    with pytest.raises(VissimInputError, match="shape"):
        blur_image(np.zeros(8), delta(3), arcmin_per_px=1.0)
    with pytest.raises(VissimInputError, match="padding"):
        blur_image(np.zeros((8, 8)), delta(3), arcmin_per_px=1.0, padding="zero")


def test_sample_kernel_is_exact_for_well_sampled_images():
    # A smooth (well-sampled) image at 1 arcmin/px blurred by a small defocus.  Reference: the
    # same continuous image sampled at 0.2 arcmin/px, blurred there, integrated onto 1 arcmin
    # pixels.  The band-limited kernel (pixel="sample", DFT = OTF; Goodman 2005 §6.3) matches
    # it; the integrated PSF adds the pixel's box once more and is measurably off.
    front = Wavefront.from_prescription(Prescription(-0.3), 3.0)

    def blob(step):
        n = int(round(64 / step))
        c = (np.arange(n) + 0.5) * step - 32.0
        return np.exp(-(c[:, None] ** 2 + c[None, :] ** 2) / (2 * 3.0**2)).astype(np.float64)

    psf_fine = compute_psf(front, arcmin_per_px=0.2, size_px=135, pixel="sample")
    reference = blur_image(blob(0.2), psf_fine, arcmin_per_px=0.2, padding="constant", background=0.0, dtype=np.float64)
    reference = reference.reshape(64, 5, 64, 5).mean(axis=(1, 3))
    coarse = blob(0.2).reshape(64, 5, 64, 5).mean(axis=(1, 3))  # exact pixel integrals
    errors = {}
    for pixel in ("sample", "integrate"):
        psf = compute_psf(front, arcmin_per_px=1.0, size_px=27, pixel=pixel)
        out = blur_image(coarse, psf, arcmin_per_px=1.0, padding="constant", background=0.0, dtype=np.float64)
        errors[pixel] = float(np.max(np.abs(out - reference)))
    assert errors["sample"] < 2e-4
    assert errors["integrate"] > 5 * errors["sample"]


# Overlap-save tiling (large images) against direct convolution: scipy.ndimage sums the kernel
# over the padded neighbourhood, sharing no code with the FFT path (odd kernels: the centre is
# unambiguous; ``ndimage.convolve`` flips the kernel as convolution does).
NDIMAGE_MODES = {"edge": "nearest", "reflect": "reflect", "constant": "constant"}


@settings(max_examples=20, deadline=None)
@given(
    st.integers(40, 260), st.integers(40, 260), st.integers(1, 12), st.sampled_from(sorted(NDIMAGE_MODES)),
    st.integers(0, 2**32 - 1),
)
def test_tiled_blur_equals_direct_convolution(rows, cols, half_kernel, padding, seed):
    from scipy import ndimage

    import vissim.optics.blur.convolve as blur

    rng = np.random.default_rng(seed)
    image = rng.random((rows, cols))
    size = 2 * half_kernel + 1
    kernel = rng.random((size, size))
    psf = PSF.from_array(kernel / kernel.sum(), 1.0)
    with pytest.MonkeyPatch.context() as patch:  # force tiles small enough for these images
        patch.setattr(blur, "tile_sizes_px", lambda: (32, 48, 64, 96, 128))
        patch.setattr(blur, "TILE_COST_FACTOR", 0.0)
        tile = blur._tile_px((rows, cols), size)
        out = blur_image(image, psf, arcmin_per_px=1.0, padding=padding, dtype=np.float64)
    background = np.mean(np.concatenate([image[0], image[-1], image[1:-1, 0], image[1:-1, -1]]))
    direct = ndimage.convolve(image, psf.data, mode=NDIMAGE_MODES[padding], cval=background)
    np.testing.assert_allclose(out, direct, atol=1e-12)
    if min(rows, cols) >= 130 and size <= 9:
        assert tile is not None  # the tiled path was taken


def test_tiles_only_for_large_images_and_small_kernels():
    from vissim.optics.blur.convolve import _tile_px

    assert _tile_px((2160, 3840), 45) is not None  # 4K, a 45 px PSF
    assert _tile_px((150, 150), 45) is None  # a campaign tile: one FFT
    assert _tile_px((2160, 3840), 301) is None  # a kernel as large as the tiles


def test_wrap_padding_refuses_a_psf_larger_than_the_image_on_both_paths(defocus_psf):
    # The 46 px PSF cannot wrap around a 40 px image: one refusal, decided in checked_blur_inputs.
    from vissim.optics.blur.device import blur_image_on

    image = random_image(shape=(40, 60))
    for blur in (blur_image, blur_image_on):
        with pytest.raises(VissimInputError, match=r"46 × 46 px PSF is larger than the 60 × 40 px \(width × height\) image"):
            blur(image, defocus_psf, arcmin_per_px=1.0, padding="wrap")


def test_each_padding_mode_continues_the_image_as_named():
    # Decided once (convolve.NUMPY_PAD_MODES) for blur_image, the device blur and the depth blur.
    from vissim.optics.blur.convolve import PADDING_MODES, pad_array

    row = np.array([[1.0, 2.0, 3.0]])
    expected = {"constant": [9, 9, 1, 2, 3, 9, 9], "edge": [1, 1, 1, 2, 3, 3, 3],
                "reflect": [2, 1, 1, 2, 3, 3, 2], "wrap": [2, 3, 1, 2, 3, 1, 2]}
    assert set(expected) == set(PADDING_MODES)
    for mode, values in expected.items():
        np.testing.assert_array_equal(pad_array(row, ((0, 0), (2, 2)), mode, background=9.0), [values], err_msg=mode)

