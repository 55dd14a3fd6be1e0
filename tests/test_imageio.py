"""Image files, linear light, provenance and atomic writes.

Tolerances: float32 EXR round trips are bit-exact (the format stores float32 as-is);
integer files are within half a quantisation step (round-to-nearest) in *encoded*
space, plus 1e-6 for float32 storage of the decoded linear values.  sRGB constants
and the expected values come from IEC 61966-2-1:1999.
"""

from __future__ import annotations

import json
import struct
import zlib
from pathlib import Path

import numpy as np
import OpenEXR
import pytest
import tifffile
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image as PILImage

from vissim.atomic import atomic_output, write_json_atomic, write_text_atomic
from vissim.errors import VissimInputError
from vissim.imageio import Image, output_bit_depth, read_image, srgb_decode, srgb_encode, to_preview_png, write_image
from vissim.provenance import from_json, make_provenance, to_json

RNG_SEED = 20240601
FLOAT32_SLOP = 1e-6


def _rng() -> np.random.Generator:
    return np.random.default_rng(RNG_SEED)


def _assert_one_line(err: pytest.ExceptionInfo) -> None:
    assert "\n" not in str(err.value)


# ---------------------------------------------------------------- sRGB transfer curve


def test_srgb_decode_of_half_matches_iec_61966_2_1():
    # ((0.5 + 0.055) / 1.055) ** 2.4 = 0.214041140... (IEC 61966-2-1 decoding formula).
    assert float(srgb_decode(0.5)) == pytest.approx(0.21404114, abs=1e-8)


def test_srgb_known_values_at_ends_threshold_and_mid_grey():
    assert float(srgb_encode(0.0)) == 0.0
    assert float(srgb_encode(1.0)) == pytest.approx(1.0, abs=1e-12)
    assert float(srgb_decode(1.0)) == pytest.approx(1.0, abs=1e-12)
    # Linear segment below the threshold: 12.92 * 0.0031308 = 0.040449936.
    assert float(srgb_encode(0.0031308)) == pytest.approx(0.040449936, abs=1e-9)
    assert float(srgb_decode(0.04045)) == pytest.approx(0.04045 / 12.92, abs=1e-12)
    # 18 % grey encodes to 8-bit code 118 (commonly quoted; 255 * 0.46136 = 117.65).
    assert round(float(srgb_encode(0.18)) * 255) == 118


def test_srgb_round_trip_float64_within_1e_6():
    x = np.linspace(0.0, 1.0, 10_001)
    assert np.max(np.abs(srgb_decode(srgb_encode(x)) - x)) <= 1e-6


def test_srgb_encode_clips_to_unit_interval_and_keeps_float32():
    out = srgb_encode(np.array([-0.5, 0.25, 3.0], dtype=np.float32))
    assert out.dtype == np.float32
    assert out[0] == 0.0 and out[2] == pytest.approx(1.0, abs=1e-6)


@settings(deadline=None, max_examples=200)
@given(st.floats(min_value=0.0, max_value=1.0, allow_nan=False))
def test_srgb_decode_inverts_encode_on_unit_interval(x):
    assert abs(float(srgb_decode(srgb_encode(x))) - x) <= 1e-6


@settings(deadline=None, max_examples=100)
@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_srgb_encode_is_monotonic(a, b):
    lo, hi = sorted((a, b))
    assert float(srgb_encode(lo)) <= float(srgb_encode(hi))


# ---------------------------------------------------------------- EXR


def _hdr_values(shape) -> np.ndarray:
    """float32 values well outside [0, 1], negatives and a subnormal: none may change."""
    arr = (_rng().standard_normal(shape) * 100).astype(np.float32)
    arr.flat[0] = np.float32(1e-42)
    arr.flat[1] = np.finfo(np.float32).max
    return arr


@pytest.mark.parametrize("shape", [(17, 23), (17, 23, 3)], ids=["mono", "rgb"])
def test_exr_round_trip_is_bit_exact_and_keeps_provenance(tmp_path, shape):
    pixels = _hdr_values(shape)
    prov = make_provenance(pupil_diameter_mm=np.float64(3.5), scene=tmp_path / "scene.json", zernike_um=np.arange(3.0))
    out = write_image(tmp_path / "img.exr", pixels, provenance=prov)
    image = read_image(out)
    assert image.pixels.dtype == np.float32
    assert image.pixels.tobytes() == pixels.tobytes()
    assert image.channel_names == (("Y",) if len(shape) == 2 else ("R", "G", "B"))
    assert image.provenance == json.loads(to_json(prov))
    assert image.provenance["inputs"]["pupil_diameter_mm"] == 3.5


