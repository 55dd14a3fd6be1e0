"""RAW reading errors, letter crops from a capture, and the camera's angular sampling."""

import math

import numpy as np
import pytest
import tifffile

from vissim.charts import optotype_tile
from vissim.errors import VissimInputError
from vissim.imaging.raw import camera_arcmin_per_px, crop_letters, read_raw_linear, resample_to_arcmin
from vissim.imaging.virtual_capture import quantise, write_dng

# Canon EOS Rebel T3 / 1100D: 5.2 um pixel pitch (Canon specification), kit lens at 18 mm (thesis §4.4.2).
REBEL_T3_PITCH_UM = 5.2
REBEL_T3_FOCAL_MM = 18.0


def test_missing_raw_file_is_an_input_error(tmp_path):
    with pytest.raises(VissimInputError, match="does not exist"):
        read_raw_linear(tmp_path / "IMG_0001.CR2")


@pytest.mark.parametrize("content", [b"", b"not a raw file at all" * 100], ids=["empty", "garbage"])
def test_unreadable_raw_file_is_an_input_error(tmp_path, content):
    path = tmp_path / "IMG_0002.CR2"
    path.write_bytes(content)
    with pytest.raises(VissimInputError, match="cannot read .* as a camera RAW file"):
        read_raw_linear(path)


