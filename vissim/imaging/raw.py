"""Camera RAW files in as linear light, letter crops, and resampling to an angular grid.

This is the one module that imports `rawpy` (LibRaw).  `read_raw_linear` returns
float32 values proportional to the light each photosite collected, normalised per channel as
``(raw - black_c) / (white - black_c)``: black -> 0, the file's white (saturation) level -> 1.

* The black level is per channel (``raw.black_level_per_channel``); the white level is the
  file's (``raw.white_level``), never the dtype's maximum (a 12- or 14-bit camera stores its
  values in ``uint16``).
* ``mode="planes"`` (the default, and the one to validate with): no demosaicing.  Each pixel
  of the result is one 2 x 2 CFA cell; its channels are the cell's four photosites in raster
  order (top-left, top-right, bottom-left, bottom-right), named from the CFA pattern with the
  second green as ``"G2"`` (RGGB -> ``R, G, G2, B``).  Nothing is interpolated, clipped or
  white-balanced; values below black (read noise) stay negative so that means are unbiased.
  The planes are half-size: one pixel spans **two** photosite pitches, and the four planes
  are offset from each other by half a plane pixel (`RawImage.rgb` averages the greens
  regardless).
* ``mode="demosaic"``: LibRaw's bilinear demosaic (``DemosaicAlgorithm.LINEAR``, a linear
  operator, unlike AHD) with every non-linear step off: ``gamma=(1, 1)``,
  ``no_auto_bright=True``, ``adjust_maximum_thr=0`` (the white level is not re-estimated from
  the pixels), ``use_camera_wb=False, use_auto_wb=False, user_wb=[1, 1, 1, 1]`` (no white
  balance), ``output_color=ColorSpace.raw`` (no colour matrix), ``output_bps=16``,
  ``user_flip=0``, highlights clipped.  LibRaw clips negatives to 0 and quantises to 16 bits,
  so this mode is for looking at, not for measuring.

Camera colour, recorded and never applied to ``pixels``: ``camera_wb`` is the file's as-shot
white balance (multipliers per channel, green = 1) and ``camera_to_srgb`` the 3 x 3 matrix
from white-balanced camera RGB to linear sRGB (D65), derived as LibRaw and dcraw do from the
file's XYZ -> camera matrix (``raw.rgb_xyz_matrix``): ``cam_rgb = cam_xyz @ XYZ_FROM_SRGB``,
rows scaled to sum to 1 (so camera white maps to sRGB white), inverted.
`RawImage.luminance` combines them into relative linear luminance (Rec. 709 / sRGB
``Y``): 1 = a neutral surface that takes the green photosites to the white level.

`crop_letters` cuts the chart's letter boxes out of a capture, and
`resample_to_arcmin` brings a capture onto the renders' angular grid by exact pixel-area
integration.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import logging
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import rawpy
import tifffile

from vissim.charts import Chart
from vissim.checks import size_text
from vissim.checks import positive_number as _positive
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.units import REC709_LUMINANCE, m_to_mm, rad_to_arcmin

scipy_sparse = lazy_module("scipy.sparse")

logger = logging.getLogger(__name__)

__all__ = ["RAW_MODES", "XYZ_FROM_SRGB", "LetterCrop", "RawImage", "ResampledImage", "camera_arcmin_per_px",
           "crop_letters", "file_sha256", "read_file_bytes", "read_raw_linear", "resample_to_arcmin"]

RAW_MODES = ("planes", "demosaic")
_PHOTOMETRIC_CFA = 32803  # TIFF/EP PhotometricInterpretation of colour-filter-array data
#: Linear sRGB (D65) -> CIE XYZ, IEC 61966-2-1; its Y row is the Rec. 709 luminance.
XYZ_FROM_SRGB = ((0.4124, 0.3576, 0.1805), REC709_LUMINANCE, (0.0193, 0.1192, 0.9505))


@dataclasses.dataclass(frozen=True)
class RawImage:
    """Linear RAW pixels: float32 ``(H, W, C)``, 0 = black level, 1 = the file's white level.

    ``black_levels`` and ``white_level`` are in raw data numbers (DN), one black level per
    channel in ``channel_names`` order.  ``cfa_pattern`` is the 2 x 2 cell in raster order,
    e.g. ``"RGGB"``.  ``sensor_px_per_pixel`` is 2 for planes (one pixel per CFA cell) and 1
    for demosaiced images.  ``camera_wb`` (one multiplier per channel, green = 1) and
    ``camera_to_srgb`` (rows: sRGB R, G, B) are described in the module docstring.
    ``camera``, ``iso``, ``exposure_s``, ``camera_wb`` and ``camera_to_srgb`` are ``None``
    when the file does not say; ``sha256`` is the file's.
    """

    pixels: np.ndarray = dataclasses.field(repr=False)
    mode: str
    channel_names: tuple[str, ...]
    black_levels: tuple[float, ...]
    white_level: float
    cfa_pattern: str
    sensor_px_per_pixel: int
    camera: str | None = None
    iso: float | None = None
    exposure_s: float | None = None
    path: str | None = None
    camera_wb: tuple[float, ...] | None = None
    camera_to_srgb: tuple[tuple[float, float, float], ...] | None = None
    sha256: str | None = None

    def channel(self, name: str) -> np.ndarray:
        """One channel by name (``"R"``, ``"G"``, ``"G2"``, ``"B"``)."""
        if name not in self.channel_names:
            raise VissimInputError(f"no channel {name!r}; this image has {', '.join(self.channel_names)}")
        return self.pixels[..., self.channel_names.index(name)]

    def rgb(self) -> np.ndarray:
        """``(H, W, 3)`` float32 R, G, B; in planes mode G is the mean of the two green planes."""
        if self.mode == "demosaic":
            return self.pixels
        groups = [[i for i, n in enumerate(self.channel_names) if n.rstrip("2") == c] for c in "RGB"]
        return np.stack([self.pixels[..., g].mean(axis=-1) for g in groups], axis=-1).astype(np.float32)

    def luminance(self) -> np.ndarray:
        """``(H, W)`` float32 relative linear luminance: camera white balance, colour matrix, Rec. 709 ``Y``."""
        if self.camera_wb is None or self.camera_to_srgb is None:
            missing = "white balance" if self.camera_wb is None else "colour matrix"
            raise VissimInputError(f"{self.path} records no camera {missing}; its luminance is undefined")
        wb_rgb = np.array([self.camera_wb[self.channel_names.index(c)] for c in "RGB"])
        weights = (np.asarray(REC709_LUMINANCE) @ np.asarray(self.camera_to_srgb)) * wb_rgb
        return (self.rgb().astype(np.float64) @ weights).astype(np.float32)

    def as_json(self) -> dict[str, Any]:
        """Everything but the pixels, JSON-ready (for a capture manifest)."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "pixels"}
        out.update(channel_names=list(self.channel_names), black_levels=list(self.black_levels),
                   shape_px=list(self.pixels.shape),
                   camera_wb=None if self.camera_wb is None else list(self.camera_wb),
                   camera_to_srgb=None if self.camera_to_srgb is None else [list(r) for r in self.camera_to_srgb])
        return out


