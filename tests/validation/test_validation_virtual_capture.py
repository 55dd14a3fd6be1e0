"""The virtual DSLR: Bayer mosaic, sensor noise, quantisation, and a DNG that rawpy reads back exactly."""

import numpy as np
import pytest
import tifffile

from vissim.errors import VissimInputError
from vissim.imaging.raw import read_raw_linear
from vissim.imaging.virtual_capture import BAYER_PATTERNS, add_sensor_noise, mosaic_bayer, quantise, write_dng

BLACK_DN, WHITE_DN = 2048, 15000  # a 14-bit-like camera with a 2048 DN pedestal


def linear_rgb(shape=(48, 64), seed=0):
    return np.random.default_rng(seed).random((*shape, 3)).astype(np.float32)


def cfa_planes(mosaic):
    """The 2 x 2 cell's photosites in raster order, as read_raw_linear(mode="planes") lays them out."""
    return np.stack([mosaic[0::2, 0::2], mosaic[0::2, 1::2], mosaic[1::2, 0::2], mosaic[1::2, 1::2]], axis=-1)


@pytest.mark.parametrize("pattern", BAYER_PATTERNS)
def test_dng_round_trip_reproduces_the_linear_cfa_planes_exactly(tmp_path, pattern):
    # Noise-free path.  Oracle: (dn - black) / (white - black) in float64, rounded once to float32.
    mosaic = mosaic_bayer(linear_rgb(), pattern)
    dn = quantise(mosaic, BLACK_DN, WHITE_DN)
    path = write_dng(tmp_path / "capture.dng", dn, black_level=BLACK_DN, white_level=WHITE_DN, pattern=pattern)
    raw = read_raw_linear(path, mode="planes")
    expected = ((cfa_planes(dn).astype(np.float64) - BLACK_DN) / (WHITE_DN - BLACK_DN)).astype(np.float32)
    np.testing.assert_array_equal(raw.pixels, expected)  # bit-exact
    # ... and the linear image itself to within half a quantisation step (plus float32 rounding).
    step = 1.0 / (WHITE_DN - BLACK_DN)
    assert np.abs(raw.pixels - cfa_planes(mosaic)).max() <= 0.5 * step + 1e-7
    assert raw.cfa_pattern == pattern and raw.white_level == WHITE_DN and raw.black_levels == (BLACK_DN,) * 4
    names = dict(zip(raw.channel_names, range(4)))
    assert sorted(names) == ["B", "G", "G2", "R"]
    np.testing.assert_array_equal(raw.channel("R"), raw.pixels[..., pattern.index("R")])


def test_per_position_black_levels_are_subtracted_per_channel(tmp_path):
    black = (2000, 2010, 2020, 2030)  # per CFA position, raster order (BlackLevelRepeatDim 2 x 2)
    dn = quantise(np.full((32, 32), 0.5), 2048, WHITE_DN)
    path = write_dng(tmp_path / "black.dng", dn, black_level=black, white_level=WHITE_DN, pattern="GRBG")
    raw = read_raw_linear(path)
    assert raw.black_levels == black and raw.channel_names == ("G", "R", "B", "G2")
    expected = [(float(dn[0, 0]) - b) / (WHITE_DN - b) for b in black]
    np.testing.assert_allclose(raw.pixels[0, 0], expected, rtol=1e-6)


def test_metadata_survives_the_round_trip(tmp_path):
    path = write_dng(tmp_path / "meta.dng", quantise(np.full((32, 32), 0.1)), black_level=BLACK_DN,
                     white_level=WHITE_DN, pattern="RGGB", camera_model="Canon EOS Rebel T3 (virtual)",
                     exposure_s=1 / 60, provenance={"seed": 3})
    raw = read_raw_linear(path)
    assert raw.camera == "Canon EOS Rebel T3 (virtual)"
    assert raw.exposure_s == pytest.approx(1 / 60, rel=1e-6)  # LibRaw holds it as float32
    assert raw.iso is None
    with tifffile.TiffFile(path) as tif:
        page = tif.pages.first
        assert page.photometric == 32803 and page.tags["DNGVersion"].value == b"\x01\x04\x00\x00"
        assert '"seed": 3' in page.description


