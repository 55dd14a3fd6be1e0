"""A real camera file through the RAW path, against LibRaw's own linear decode.

The file: ``_DSC2164.ARW`` (Sony ILCE-7RM3, ISO 3200, 1/640 s, a blue-lit stage), fetched once
by ``scripts/fetch_real_raw.py`` with pip from the libraw-cffi 0.19.0 sdist and cached (see that
script).  Without the package index these tests skip, saying why; a file that does not match
its pinned sha256 fails them.

Oracle: ``rawpy.postprocess`` at half size (one output pixel per 2 x 2 CFA cell, so nothing is
interpolated: no demosaic differences), linear (``gamma=(1, 1)``, ``no_auto_bright``, 16 bits),
with the camera's white balance, in the camera's colour space (``raw``) and in sRGB.  LibRaw
subtracts the black level, scales and white-balances, converts colour and quantises on its
own; vissim does each of these itself from the file's metadata.  LibRaw takes the levels from
the file too (its ``user_sat`` counts from the black level, measured: ``user_sat=16383`` put
65535 at 16383 DN above black), so the stated levels are asserted directly.
"""

import importlib.util
import subprocess
import sys
import tarfile
from pathlib import Path

import numpy as np
import pytest
import rawpy

from vissim.errors import VissimInputError
from vissim.units import REC709_LUMINANCE
from vissim.validation.dslr.captures import capture_provenance, capture_tile, load_manifest, read_capture
from vissim.imaging.raw import read_raw_linear

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "fetch_real_raw.py"
DN16 = 1 / 65535  # one step of LibRaw's 16-bit output, 1 = the white level (green, after white balance)