def test_exr_provenance_is_a_single_string_attribute(tmp_path):
    write_image(tmp_path / "img.exr", np.ones((4, 5), np.float32), provenance={"n": 3, "x_mm": 0.5})
    header = OpenEXR.File(str(tmp_path / "img.exr"), header_only=True).parts[0].header
    assert isinstance(header["vissim_provenance"], str)
    assert from_json(header["vissim_provenance"]) == {"n": 3, "x_mm": 0.5}
    assert "n" not in header and "x_mm" not in header


def test_exr_write_of_non_contiguous_view_is_bit_exact(tmp_path):
    # OpenEXR.Channel ignores strides; write_image must copy views to contiguous memory.
    base = _hdr_values((20, 30, 3))
    view = base[::2, ::3]
    write_image(tmp_path / "v.exr", view)
    assert read_image(tmp_path / "v.exr").pixels.tobytes() == np.ascontiguousarray(view).tobytes()


def test_truncated_exr_is_refused_with_one_line(tmp_path):
    path = write_image(tmp_path / "full.exr", _rng().random((64, 48, 3), dtype=np.float32))
    data = path.read_bytes()
    cut = tmp_path / "cut.exr"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(VissimInputError, match="cut.exr") as err:
        read_image(cut)
    _assert_one_line(err)


def test_exr_with_only_z_channel_is_refused_naming_the_channels(tmp_path):
    path = tmp_path / "depth.exr"
    OpenEXR.File({}, {"Z": OpenEXR.Channel(np.zeros((4, 4), np.float32))}).write(str(path))
    with pytest.raises(VissimInputError, match=r"channels \['Z'\]") as err:
        read_image(path)
    _assert_one_line(err)


def test_exr_ignores_alpha_and_reads_half_as_float32(tmp_path):
    rgb = _rng().random((5, 6, 3)).astype(np.float16)
    chans = {c: OpenEXR.Channel(np.ascontiguousarray(rgb[..., i])) for i, c in enumerate("RGB")}
    chans["A"] = OpenEXR.Channel(np.ones((5, 6), np.float16))
    OpenEXR.File({}, chans).write(str(tmp_path / "h.exr"))
    image = read_image(tmp_path / "h.exr")
    assert image.pixels.shape == (5, 6, 3) and image.pixels.dtype == np.float32
    assert np.array_equal(image.pixels, rgb.astype(np.float32))


# ---------------------------------------------------------------- PNG / TIFF


def _encoded_error(read: np.ndarray, original: np.ndarray) -> float:
    return float(np.max(np.abs(srgb_encode(read.astype(np.float64)) - srgb_encode(original.astype(np.float64)))))


@pytest.mark.parametrize(
    ("suffix", "shape", "bit_depth"),
    [(".png", (19, 21, 3), 8), (".png", (19, 21), 8), (".png", (19, 21), 16),
     (".tif", (19, 21, 3), 16), (".tiff", (19, 21), 8)],
)
def test_integer_round_trip_within_half_a_quantisation_step(tmp_path, suffix, shape, bit_depth):
    pixels = _rng().random(shape, dtype=np.float32)
    path = write_image(tmp_path / f"img{suffix}", pixels, bit_depth=bit_depth, provenance={"seed": RNG_SEED})
    image = read_image(path)
    assert image.pixels.shape == shape and image.pixels.dtype == np.float32
    step = 1.0 / (2**bit_depth - 1)
    assert _encoded_error(image.pixels, pixels) <= 0.5 * step + FLOAT32_SLOP
    assert (tmp_path / f"img{suffix}.json").is_file()
    assert image.provenance == {"seed": RNG_SEED}


def test_png_stores_srgb_codes(tmp_path):
    write_image(tmp_path / "g.png", np.full((2, 2), 0.18, np.float32))
    assert np.all(np.asarray(PILImage.open(tmp_path / "g.png")) == 118)


def test_linear_encoding_round_trip_within_half_a_step(tmp_path):
    pixels = _rng().random((8, 9), dtype=np.float32)
    write_image(tmp_path / "lin.png", pixels, encoding="linear", bit_depth=16)
    image = read_image(tmp_path / "lin.png", encoding="linear")
    assert np.max(np.abs(image.pixels - pixels)) <= 0.5 / 65535 + FLOAT32_SLOP