def test_truncated_dng_is_an_input_error(tmp_path):
    good = write_dng(tmp_path / "good.dng", quantise(np.full((32, 32), 0.5)), black_level=2048, white_level=15000,
                     pattern="RGGB")
    data = good.read_bytes()
    truncated = tmp_path / "truncated.dng"
    truncated.write_bytes(data[: len(data) // 2])
    for mode in ("planes", "demosaic"):
        with pytest.raises(VissimInputError, match="truncated.dng"):
            read_raw_linear(truncated, mode=mode)


def test_plain_tiff_is_not_taken_for_sensor_data(tmp_path):
    # LibRaw reads any uncompressed 16-bit TIFF as a Bayer RAW (RGGB, white 65535); vissim refuses it.
    path = tmp_path / "scan.tif"
    tifffile.imwrite(path, np.full((64, 64), 3000, np.uint16))
    for mode in ("planes", "demosaic"):
        with pytest.raises(VissimInputError, match="scan.tif is a plain TIFF image .* not a camera RAW file"):
            read_raw_linear(path, mode=mode)


def test_rows_of_zero_under_a_black_level_are_refused(tmp_path):
    # What LibRaw returns for raw data a short file lacks: rows of 0 DN, which a sensor with a
    # black level of 2048 DN cannot read.
    dn = quantise(np.full((32, 32), 0.5), black_level=2048, white_level=15000)
    dn[20:] = 0
    path = write_dng(tmp_path / "zeros.dng", dn, black_level=2048, white_level=15000, pattern="RGGB")
    with pytest.raises(VissimInputError, match="zeros.dng: 12 of 32 sensor rows .from row 20. are all 0 DN"):
        read_raw_linear(path)


def test_unknown_mode_is_refused(tmp_path):
    with pytest.raises(VissimInputError, match="planes, demosaic"):
        read_raw_linear(tmp_path / "x.dng", mode="half")


def test_rebel_t3_samples_about_one_arcmin_per_pixel():
    # atan(5.2 um / 18 mm) = 2.8889e-4 rad = 0.99313 arcmin (thesis: "about 1 arcmin per pixel").
    assert camera_arcmin_per_px(REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM) == pytest.approx(0.99313, abs=1e-5)
    # A planes-mode pixel spans two photosites: 1.986 arcmin.
    assert camera_arcmin_per_px(2 * REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM) == pytest.approx(1.98625, abs=1e-5)
    # Focused on the chart at 914.4 mm the sensor sits at 18 * 914.4 / 896.4 = 18.361 mm: 0.97358 arcmin.
    assert camera_arcmin_per_px(REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM, object_distance_m=0.9144) == pytest.approx(
        0.97358, abs=1e-5)
    with pytest.raises(VissimInputError, match="pixel pitch"):
        camera_arcmin_per_px(-5.2, 18.0)


def test_resampling_is_exact_pixel_area_integration():
    # Source at s arcmin/px, target 2 s: every output pixel is the mean of a 2 x 2 block, exactly.
    image = np.random.default_rng(0).random((40, 61)).astype(np.float32)
    source = camera_arcmin_per_px(REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM)
    out = resample_to_arcmin(image, REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM, 2 * source)
    assert out.pixels.shape == (20, 30) and out.scale == pytest.approx(0.5)
    np.testing.assert_allclose(out.pixels, image[:, :60].reshape(20, 2, 30, 2).mean(axis=(1, 3)), atol=1e-6)


def test_resampling_the_rebel_t3_to_one_arcmin_preserves_the_integral():
    image = np.random.default_rng(1).random((300, 200))
    out = resample_to_arcmin(image, REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM, 1.0)
    scale = out.scale  # 0.99313 output px per input px
    assert out.pixels.shape == (math.floor(300 * scale), math.floor(200 * scale)) == (297, 198)
    assert out.arcmin_per_px == 1.0 and out.source_arcmin_per_px == pytest.approx(0.99313, abs=1e-5)
    # The output covers input [0, n_out / scale) on each axis, the last input pixel partly; the sum of
    # output means times the output pixel area (1 / scale^2 input px) is the input's integral there.
    weights = [np.clip(n_out / scale - np.arange(n_in), 0.0, 1.0) for n_out, n_in in zip(out.pixels.shape, image.shape)]
    integral = weights[0] @ image @ weights[1]
    assert out.pixels.sum() / scale**2 == pytest.approx(integral, rel=1e-12)
    constant = resample_to_arcmin(np.full((50, 50), 0.37), REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM, 1.0)
    np.testing.assert_allclose(constant.pixels, 0.37, rtol=1e-12)


def test_planes_resampling_uses_twice_the_pixel_pitch(tmp_path):
    path = write_dng(tmp_path / "flat.dng", quantise(np.full((64, 64), 0.25)), black_level=2048, white_level=15000,
                     pattern="RGGB")
    planes = read_raw_linear(path)
    assert planes.sensor_px_per_pixel == 2
    out = resample_to_arcmin(planes, REBEL_T3_PITCH_UM, REBEL_T3_FOCAL_MM, 1.0)
    assert out.source_arcmin_per_px == pytest.approx(1.98625, abs=1e-5)
    assert out.pixels.shape == (63, 63, 4)  # floor(32 * 1.98625)


def test_crop_letters_finds_each_letter_in_a_scaled_shifted_capture():
    tile = optotype_tile("K", 1.0)  # 50 px letter snapped to whole pixels on the 133 x 113 tile
    capture = np.pad(np.kron(tile.pixels, np.ones((2, 2), np.float32)), ((10, 4), (7, 3)), constant_values=0.9)
    (crop,) = crop_letters(capture, tile.sidecar(), scale=2.0, offset_px=(10, 7))
    top, left, bottom, right = (int(v) for v in tile.letters[0].box_px)
    assert crop.letter == "K" and crop.logmar == 1.0
    assert crop.box_px == (10 + 2 * top, 7 + 2 * left, 10 + 2 * bottom, 7 + 2 * right)
    np.testing.assert_array_equal(crop.pixels, np.kron(tile.pixels[top:bottom, left:right], np.ones((2, 2))))
    (wide,) = crop_letters(capture, tile, scale=(2.0, 2.0), offset_px=(10, 7), margin_letter_heights=0.2)
    assert wide.pixels.shape == (2 * 70, 2 * 70)  # 50 px + 2 x 10 px margin, doubled


def test_crop_outside_the_capture_is_refused():
    tile = optotype_tile("K", 1.0)
    with pytest.raises(VissimInputError, match="outside"):
        crop_letters(tile.pixels, tile.sidecar(), scale=1.0, offset_px=(100, 0))