def read_file_bytes(path: str | os.PathLike[str]) -> bytes:
    """A RAW file's bytes, or one error naming it."""
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise VissimInputError(f"cannot read RAW file {path}: {exc.strerror or exc}") from None


def file_sha256(path: str | os.PathLike[str]) -> str:
    """The sha256 of a file's bytes, hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _camera_name(data: bytes) -> str | None:
    """Make and model from the TIFF tags of TIFF-based RAWs (DNG, CR2, NEF, ...); rawpy does not expose them."""
    try:
        with tifffile.TiffFile(io.BytesIO(data)) as tif:
            tags = tif.pages.first.tags
            unique = tags.get(50708)
            if unique is not None:
                return str(unique.value).strip() or None
            parts = [str(tags[k].value).strip() for k in ("Make", "Model") if k in tags]
    except Exception:  # noqa: BLE001 - not a TIFF-based RAW: no camera name, not an error
        return None
    name = " ".join(p for p in parts if p)
    return name or None


def _tiff_ifds(tif: Any) -> list[Any]:
    """The TIFF's IFDs and their sub-IFDs (where TIFF-based RAWs keep the sensor data)."""
    ifds = list(tif.pages)
    for page in list(ifds):
        for k in range(len(getattr(page, "subifds", None) or ())):
            ifds.append(tifffile.TiffPages(page, index=k).first)
    return ifds