def test_float32_tiff_is_read_as_linear_exactly(tmp_path):
    pixels = _rng().random((7, 8, 3), dtype=np.float32) * 4.0
    tifffile.imwrite(tmp_path / "f.tif", pixels, photometric="rgb")
    image = read_image(tmp_path / "f.tif")
    assert image.pixels.tobytes() == pixels.tobytes()
    assert image.provenance == {}


def test_png_alpha_is_dropped(tmp_path):
    rgba = _rng().integers(0, 256, (5, 6, 4), dtype=np.uint8)
    PILImage.fromarray(rgba).save(tmp_path / "a.png")
    image = read_image(tmp_path / "a.png")
    assert image.pixels.shape == (5, 6, 3)
    assert np.allclose(image.pixels, srgb_decode(rgba[..., :3] / 255.0), atol=FLOAT32_SLOP)


def test_text_file_named_png_is_refused(tmp_path):
    path = tmp_path / "x.png"
    path.write_text("not an image\n")
    with pytest.raises(VissimInputError, match="x.png") as err:
        read_image(path)
    _assert_one_line(err)


def test_truncated_png_and_tiff_are_refused(tmp_path):
    noise = _rng().random((64, 64, 3), dtype=np.float32)
    for name in ("n.png", "n.tif"):
        data = write_image(tmp_path / name, noise).read_bytes()
        (tmp_path / f"cut_{name}").write_bytes(data[: len(data) // 2])
        with pytest.raises(VissimInputError, match=f"cut_{name}"):
            read_image(tmp_path / f"cut_{name}")


def test_16_bit_colour_png_is_refused_both_ways(tmp_path):
    with pytest.raises(VissimInputError, match="16-bit colour PNG"):
        write_image(tmp_path / "c.png", np.zeros((2, 2, 3)), bit_depth=16)
    # Hand-made 16-bit RGB PNG (filter 0): Pillow would silently truncate it to 8 bits.
    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    rows = b"".join(b"\x00" + np.full((2, 3), 40000, ">u2").tobytes() for _ in range(2))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 16, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
    (tmp_path / "c16.png").write_bytes(png)
    with pytest.raises(VissimInputError, match="16-bit colour PNG"):
        read_image(tmp_path / "c16.png")


def test_16_bit_grey_with_alpha_png_is_refused_both_ways_and_grey_alone_kept(tmp_path):
    # Pillow keeps 16 bits only for grey without alpha; the writer, the reader and output_bit_depth share that rule.
    with pytest.raises(VissimInputError, match=r"16-bit grey \+ alpha PNG"):
        write_image(tmp_path / "a.png", np.zeros((2, 2)), alpha=np.ones((2, 2)), bit_depth=16)
    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    rows = b"".join(b"\x00" + np.full((2, 2), 40000, ">u2").tobytes() for _ in range(2))  # grey, alpha
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 16, 4, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
    (tmp_path / "la16.png").write_bytes(png)
    with pytest.raises(VissimInputError, match=r"16-bit grey \+ alpha PNG"):
        read_image(tmp_path / "la16.png")
    grey = write_image(tmp_path / "g.png", np.full((2, 2), 12345 / 65535), encoding="linear", bit_depth=16)
    assert read_image(grey).bit_depth == 16 and output_bit_depth(read_image(grey), tmp_path / "out.png") == 16


# ---------------------------------------------------------------- write validation


@pytest.mark.parametrize(
    ("pixels", "match"),
    [(np.array([[0.1, np.nan]]), "NaN or infinite"), (np.array([[np.inf]]), "NaN or infinite"),
     (np.zeros(5), "shape"), (np.zeros((2, 2, 4)), "4 channels"), (np.zeros((2, 2, 2, 3)), "shape")],
)
def test_bad_pixels_are_refused(tmp_path, pixels, match):
    with pytest.raises(VissimInputError, match=match) as err:
        write_image(tmp_path / "bad.exr", pixels)
    _assert_one_line(err)
    assert list(tmp_path.iterdir()) == []


def test_unsupported_suffix_and_mismatched_channel_names_are_refused(tmp_path):
    with pytest.raises(VissimInputError, match=r"'\.pdf'"):
        write_image(tmp_path / "out.pdf", np.zeros((2, 2)))
    with pytest.raises(VissimInputError, match="channel_names"):
        write_image(tmp_path / "out.exr", np.zeros((2, 2)), channel_names=("R", "G", "B"))


@pytest.mark.parametrize("name", ["keep.png", "keep.exr"])
def test_refuses_to_overwrite_and_leaves_original_untouched(tmp_path, name):
    path = write_image(tmp_path / name, np.full((3, 3), 0.25, np.float32))
    before = path.read_bytes()
    with pytest.raises(VissimInputError, match="already exists") as err:
        write_image(path, np.full((3, 3), 0.75, np.float32))
    _assert_one_line(err)
    assert path.read_bytes() == before
    write_image(path, np.full((3, 3), 0.75, np.float32), overwrite=True)
    assert read_image(path).pixels.mean() == pytest.approx(0.75, abs=0.01)
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_overwrite_without_provenance_removes_stale_sidecar(tmp_path):
    path = write_image(tmp_path / "s.png", np.zeros((2, 2)), provenance={"run": 1})
    write_image(path, np.zeros((2, 2)), overwrite=True)
    assert not (tmp_path / "s.png.json").exists()
    assert read_image(path).provenance == {}


def test_preview_png_scales_peak_to_white(tmp_path):
    psf = np.zeros((9, 9), np.float32)
    psf[4, 4], psf[4, 5] = 0.02, 0.005
    to_preview_png(tmp_path / "psf.png", psf)
    codes = np.asarray(PILImage.open(tmp_path / "psf.png"))
    assert codes[4, 4] == 255 and codes[0, 0] == 0
    assert codes[4, 5] == round(float(srgb_encode(0.25)) * 255)
    with pytest.raises(VissimInputError, match="maximum"):
        to_preview_png(tmp_path / "zero.png", np.zeros((3, 3)))


def test_image_rejects_mismatched_channel_names():
    with pytest.raises(VissimInputError):
        Image(np.zeros((2, 2), np.float32), ("R", "G", "B"))


# ---------------------------------------------------------------- atomic writes


@pytest.mark.parametrize("exc_type", [ValueError, KeyboardInterrupt])
def test_exception_inside_atomic_output_leaves_no_temp_and_no_target(tmp_path, exc_type):
    target = tmp_path / "sub" / "out.png"
    with pytest.raises(exc_type):
        with atomic_output(target) as tmp:
            assert tmp.parent == target.parent and tmp.name.startswith(".out.png.") and tmp.suffix == ".png"
            tmp.write_bytes(b"partial")
            raise exc_type("boom")
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []  # nor the folder the write made for it


def test_failed_overwrite_keeps_existing_target(tmp_path):
    target = write_text_atomic(tmp_path / "notes.txt", "original")
    with pytest.raises(VissimInputError, match=f"cannot write {target}: disk full"):  # a writer's own error
        with atomic_output(target, overwrite=True) as tmp:
            tmp.write_text("half")
            raise RuntimeError("disk full")
    assert target.read_text() == "original"
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]


def test_write_json_atomic_is_sorted_indented_and_refuses_nan(tmp_path):
    path = write_json_atomic(tmp_path / "m.json", {"b": 1, "a": [1.5]})
    assert path.read_text() == json.dumps({"a": [1.5], "b": 1}, indent=2) + "\n"
    with pytest.raises(VissimInputError, match="finite"):
        write_json_atomic(tmp_path / "nan.json", {"x_mm": float("nan")})
    assert not (tmp_path / "nan.json").exists()


def test_provenance_records_versions_and_json_safe_inputs():
    prov = make_provenance(path=Path("a/b.exr"), arr=np.array([1, 2]), x=np.float32(0.5), bad=float("inf"))
    assert set(prov) == {"vissim_version", "python", "numpy", "created_utc", "inputs"}
    assert prov["inputs"] == {"path": "a/b.exr", "arr": [1, 2], "x": 0.5, "bad": "inf"}
    assert from_json(to_json(prov)) == prov
    with pytest.raises(VissimInputError):
        from_json("[1, 2]")


def test_data_maps_round_trip_with_infinity_and_refuse_nan(tmp_path):
    from vissim.imageio import read_data_map, write_data_map

    depth = np.array([[0.5, 2.0], [np.inf, 6.0]], np.float32)
    path = write_data_map(tmp_path / "depth.exr", depth, provenance={"unit": "m"})
    back = read_data_map(path)
    assert back.channel_names == ("Z",) and back.provenance["unit"] == "m"
    np.testing.assert_array_equal(back.pixels, depth)
    np.save(tmp_path / "d.npy", depth.astype(np.float64))
    np.testing.assert_array_equal(read_data_map(tmp_path / "d.npy").pixels, depth)
    with pytest.raises(VissimInputError, match="NaN"):
        write_data_map(tmp_path / "bad.exr", np.array([[np.nan, 1.0]]))


# ---------------------------------------------------------------- angular sampling


@pytest.mark.parametrize("name", ["s.exr", "s.png", "s.tif"])
def test_arcmin_per_px_round_trips_through_the_file(tmp_path, name):
    path = tmp_path / name
    pixels = _rng().random((6, 5)).astype(np.float32)
    write_image(path, pixels, provenance=make_provenance(command="test"), arcmin_per_px=0.375)
    image = read_image(path)
    assert image.arcmin_per_px == 0.375
    assert image.provenance["arcmin_per_px"] == 0.375  # the one documented place: top-level key
    assert image.provenance["inputs"]["command"] == "test"  # the rest of the record is kept
    if path.suffix != ".exr":
        assert json.loads((tmp_path / (name + ".json")).read_text())["arcmin_per_px"] == 0.375


def test_arcmin_per_px_without_other_provenance_writes_a_record(tmp_path):
    write_image(tmp_path / "a.png", np.zeros((3, 3), np.float32), arcmin_per_px=2.0)
    assert (tmp_path / "a.png.json").is_file()
    assert read_image(tmp_path / "a.png").arcmin_per_px == 2.0
    to_preview_png(tmp_path / "p.png", np.ones((3, 3), np.float32), arcmin_per_px=0.25)
    assert read_image(tmp_path / "p.png").arcmin_per_px == 0.25


def test_an_image_without_sampling_reads_as_none(tmp_path):
    write_image(tmp_path / "a.exr", np.zeros((3, 3), np.float32))
    write_image(tmp_path / "b.png", np.zeros((3, 3), np.float32), provenance={"note": "no sampling"})
    assert read_image(tmp_path / "a.exr").arcmin_per_px is None
    assert read_image(tmp_path / "b.png").arcmin_per_px is None


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), 1e9])
def test_a_bad_arcmin_per_px_is_refused_before_writing(tmp_path, value):
    with pytest.raises(VissimInputError, match="arcmin per pixel") as err:
        write_image(tmp_path / "a.exr", np.zeros((3, 3), np.float32), arcmin_per_px=value)
    _assert_one_line(err)
    assert not (tmp_path / "a.exr").exists()