def _load_fetcher():
    spec = importlib.util.spec_from_file_location("fetch_real_raw", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


fetcher = _load_fetcher()


@pytest.fixture(scope="module")
def arw_path():
    try:
        return fetcher.fetch_real_raw()
    except fetcher.FetchUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def arw(arw_path):
    return read_raw_linear(arw_path, mode="planes")


def libraw_half_size(path, colour_space):
    """LibRaw's linear decode with the camera's white balance, one pixel per CFA cell, in [0, 1]."""
    with rawpy.imread(str(path)) as raw:
        rgb16 = raw.postprocess(half_size=True, use_camera_wb=True, gamma=(1, 1), no_auto_bright=True,
                                output_bps=16, output_color=colour_space, user_flip=0, adjust_maximum_thr=0.0,
                                highlight_mode=rawpy.HighlightMode.Clip)
    return rgb16, rgb16.astype(np.float64) * DN16


def test_sony_arw_levels_pattern_and_white_balance(arw):
    # Sony's 14-bit ARW: black 512 DN, white 16383 DN (2^14 - 1); the ILCE-7RM3's sensor is RGGB.
    assert arw.camera == "SONY ILCE-7RM3"
    assert arw.black_levels == (512.0,) * 4 and arw.white_level == 16383.0
    assert arw.cfa_pattern == "RGGB" and arw.channel_names == ("R", "G", "G2", "B")
    # As-shot white balance, as LibRaw reads it from the file: R : G : B = 2528 : 1024 : 1564.
    assert arw.camera_wb == pytest.approx((2528 / 1024, 1.0, 1.0, 1564 / 1024), rel=1e-12)
    assert arw.iso == 3200 and arw.exposure_s == pytest.approx(1 / 640, rel=1e-6)
    assert arw.pixels.shape == (3464 // 2, 5184 // 2, 4) and arw.sha256 == fetcher.ARW_SHA256


def test_white_balanced_planes_match_libraw_photosite_for_photosite(arw, arw_path):
    codes, libraw = libraw_half_size(arw_path, rawpy.ColorSpace.raw)
    wb = np.array([arw.camera_wb[arw.channel_names.index(c)] for c in "RGB"])
    ours = arw.rgb().astype(np.float64) * wb
    inside = ((arw.pixels > 0) & (arw.pixels < 1)).all(axis=-1)  # LibRaw clips each photosite to [black, white]
    unclipped = inside[..., None] & (codes > 0) & (codes < 65535)
    assert unclipped.all(axis=-1).mean() > 0.5  # most of the frame is compared
    # LibRaw truncates each scaled photosite to a 16-bit integer: ours - LibRaw's in [0, 1) DN16 for R
    # and B; G is the mean of two truncated greens, so [0, 2) DN16.  A wrong black level (1 DN = 4 DN16),
    # white level, white balance or CFA position would leave this range on most pixels.
    for c, top in zip(range(3), (1, 2, 1)):
        difference = (ours[..., c] - libraw[..., c])[unclipped[..., c]] / DN16
        assert difference.min() > -0.01 and difference.max() < top, "RGB"[c]


def test_linear_luminance_matches_libraw_srgb(arw, arw_path):
    codes, srgb = libraw_half_size(arw_path, rawpy.ColorSpace.sRGB)
    ours = arw.luminance().astype(np.float64)
    theirs = srgb @ np.asarray(REC709_LUMINANCE)
    # Compared where LibRaw clipped nothing: every photosite of the cell inside (black, white) and
    # every sRGB channel inside (0, 65535); most of this saturated-blue scene is outside sRGB (R < 0).
    keep = ((arw.pixels > 0) & (arw.pixels < 1)).all(axis=-1) & ((codes > 0) & (codes < 65535)).all(axis=-1)
    assert keep.sum() > 100_000
    # Tolerance: LibRaw truncates the camera channels, then the sRGB channels, to 16 bits; through
    # the luminance weights of white-balanced camera RGB (0.26, 0.97, -0.23) that is under 4 DN16.
    # The relative part covers LibRaw's sRGB primaries (6 digits) against vissim's (IEC, 4 digits).
    np.testing.assert_allclose(ours[keep], theirs[keep], rtol=1e-3, atol=4 * DN16)


def test_capture_path_reads_the_arw_and_records_its_provenance(arw_path, tmp_path):
    # A capture manifest naming the real file; pitch 35.9 mm / 7952 px (Sony), focal length from the file.
    manifest = tmp_path / "manifest.toml"
    manifest.write_text(
        f'[[capture]]\nid = "a7r3"\nfile = "{arw_path}"\nsha256 = "{fetcher.ARW_SHA256}"\n'
        'pixel_pitch_um = 4.51\nfocal_length_mm = 129.0\nf_number = 6.3\nchart_distance_m = 20.0\n'
        'letter = "K"\nletter_center_px = [560.0, 2600.0]\n'
    )
    capture = load_manifest(manifest)["a7r3"]
    raw = read_capture(capture)
    record = capture_provenance(capture, raw)
    assert record["sha256"] == fetcher.ARW_SHA256 and record["file"] == str(arw_path)
    assert record["raw"]["camera"] == "SONY ILCE-7RM3" and record["raw"]["cfa_pattern"] == "RGGB"
    assert record["raw"]["black_levels"] == [512.0] * 4 and record["raw"]["white_level"] == 16383.0
    assert record["raw"]["camera_wb"] == pytest.approx([2528 / 1024, 1.0, 1.0, 1564 / 1024])
    # The tile step runs on a real file too (its paper ring is the lit screen here; a chart is tested
    # with virtual captures in test_capture_path.py).
    tile = capture_tile(capture, 1.0, (64, 64), raw=raw)
    assert tile.shape == (64, 64) and np.all(np.isfinite(tile))


def test_a_cut_short_arw_is_refused_not_read_as_repeated_rows(arw_path, tmp_path):
    # LibRaw decodes a Sony ARW cut in half without complaint (the missing rows repeat earlier data).
    half = tmp_path / "half.ARW"
    data = arw_path.read_bytes()
    half.write_bytes(data[: len(data) // 2])
    with pytest.raises(VissimInputError, match=f"half.ARW is truncated: .* byte {len(data)} .* {len(data) // 2} bytes"):
        read_raw_linear(half)


def test_a_tampered_sdist_fails_and_leaves_nothing_in_the_cache(tmp_path):
    member = tmp_path / "_DSC2164.ARW"
    member.write_bytes(b"\0" * fetcher.ARW_SIZE_BYTES)  # the right size, the wrong bytes
    sdist = tmp_path / fetcher.SDIST_NAME
    with tarfile.open(sdist, "w:gz") as archive:
        archive.add(member, arcname=fetcher.MEMBER)
    target = tmp_path / "cache" / "real_raw" / fetcher.ARW_NAME
    with pytest.raises(fetcher.HashMismatch, match="expected " + fetcher.ARW_SHA256):
        fetcher.extract_arw(sdist, target)
    assert not any(target.parent.iterdir())
    with pytest.raises(fetcher.HashMismatch, match="expected " + fetcher.SDIST_SHA256):
        fetcher.check_sha256(sdist, fetcher.SDIST_SHA256, "the sdist")


def test_a_damaged_cached_file_fails_rather_than_being_used(tmp_path):
    cached = tmp_path / "real_raw" / fetcher.ARW_NAME
    cached.parent.mkdir()
    cached.write_bytes(b"II*\0 not the ARW")
    with pytest.raises(fetcher.HashMismatch, match="delete it to fetch it again"):
        fetcher.fetch_real_raw(tmp_path)


def test_unreachable_index_is_a_skip_reason_not_a_failure(tmp_path, monkeypatch):
    monkeypatch.setenv("PIP_INDEX_URL", "http://127.0.0.1:9/simple")  # port 9 (discard): nothing listens
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path))
    with pytest.raises(fetcher.FetchUnavailable, match="could not fetch libraw-cffi 0.19.0 sdist from the package"):
        fetcher.fetch_real_raw()
    assert not (tmp_path / "real_raw" / fetcher.ARW_NAME).exists()


def test_script_prints_the_cached_path(arw_path):
    done = subprocess.run([sys.executable, str(SCRIPT)], capture_output=True, text=True, check=False,
                          env={"VISSIM_CACHE_DIR": str(arw_path.parent.parent), "PATH": ""})
    assert done.returncode == 0 and done.stdout.strip() == str(arw_path)