def _check_tiff_structure(path: Path, data: bytes) -> None:
    """Refuse a plain TIFF (LibRaw reads any uncompressed TIFF as sensor data) and a TIFF-based RAW cut short
    (``data``: the file's bytes)."""
    try:
        with tifffile.TiffFile(io.BytesIO(data)) as tif:
            ifds = _tiff_ifds(tif)
            tags = ifds[0].tags
            camera_tags = any(k in tags for k in ("Make", "Model", 50706, 50708))  # 50706 DNGVersion, 50708 model
            cfa = any(int(getattr(ifd, "photometric", 0)) == _PHOTOMETRIC_CFA for ifd in ifds)
            data_end = max((o + n for ifd in ifds for o, n in zip(ifd.dataoffsets, ifd.databytecounts)), default=0)
    except Exception:  # noqa: BLE001 - not a TIFF (CR3, RAF, ...): LibRaw decides
        return
    if not (camera_tags or cfa):
        raise VissimInputError(f"{path} is a plain TIFF image (no Make, Model or DNG tags), not a camera RAW file")
    size = len(data)
    if data_end > size:
        raise VissimInputError(f"{path} is truncated: its image data runs to byte {data_end} but the file has "
                               f"{size} bytes")


def _refuse_zero_rows(raw: Any, path: Path) -> None:
    """LibRaw fills raw data missing from a short file with 0 DN; a sensor whose black level is above 0 never
    reads a whole row of 0 DN (TIFF-based files are caught earlier by their data offsets)."""
    black = min(float(b) for b in raw.black_level_per_channel)
    visible = np.asarray(raw.raw_image_visible)
    empty = np.flatnonzero(~visible.any(axis=1))
    if black > 0 and empty.size:
        raise VissimInputError(f"{path}: {empty.size} of {visible.shape[0]} sensor rows (from row {empty[0]}) are "
                               f"all 0 DN, below the black level {black:g} DN: truncated or damaged raw data")


def _nonzero(value: float) -> float | None:
    return float(value) if value and math.isfinite(value) and value > 0 else None


def _camera_wb(raw: Any, colour_indices: list[int]) -> tuple[float, ...] | None:
    """As-shot multipliers per CFA colour index (LibRaw order, e.g. R G B G2), green = 1; None if absent."""
    wb = [float(w) for w in raw.camera_whitebalance]
    if len(wb) > 3 and wb[3] == 0:
        wb[3] = wb[1]  # LibRaw leaves the second green 0 when it equals the first
    if wb[1] <= 0 or not all(math.isfinite(w) and w > 0 for w in (wb[i] for i in colour_indices)):
        return None
    return tuple(wb[i] / wb[1] for i in colour_indices)


