"""Real (or virtual) RAW captures as ground truth: the manifest and the capture -> tile path.

A manifest (TOML) lists captures so real photographs can be dropped in::

    [[capture]]
    id = "t3-k-plus2"
    file = "raw/IMG_0412.CR2"          # relative to the manifest
    sha256 = "..."                     # checked before use
    pixel_pitch_um = 5.2               # Canon EOS Rebel T3 / 1100D
    focal_length_mm = 18.0
    f_number = 5.0
    chart_distance_m = 0.9144
    lenses = [2.0]                      # as in a campaign
    letter = "K"
    logmar = 1.0
    polarity = "black-on-white"
    letter_center_px = [1732.0, 2590.0] # (row, col) of the letter's centre on the sensor
    no_lens_capture = "t3-k-plain"      # the same chart without lenses (simulation input)
    repeat_capture = "t3-k-plus2-b"     # optional: a second exposure, for the noise floor

A campaign item with ``capture = "t3-k-plus2"`` takes its ground truth from the capture.
Absent files are skipped with a clear message, never silently.

Capture -> tile: the RAW is read linearly (`read_capture`, which checks the file's
sha256 and uses `vissim.imaging.raw.read_raw_linear`, no demosaicing), the
photosites are divided by their channel's gain (the median of the paper in a ring around the
letter, 0.75 to 1.5 tile half-widths measured on the sky, so a neutral chart gives one grey
level per photosite, at full sensor resolution and without interpolation), resampled by exact
area integration onto the campaign's arcmin/px (camera scale from pitch, focal length and focus
distance), cropped to the tile around the letter, and scaled so that the paper has the chart's
paper reflectance.  `capture_provenance` records what the file says: camera, black and
white levels, CFA pattern, as-shot white balance and the file's sha256.
"""

from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vissim.charts import PAPER_REFLECTANCE, POLARITIES
from vissim.errors import VissimInputError
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_F_NUMBER, THESIS_FOCAL_LENGTH_MM
from vissim.units import mm_to_m
from vissim.validation.engine.fields import LensSpec
from vissim.validation.engine.fields import field_error, lenses, number, read_toml_file, tables, text
from vissim.imaging.raw import (RawImage, camera_arcmin_per_px, file_sha256, read_file_bytes, read_raw_linear,
                               resample_to_arcmin)