def test_demosaic_mode_of_a_flat_field_is_linear(tmp_path):
    rgb = np.empty((32, 48, 3), np.float32)
    rgb[...] = (0.1, 0.3, 0.6)
    dn = quantise(mosaic_bayer(rgb, "RGGB"), BLACK_DN, WHITE_DN)
    path = write_dng(tmp_path / "flat.dng", dn, black_level=BLACK_DN, white_level=WHITE_DN, pattern="RGGB")
    raw = read_raw_linear(path, mode="demosaic")
    assert raw.pixels.shape == (32, 48, 3) and raw.channel_names == ("R", "G", "B")
    # LibRaw scales to 16 bits: allow 2 / 65535 plus the DN quantisation.
    np.testing.assert_allclose(raw.pixels[4:-4, 4:-4], np.broadcast_to(rgb[4:-4, 4:-4], (24, 40, 3)),
                               atol=2 / 65535 + 0.5 / (WHITE_DN - BLACK_DN))
    np.testing.assert_allclose(read_raw_linear(path).rgb()[2:-2, 2:-2], rgb[:16, :24][2:-2, 2:-2], atol=1e-4)


def test_mosaic_takes_each_pixels_filter_colour():
    rgb = linear_rgb((4, 4))
    mosaic = mosaic_bayer(rgb, "BGGR")
    assert mosaic[0, 0] == rgb[0, 0, 2] and mosaic[0, 1] == rgb[0, 1, 1]
    assert mosaic[1, 0] == rgb[1, 0, 1] and mosaic[1, 1] == rgb[1, 1, 0]
    mono = rgb[..., 0]
    np.testing.assert_array_equal(mosaic_bayer(mono), mono)
    with pytest.raises(VissimInputError, match="Bayer pattern"):
        mosaic_bayer(rgb, "RGBW")


def test_sensor_noise_has_shot_and_read_variance_and_is_seeded():
    # Mean m (fraction of full well F): variance m / F + (read / F)^2 (Poisson + Gaussian).
    # 65536 samples: relative standard error of a variance ~ sqrt(2 / 65536) = 0.6 %; allow 4 %.
    full_well, read = 20000.0, 8.0
    flat = np.full((256, 256), 0.25)
    noisy = add_sensor_noise(flat, full_well_electrons=full_well, read_noise_electrons=read, rng=123)
    assert noisy.mean() == pytest.approx(0.25, abs=1e-4)
    assert noisy.var() == pytest.approx(0.25 / full_well + (read / full_well) ** 2, rel=0.04)
    again = add_sensor_noise(flat, full_well_electrons=full_well, read_noise_electrons=read,
                             rng=np.random.default_rng(123))
    np.testing.assert_array_equal(noisy, again)
    with pytest.raises(VissimInputError, match="full well"):
        add_sensor_noise(flat, full_well_electrons=0, read_noise_electrons=read, rng=1)


def test_quantise_rounds_and_clips_like_a_sensor():
    values = np.array([[-1.0, 0.0, 0.5, 1.0, 2.0]])
    dn = quantise(values, black_level=BLACK_DN, white_level=WHITE_DN)
    assert dn.dtype == np.uint16
    np.testing.assert_array_equal(dn, [[0, BLACK_DN, BLACK_DN + 6476, WHITE_DN, WHITE_DN]])
    with pytest.raises(VissimInputError, match="14 bits"):
        quantise(values, black_level=BLACK_DN, white_level=20000, bits=14)


def test_write_dng_refuses_to_overwrite_and_bad_input(tmp_path):
    dn = quantise(np.full((24, 24), 0.5))
    path = write_dng(tmp_path / "a.dng", dn, black_level=BLACK_DN, white_level=WHITE_DN, pattern="RGGB")
    with pytest.raises(VissimInputError, match="already exists"):
        write_dng(path, dn, black_level=BLACK_DN, white_level=WHITE_DN, pattern="RGGB")
    write_dng(path, dn, black_level=BLACK_DN, white_level=WHITE_DN, pattern="RGGB", overwrite=True)
    with pytest.raises(VissimInputError, match="uint16"):
        write_dng(tmp_path / "b.dng", dn.astype(np.float32), black_level=BLACK_DN, white_level=WHITE_DN,
                  pattern="RGGB")
    with pytest.raises(VissimInputError, match="white level"):
        write_dng(tmp_path / "c.dng", dn, black_level=BLACK_DN, white_level=1000, pattern="RGGB")
    with pytest.raises(VissimInputError, match="22 px"):
        write_dng(tmp_path / "d.dng", dn[:20], black_level=BLACK_DN, white_level=WHITE_DN, pattern="RGGB")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.dng"]
