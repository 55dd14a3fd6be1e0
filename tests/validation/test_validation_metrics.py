"""Comparison metrics: SSIM (Wang 2004), PSNR and absolute difference, against scikit-image and formulas."""

import json
import math

import numpy as np
import pytest
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

from vissim.errors import VissimInputError
from vissim.imaging.metrics import compare_images, noise_floor

WANG_2004 = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False)


def pair(shape=(48, 64), seed=0):
    rng = np.random.default_rng(seed)
    reference = rng.random(shape)
    return reference, np.clip(reference + rng.normal(0, 0.05, shape), 0, 1)


def test_ssim_is_scikit_images_wang_2004_ssim():
    # Oracle: skimage.metrics.structural_similarity with Wang et al. 2004's settings, called directly.
    reference, test = pair()
    result = compare_images(reference, test, data_range=1.0)
    expected, expected_map = structural_similarity(reference, test, data_range=1.0, full=True, **WANG_2004)
    assert result.ssim == expected
    np.testing.assert_array_equal(result.ssim_map, expected_map)


def test_colour_ssim_is_the_mean_over_channels():
    reference, test = pair((40, 40, 3), seed=1)
    result = compare_images(reference, test, data_range=1.0)
    expected = structural_similarity(reference, test, data_range=1.0, channel_axis=-1, **WANG_2004)
    assert result.ssim == expected
    assert result.ssim_map.shape == (40, 40, 3)


def test_psnr_of_a_known_mse_follows_the_formula():
    # A uniform error of 0.1 on a range of 1: MSE = 0.01, PSNR = 10 log10(1 / 0.01) = 20 dB exactly.
    reference = np.zeros((32, 32))
    result = compare_images(reference, reference + 0.1, data_range=1.0)
    assert result.mse == pytest.approx(0.01, rel=1e-12)
    assert result.psnr_db == pytest.approx(20.0, abs=1e-9)
    np.testing.assert_allclose(result.squared_error_map, 0.01, rtol=1e-12)
    # The same range in 14-bit data numbers: 10 log10(16383**2 / 1638.3**2) = 20 dB.
    assert compare_images(reference, reference + 1638.3, data_range=16383).psnr_db == pytest.approx(20.0, abs=1e-9)


def test_psnr_equals_scikit_images():
    reference, test = pair(seed=2)
    expected = peak_signal_noise_ratio(reference, test, data_range=1.0)
    assert compare_images(reference, test, data_range=1.0).psnr_db == pytest.approx(expected, rel=1e-12)


def test_absolute_difference_map_and_mean():
    reference, test = pair(seed=3)
    result = compare_images(reference, test, data_range=1.0)
    np.testing.assert_array_equal(result.abs_diff_map, np.abs(reference - test))
    assert result.mean_abs_diff == pytest.approx(np.abs(reference - test).mean(), rel=1e-12)
    assert result.max_abs_diff == np.abs(reference - test).max()


def test_data_range_is_required_and_never_guessed():
    reference, test = pair()
    with pytest.raises(TypeError):
        compare_images(reference, test)  # keyword-only and without a default
    for bad in (None, 0, -1.0, math.nan, math.inf, "full"):
        with pytest.raises(VissimInputError, match="data_range"):
            compare_images(reference, test, data_range=bad)


def test_shapes_must_match():
    with pytest.raises(VissimInputError, match="sizes must match"):
        compare_images(np.zeros((32, 32)), np.zeros((32, 33)), data_range=1.0)


def test_images_smaller_than_the_ssim_window_are_refused():
    with pytest.raises(VissimInputError, match=r"image is 32 × 8 px \(width × height\); SSIM.s Gaussian window needs at least 11 × 11 px"):
        compare_images(np.zeros((8, 32)), np.zeros((8, 32)), data_range=1.0)


def test_identical_images_give_ssim_1_and_infinite_psnr_in_json():
    reference, _ = pair()
    result = compare_images(reference, reference, data_range=1.0)
    assert result.ssim == pytest.approx(1.0) and result.psnr_db == math.inf and result.mse == 0.0
    table = result.as_json()
    assert table["psnr_db"] == "inf"
    json.dumps(table, allow_nan=False)  # numbers only, no maps, no NaN/inf
    assert "ssim_map" not in table


def test_noise_floor_of_two_seeds_has_mse_twice_the_noise_variance():
    # Two renders = one scene + independent Gaussian noise of sigma 0.02 each: E[MSE] = 2 sigma^2.
    # With 256 x 256 samples the MSE's relative standard error is sqrt(2 / 65536) = 0.55 %; allow 3 %.
    scene = np.random.default_rng(4).random((256, 256)) * 0.5 + 0.25
    sigma = 0.02
    a = scene + np.random.default_rng(10).normal(0, sigma, scene.shape)
    b = scene + np.random.default_rng(11).normal(0, sigma, scene.shape)
    floor = noise_floor(a, b, data_range=1.0)
    assert floor.mse == pytest.approx(2 * sigma**2, rel=0.03)
    assert floor.psnr_db == pytest.approx(10 * math.log10(1 / (2 * sigma**2)), abs=0.15)
    assert floor.as_json() == compare_images(a, b, data_range=1.0).as_json()