__all__ = ["Capture", "neutral_mosaic", "load_manifest", "open_capture", "read_capture", "capture_tile", "capture_provenance",
           "file_sha256"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Capture:
    id: str
    file: Path
    sha256: str | None
    pixel_pitch_um: float
    focal_length_mm: float
    f_number: float
    chart_distance_m: float
    lenses: tuple[LensSpec, ...]
    letter: str
    logmar: float
    polarity: str
    letter_center_px: tuple[float, float]
    no_lens_capture: str | None = None
    repeat_capture: str | None = None


def _optional_text(entry: dict, key: str, source: str, where: str) -> str | None:
    return None if entry.get(key) is None else text(entry[key], source, f"{where}.{key}")


def _capture(entry: dict, path: Path, i: int) -> Capture:
    source, where = str(path), f"capture[{i}]"
    for key in ("id", "file", "letter", "letter_center_px"):
        if key not in entry:
            raise field_error(source, where, f"lacks the field {key!r}")
    polarity = entry.get("polarity", "black-on-white")
    if polarity not in POLARITIES:
        raise field_error(source, f"{where}.polarity", f"must be {' or '.join(POLARITIES)}, got {polarity!r}")
    center = entry["letter_center_px"]
    if not (isinstance(center, list) and len(center) == 2):
        raise field_error(source, f"{where}.letter_center_px", f"must be [row, col] in sensor pixels, got {center!r}")

    def positive(key: str, default: float, unit: str) -> float:
        return number(entry.get(key, default), source, f"{where}.{key}", unit, positive=True)

    return Capture(
        id=text(entry["id"], source, f"{where}.id"),
        file=(path.parent / text(entry["file"], source, f"{where}.file")).resolve(),
        sha256=_optional_text(entry, "sha256", source, where),
        pixel_pitch_um=positive("pixel_pitch_um", 5.2, "um"),
        focal_length_mm=positive("focal_length_mm", THESIS_FOCAL_LENGTH_MM, "mm"),
        f_number=positive("f_number", THESIS_F_NUMBER, "(f-number)"),
        chart_distance_m=positive("chart_distance_m", mm_to_m(THESIS_CHART_DISTANCE_MM), "m"),
        lenses=lenses(entry.get("lenses", []), source, f"{where}.lenses"),
        letter=text(entry["letter"], source, f"{where}.letter").upper(),
        logmar=number(entry.get("logmar", 1.0), source, f"{where}.logmar", "LogMAR"),
        polarity=polarity,
        letter_center_px=tuple(number(v, source, f"{where}.letter_center_px[{k}]", "sensor px")
                               for k, v in enumerate(center)),
        no_lens_capture=_optional_text(entry, "no_lens_capture", source, where),
        repeat_capture=_optional_text(entry, "repeat_capture", source, where),
    )


def load_manifest(path: str | Path) -> dict[str, Capture]:
    """Read a capture manifest; every field is checked, files are not (see `open_capture`)."""
    path = Path(path)
    raw = read_toml_file(path, "capture manifest")
    captures = {}
    for i, entry in enumerate(tables(raw, "capture", str(path))):
        capture = _capture(entry, path, i)
        if capture.id in captures:
            raise field_error(str(path), f"capture[{i}]", f"duplicate capture id {capture.id!r}")
        captures[capture.id] = capture
    return captures


def open_capture(capture: Capture) -> RawImage | str:
    """The capture's RAW as linear CFA planes, its file read once and checked against the manifest's sha256
    before it is decoded; or why it cannot be used (absent file, another sha256)."""
    if not capture.file.exists():
        return f"capture {capture.id!r}: {capture.file} is absent"
    data = read_file_bytes(capture.file)
    if capture.sha256 and hashlib.sha256(data).hexdigest() != capture.sha256.lower():
        return f"capture {capture.id!r}: {capture.file} does not match its sha256 in the manifest"
    return read_raw_linear(capture.file, mode="planes", data=data)


def neutral_mosaic(planes: np.ndarray, paper_mask: np.ndarray, cell_px: int) -> np.ndarray:
    """Full-resolution grey image from the CFA planes, each divided by its paper level.

    Plane ``c`` holds photosite ``divmod(c, cell_px)`` (row, col) of every ``cell_px`` x ``cell_px``
    CFA cell (raster order, `vissim.imaging.raw`).
    """
    rows, cols, channels = planes.shape
    if channels != cell_px * cell_px:
        raise VissimInputError(f"a capture tile needs the RAW's CFA planes (mode='planes'), got {channels} channels")
    gains = [float(np.median(planes[..., c][paper_mask])) for c in range(channels)]
    if min(gains) <= 0:
        raise VissimInputError("the capture's paper is not above black in every colour channel; check exposure")
    mosaic = np.empty((cell_px * rows, cell_px * cols), np.float64)
    for c in range(channels):
        dr, dc = divmod(c, cell_px)
        mosaic[dr::cell_px, dc::cell_px] = planes[..., c] / gains[c]
    return mosaic


def read_capture(capture: Capture) -> RawImage:
    """The capture's RAW (`open_capture`), or one error saying why it cannot be used."""
    raw = open_capture(capture)
    if isinstance(raw, str):
        raise VissimInputError(raw)
    return raw


def capture_provenance(capture: Capture, raw: RawImage) -> dict:
    """What a capture's file says (camera, levels, CFA pattern, white balance), with its measured sha256."""
    record = raw.as_json()
    return {"capture": capture.id, "file": str(capture.file), "sha256": record.pop("sha256"), "raw": record}


def capture_tile(capture: Capture, arcmin_per_px: float, tile_px: tuple[int, int], *,
                 raw: RawImage | None = None) -> np.ndarray:
    """The capture's letter as a linear tile on the campaign's grid (paper = 0.9); ``raw`` if already read."""
    raw = read_capture(capture) if raw is None else raw
    row, col = capture.letter_center_px
    # paper: a ring around the letter between 0.75 and 1.5 tile half-widths, converted to sensor
    # pixels by the camera's scale (plane pixel (i, j) is a CFA cell of n x n sensor pixels from
    # (n i, n j), n = raw.sensor_px_per_pixel, centred at (n i + (n - 1) / 2, n j + (n - 1) / 2))
    cell = raw.sensor_px_per_pixel
    pr, pc = np.mgrid[: raw.pixels.shape[0], : raw.pixels.shape[1]]
    distance = np.hypot(cell * pr + (cell - 1) / 2 - row, cell * pc + (cell - 1) / 2 - col)
    sensor_arcmin_per_px = camera_arcmin_per_px(capture.pixel_pitch_um, capture.focal_length_mm,
                                                object_distance_m=capture.chart_distance_m)
    reach = max(tile_px) / 2 * arcmin_per_px / sensor_arcmin_per_px
    ring = (distance > 0.75 * reach) & (distance < 1.5 * reach)
    if capture.polarity == "white-on-black":
        ring = np.zeros_like(ring)  # background is ink: take the paper from the brightest letter pixels
        ring[np.unravel_index(np.argsort(raw.pixels.mean(axis=-1), axis=None)[-64:], ring.shape)] = True
    mosaic = neutral_mosaic(raw.pixels, ring, cell)
    resampled = resample_to_arcmin(mosaic, capture.pixel_pitch_um, capture.focal_length_mm, arcmin_per_px,
                                   sensor_px_per_image_px=1, object_distance_m=capture.chart_distance_m)
    scale = resampled.scale
    centre = (row * scale, col * scale)
    top = int(round(centre[0] - tile_px[0] / 2))
    left = int(round(centre[1] - tile_px[1] / 2))
    tile = resampled.pixels[top : top + tile_px[0], left : left + tile_px[1]]
    if tile.shape != tuple(tile_px) or top < 0 or left < 0:
        raise VissimInputError(f"capture {capture.id!r}: the letter tile runs off the image; check letter_center_px")
    return (tile * PAPER_REFLECTANCE).astype(np.float32)