def _camera_to_srgb(raw: Any) -> tuple[tuple[float, float, float], ...] | None:
    """White-balanced camera RGB -> linear sRGB from the file's XYZ -> camera matrix; None if it has none."""
    cam_xyz = np.asarray(raw.rgb_xyz_matrix, dtype=np.float64)[:3]
    cam_rgb = cam_xyz @ np.asarray(XYZ_FROM_SRGB)
    sums = cam_rgb.sum(axis=1, keepdims=True)
    if not np.all(np.isfinite(cam_rgb)) or np.any(sums <= 0):
        return None
    try:
        matrix = np.linalg.inv(cam_rgb / sums)
    except np.linalg.LinAlgError:
        return None
    return tuple(tuple(float(v) for v in row) for row in matrix)


def _planes(raw: Any, path: Path) -> tuple[np.ndarray, tuple[str, ...], tuple[float, ...], str]:
    pattern = raw.raw_pattern
    if pattern is None or np.asarray(pattern).shape != (2, 2) or raw.num_colors != 3:
        raise VissimInputError(f"{path} is not a 2 x 2 Bayer RAW (CFA pattern {pattern!r}); use mode='demosaic'")
    desc = raw.color_desc.decode("ascii")
    indices = [int(i) for i in np.asarray(pattern).ravel()]
    letters = [desc[i] for i in indices]
    cfa_pattern = "".join(letters)
    if sorted(cfa_pattern) != sorted("RGGB"):
        raise VissimInputError(f"{path} has CFA pattern {cfa_pattern!r}; planes mode reads R, G, G, B Bayer sensors")
    names = tuple("G2" if c == "G" and letters[:k].count("G") else c for k, c in enumerate(letters))
    black_per_colour = raw.black_level_per_channel
    black = np.array([black_per_colour[i] for i in indices], dtype=np.float64)
    visible = np.asarray(raw.raw_image_visible)
    rows, cols = (s - s % 2 for s in visible.shape)
    if (rows, cols) != visible.shape:
        logger.debug("%s: dropping the last odd row/column of a %s image", path, visible.shape)
    cells = visible[:rows, :cols].reshape(rows // 2, 2, cols // 2, 2).transpose(0, 2, 1, 3)
    planes = cells.reshape(rows // 2, cols // 2, 4).astype(np.float64)
    white = float(raw.white_level)
    linear = ((planes - black) / (white - black)).astype(np.float32)
    return linear, names, tuple(float(b) for b in black), cfa_pattern


def _demosaic(raw: Any) -> np.ndarray:
    rgb16 = raw.postprocess(
        demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR, gamma=(1, 1), no_auto_bright=True, bright=1.0,
        adjust_maximum_thr=0.0, use_camera_wb=False, use_auto_wb=False, user_wb=[1.0, 1.0, 1.0, 1.0],
        output_color=rawpy.ColorSpace.raw, output_bps=16, user_flip=0, highlight_mode=rawpy.HighlightMode.Clip,
    )
    return (rgb16.astype(np.float64) / 65535.0).astype(np.float32)


def read_raw_linear(path: str | os.PathLike[str], *, mode: str = "planes", data: bytes | None = None) -> RawImage:
    """Read a camera RAW (CR2, NEF, DNG, ...) as linear light; see the module docstring.

    ``data``: the file's bytes, if the caller has read them already (they are decoded and hashed as
    given; the file is not read again).

    Raises `VissimInputError` for a missing, unreadable or unsupported file.
    """
    if mode not in RAW_MODES:
        raise VissimInputError(f"RAW mode must be one of {', '.join(RAW_MODES)}; got {mode!r}")
    path = Path(path)
    if not path.is_file():
        raise VissimInputError(f"RAW file {path} {'is not a file' if path.exists() else 'does not exist'}")
    if data is None:
        data = read_file_bytes(path)  # read once: the TIFF checks, LibRaw and the checksum see the same bytes
    _check_tiff_structure(path, data)
    try:
        with rawpy.imread(io.BytesIO(data)) as raw:
            _refuse_zero_rows(raw, path)
            white = float(raw.white_level)
            # Read the CFA layout and levels before postprocess(), which rewrites them.
            pattern_indices = None if raw.raw_pattern is None else [int(i) for i in np.asarray(raw.raw_pattern).ravel()]
            desc = raw.color_desc.decode("ascii")
            black_per_colour = [float(b) for b in raw.black_level_per_channel]
            other = raw.other
            camera_to_srgb = _camera_to_srgb(raw)
            if mode == "planes":
                pixels, names, blacks, cfa = _planes(raw, path)
                wb = _camera_wb(raw, pattern_indices)
            else:
                cfa = "".join(desc[i] for i in pattern_indices) if pattern_indices else ""
                pixels, names, blacks = _demosaic(raw), ("R", "G", "B"), tuple(black_per_colour[:3])
                wb = _camera_wb(raw, [0, 1, 2])
    except VissimInputError:
        raise
    except (rawpy.LibRawError, rawpy.NotSupportedError, OSError, ValueError) as exc:
        detail = exc.args[0].decode(errors="replace") if exc.args and isinstance(exc.args[0], bytes) else str(exc)
        raise VissimInputError(f"cannot read {path} as a camera RAW file: {type(exc).__name__}: {detail}") from exc
    if not white > max(blacks):
        raise VissimInputError(f"{path}: white level {white:g} DN is not above the black level {max(blacks):g} DN")
    saturated = int(np.count_nonzero(pixels >= 1.0))
    if saturated:
        logger.warning("%s: %d pixel values at or above the white level (saturated)", path, saturated)
    image = RawImage(
        pixels=pixels, mode=mode, channel_names=names, black_levels=blacks, white_level=white, cfa_pattern=cfa,
        sensor_px_per_pixel=2 if mode == "planes" else 1, camera=_camera_name(data),
        iso=_nonzero(other.iso_speed), exposure_s=_nonzero(other.shutter_speed), path=str(path),
        camera_wb=wb, camera_to_srgb=camera_to_srgb, sha256=hashlib.sha256(data).hexdigest(),
    )
    logger.debug("read %s (%s): %s px, black %s DN, white %g DN", path, mode, pixels.shape, blacks, white)
    return image


# ---------------------------------------------------------------- letter crops


@dataclasses.dataclass(frozen=True)
class LetterCrop:
    """One letter cut from a capture; ``box_px`` (top, left, bottom, right) is in capture pixels."""

    letter: str
    logmar: float
    row: int
    position: int
    box_px: tuple[int, int, int, int]
    pixels: np.ndarray = dataclasses.field(repr=False)


def _pair(value: Any, name: str, unit: str, *, positive: bool) -> tuple[float, float]:
    try:
        values = np.broadcast_to(np.asarray(value, dtype=float), (2,))
    except (TypeError, ValueError):
        values = None
    if values is None or not np.all(np.isfinite(values)) or (positive and np.any(values <= 0)):
        raise VissimInputError(f"{name} must be {'positive ' if positive else ''}finite (rows, cols) in {unit}, "
                               f"got {value!r}")
    return float(values[0]), float(values[1])


def crop_letters(
    image: np.ndarray,
    sidecar: dict[str, Any] | Chart,
    *,
    scale: float | tuple[float, float],
    offset_px: tuple[float, float],
    margin_letter_heights: float = 0.0,
) -> tuple[LetterCrop, ...]:
    """Cut every letter box of a chart out of a capture of that chart.

    A chart pixel coordinate ``(r, c)`` (the sidecar's ``box_px``, from the top-left corner,
    pixel ``(r, c)`` covering ``[r, r+1) x [c, c+1)``) lands at capture coordinate
    ``(scale_r * r + offset_r, scale_c * c + offset_c)``.  ``scale`` is capture pixels per chart
    pixel (one number, or (rows, cols)); ``offset_px`` is where the chart's top-left corner lies
    in the capture, in capture pixels.  Each box grows by ``margin_letter_heights`` letter
    heights on every side (blur spills outside the letter).  Crops of equally tall letters have
    equal sizes: the start is rounded to the nearest pixel and the size rounded separately.
    """
    letters = (sidecar.sidecar() if isinstance(sidecar, Chart) else sidecar).get("letters")
    if not letters:
        raise VissimInputError("the chart sidecar lists no letters (expected the 'letters' of Chart.sidecar())")
    array = np.asarray(image)
    if array.ndim not in (2, 3):
        raise VissimInputError(f"image must have shape (H, W) or (H, W, C), got {array.shape}")
    scale_rc = _pair(scale, "scale", "capture px per chart px", positive=True)
    offset_rc = _pair(offset_px, "offset_px", "capture px", positive=False)
    margin = float(margin_letter_heights)
    if not math.isfinite(margin) or margin < 0:
        raise VissimInputError(f"margin_letter_heights must be >= 0 (letter heights), got {margin_letter_heights!r}")
    crops = []
    for entry in letters:
        box = entry["box_px"]
        height = box["bottom"] - box["top"]
        edges = [(box["top"] - margin * height, box["bottom"] + margin * height),
                 (box["left"] - margin * height, box["right"] + margin * height)]
        (r0, r1), (c0, c1) = ((round(s * lo + o), round(s * lo + o) + round(s * (hi - lo)))
                              for (lo, hi), s, o in zip(edges, scale_rc, offset_rc))
        if r0 < 0 or c0 < 0 or r1 > array.shape[0] or c1 > array.shape[1]:
            raise VissimInputError(
                f"letter {entry['letter']} (row {entry['row']}, position {entry['position']}) falls at capture "
                f"px rows {r0}-{r1}, cols {c0}-{c1}, outside the {size_text(array.shape)} image"
            )
        crops.append(LetterCrop(letter=entry["letter"], logmar=float(entry["logmar"]), row=int(entry["row"]),
                                position=int(entry["position"]), box_px=(r0, c0, r1, c1),
                                pixels=array[r0:r1, c0:c1].copy()))
    return tuple(crops)


# ---------------------------------------------------------------- angular resampling


def camera_arcmin_per_px(
    pixel_pitch_um: float, focal_length_mm: float, *, object_distance_m: float | None = None
) -> float:
    """Angle one photosite subtends at the lens: ``atan(pitch / image distance)``, in arcmin.

    With the lens focused at infinity the image distance is the focal length (Canon EOS
    Rebel T3 / 1100D: 5.2 um at 18 mm -> 0.993 arcmin/px).  Focused at ``object_distance_m``
    the sensor sits at the thin-lens image distance ``f d / (d - f)`` and each pixel subtends
    less: at 18 mm and 0.9144 m, 18.36 mm, 2 % finer.
    """
    pixel_pitch_um = _positive(pixel_pitch_um, "pixel pitch", "um")
    focal_length_mm = image_distance_mm = _positive(focal_length_mm, "focal length", "mm")
    if object_distance_m is not None:
        object_mm = m_to_mm(_positive(object_distance_m, "object distance", "m"))
        if object_mm <= focal_length_mm:
            raise VissimInputError(
                f"object distance must exceed the focal length {focal_length_mm:g} mm, got {object_distance_m!r} m"
            )
        image_distance_mm = focal_length_mm * object_mm / (object_mm - focal_length_mm)
    return rad_to_arcmin(math.atan(pixel_pitch_um * 1e-3 / image_distance_mm))


@dataclasses.dataclass(frozen=True)
class ResampledImage:
    """An image on an angular grid: ``pixels`` (H, W[, C]) at ``arcmin_per_px``."""

    pixels: np.ndarray = dataclasses.field(repr=False)
    arcmin_per_px: float
    source_arcmin_per_px: float

    @property
    def scale(self) -> float:
        """Output pixels per input pixel."""
        return self.source_arcmin_per_px / self.arcmin_per_px


def _area_matrix(n_in: int, scale: float) -> scipy_sparse.csr_matrix:
    """(n_out, n_in) weights: output pixel k averages input span [k/scale, (k+1)/scale) by overlap."""
    n_out = int(math.floor(n_in * scale + 1e-9))
    if n_out < 1:
        raise VissimInputError(f"resampling {n_in} px by {scale:g} leaves no whole output pixel")
    lo = np.arange(n_out) / scale
    hi = lo + 1.0 / scale
    span = int(math.ceil(1.0 / scale)) + 2
    j = np.floor(lo).astype(int)[:, None] + np.arange(span)[None, :]
    weight = np.clip(np.minimum(hi[:, None], j + 1) - np.maximum(lo[:, None], j), 0.0, None) * scale
    keep = (weight > 0) & (j < n_in)
    rows = np.broadcast_to(np.arange(n_out)[:, None], j.shape)[keep]
    return scipy_sparse.csr_matrix((weight[keep], (rows, j[keep])), shape=(n_out, n_in))


def resample_to_arcmin(
    image: np.ndarray | RawImage,
    pixel_pitch_um: float,
    focal_length_mm: float,
    target_arcmin_per_px: float,
    *,
    sensor_px_per_image_px: int | None = None,
    object_distance_m: float | None = None,
) -> ResampledImage:
    """Resample a capture from camera pixels onto a grid of ``target_arcmin_per_px``.

    The camera's scale is `camera_arcmin_per_px` times ``sensor_px_per_image_px`` (2 for
    planes-mode pixels, which span two photosites; taken from a `RawImage`, default 1
    for an array).  Resampling is exact pixel-area integration: output pixel ``k`` is the
    area-weighted mean of the input over ``[k, k+1) * target / source`` input pixels, separably
    in rows and columns, starting at the top-left corner; only whole output pixels are kept.
    It preserves the mean radiance of every region exactly, adds only the output pixel's own
    box aperture, and needs no anti-aliasing filter (unlike interpolation, e.g.
    ``skimage.transform.rescale``, whose Gaussian prefilter is an approximation).
    """
    array = image.pixels if isinstance(image, RawImage) else np.asarray(image)
    default = image.sensor_px_per_pixel if isinstance(image, RawImage) else 1
    factor = default if sensor_px_per_image_px is None else sensor_px_per_image_px
    if int(factor) != factor or factor < 1:
        raise VissimInputError(f"sensor_px_per_image_px must be a whole number >= 1 (photosites), got {factor!r}")
    if array.ndim not in (2, 3) or not np.issubdtype(array.dtype, np.floating) or not np.all(np.isfinite(array)):
        raise VissimInputError(
            f"image must be finite floats of shape (H, W) or (H, W, C), got {array.dtype} {array.shape}"
        )
    target = float(target_arcmin_per_px)
    if not (math.isfinite(target) and target > 0):
        raise VissimInputError(f"target sampling must be a positive number of arcmin/px, got {target_arcmin_per_px!r}")
    pitch_um = _positive(pixel_pitch_um, "pixel pitch", "um") * int(factor)
    source = camera_arcmin_per_px(pitch_um, focal_length_mm, object_distance_m=object_distance_m)
    scale = source / target
    row_matrix, col_matrix = _area_matrix(array.shape[0], scale), _area_matrix(array.shape[1], scale)
    channels = [array] if array.ndim == 2 else [array[..., c] for c in range(array.shape[2])]
    out = [(col_matrix @ (row_matrix @ c.astype(np.float64)).T).T for c in channels]
    pixels = (out[0] if array.ndim == 2 else np.stack(out, axis=-1)).astype(array.dtype)
    logger.debug("resampled %s px at %.4f arcmin/px to %s px at %.4f arcmin/px",
                 array.shape, source, pixels.shape, target)
    return ResampledImage(pixels=pixels, arcmin_per_px=target, source_arcmin_per_px=source)