@pytest.mark.parametrize("provenance", [
    {"inputs": {"arcmin_per_px": 0.5}},                                   # blur, blur-depth outputs
    {"inputs": {"command": "vissim chart", "options": {"arcmin_per_px": 0.5}}},  # vissim chart
    {"inputs": {"bench": {"arcmin_per_px": 0.5, "spp": 4}}},              # render bench
    {"inputs": {"render": {"arcmin_per_px": 0.5}}},                       # campaign renders
    {"inputs": {"settings": {"arcmin_per_px": 0.5}}},                     # campaign items
    {"inputs": {"summary": {"arcmin_per_px": 0.5}}},                      # render atv
    {"inputs": {"psf": {"arcmin_per_px": 0.5}}},                          # psf
])
def test_files_written_before_the_sampling_key_keep_their_sampling(tmp_path, provenance):
    write_image(tmp_path / "old.exr", np.zeros((3, 3), np.float32), provenance=provenance)
    write_image(tmp_path / "old.png", np.zeros((3, 3), np.float32), provenance=provenance)
    assert read_image(tmp_path / "old.exr").arcmin_per_px == 0.5
    assert read_image(tmp_path / "old.png").arcmin_per_px == 0.5


def test_the_top_level_sampling_wins_over_older_places(tmp_path):
    write_image(tmp_path / "a.exr", np.zeros((3, 3), np.float32),
                provenance={"inputs": {"input_provenance": {"arcmin_per_px": 9.0}, "arcmin_per_px": 3.0}},
                arcmin_per_px=1.5)
    assert read_image(tmp_path / "a.exr").arcmin_per_px == 1.5
    # a sampling buried in an *input's* provenance is not the image's own
    write_image(tmp_path / "b.exr", np.zeros((3, 3), np.float32),
                provenance={"inputs": {"input_provenance": {"arcmin_per_px": 9.0}}})
    assert read_image(tmp_path / "b.exr").arcmin_per_px is None


def test_image_arcmin_per_px_must_be_positive():
    assert Image(np.zeros((2, 2), np.float32), ("Y",), {}, 1).arcmin_per_px == 1.0
    with pytest.raises(VissimInputError, match="arcmin_per_px"):
        Image(np.zeros((2, 2), np.float32), ("Y",), {}, -1.0)
