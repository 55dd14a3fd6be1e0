"""A virtual DSLR: mosaic a linear image, add sensor noise, quantise, and write a DNG.

The chain mirrors a real capture, so that the RAW side of the validation
(`vissim.imaging.raw.read_raw_linear`) can be tested on files whose contents are
known exactly::

    linear (H, W[, 3]) --mosaic_bayer--> CFA mosaic in [0, 1] (1 = full well = white level)
        --add_sensor_noise--> noisy mosaic --quantise--> uint16 data numbers --write_dng--> .dng

`write_dng` writes a minimal DNG 1.4 with `tifffile`: one uncompressed 16-bit CFA
IFD.  What LibRaw (rawpy) actually needs to read it as a Bayer RAW with the right levels is
``PhotometricInterpretation = 32803`` (CFA), ``CFAPattern``, ``BlackLevel`` and ``WhiteLevel``
(without ``CFAPattern`` LibRaw sees a 4-colour CMYG sensor; without ``WhiteLevel`` it assumes
65535).  The rest is what the DNG specification requires of a colour CFA file --
``CFARepeatPatternDim``, ``DNGVersion``, ``UniqueCameraModel``, ``ColorMatrix1`` (identity:
the virtual camera's channels *are* its colour space) with ``CalibrationIlluminant1`` (D65) --
plus ``AsShotNeutral`` (1, 1, 1: no white balance), ``BlackLevelRepeatDim`` when the black level
differs per CFA position, and ``ExposureTime`` when given.  A written DNG read back with
``read_raw_linear(mode="planes")`` reproduces ``(dn - black) / (white - black)`` bit for bit
(``tests/validation/test_validation_virtual_capture.py``).
"""

from __future__ import annotations

import fractions
import logging
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import tifffile

from vissim.checks import size_text
from vissim.atomic import atomic_output
from vissim.errors import VissimInputError
from vissim.provenance import to_json

logger = logging.getLogger(__name__)

__all__ = ["BAYER_PATTERNS", "DEFAULT_CAMERA_MODEL", "add_sensor_noise", "mosaic_bayer", "quantise", "write_dng"]

BAYER_PATTERNS = ("RGGB", "BGGR", "GRBG", "GBRG")
DEFAULT_CAMERA_MODEL = "vissim virtual DSLR"
_CFA_COLOUR_CODE = {"R": 0, "G": 1, "B": 2}  # TIFF/EP CFAPattern codes
_PHOTOMETRIC_CFA = 32803
_ILLUMINANT_D65 = 21
_LIBRAW_MIN_SIDE_PX = 22  # dcraw/LibRaw identify(): "height < 22 || width < 22" -> not a RAW


def _pattern(pattern: str) -> str:
    text = str(pattern).upper()
    if text not in BAYER_PATTERNS:
        raise VissimInputError(f"Bayer pattern must be one of {', '.join(BAYER_PATTERNS)}; got {pattern!r}")
    return text


def mosaic_bayer(linear_rgb_or_mono: Any, pattern: str = "RGGB") -> np.ndarray:
    """Sample a linear image through a Bayer filter: ``(H, W)`` float32, one colour per pixel.

    ``pattern`` names the 2 x 2 cell in raster order (``"RGGB"``: R at [0, 0], G at [0, 1] and
    [1, 0], B at [1, 1]).  An ``(H, W, 3)`` image gives each pixel its filter's channel; a mono
    ``(H, W)`` image (a grey scene, equal in every channel) passes through unchanged.
    """
    cell = _pattern(pattern)
    array = np.asarray(linear_rgb_or_mono)
    if not np.issubdtype(array.dtype, np.floating):
        raise VissimInputError(f"the image must be linear light as floats, got dtype {array.dtype}")
    if not (array.ndim == 2 or (array.ndim == 3 and array.shape[2] == 3)) or min(array.shape[:2]) < 2:
        raise VissimInputError(f"image must have shape (H, W) or (H, W, 3) with H, W >= 2, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise VissimInputError("image has NaN or infinite pixels")
    if array.ndim == 2:
        return array.astype(np.float32, copy=True)
    mosaic = np.empty(array.shape[:2], np.float32)
    for k, colour in enumerate(cell):
        dr, dc = divmod(k, 2)
        mosaic[dr::2, dc::2] = array[dr::2, dc::2, "RGB".index(colour)]
    return mosaic


def add_sensor_noise(
    mosaic: Any,
    *,
    full_well_electrons: float,
    read_noise_electrons: float,
    rng: np.random.Generator | int,
) -> np.ndarray:
    """Photon shot noise and read noise on a mosaic whose value 1 is the full well.

    Electrons = ``mosaic * full_well_electrons``; each pixel gets a Poisson draw of that mean
    plus Gaussian read noise of ``read_noise_electrons`` (rms), and is divided by the full well
    again.  Results can be negative (read noise below black) or above 1; `quantise` clips
    as a sensor would.  ``rng`` is a `numpy.random.Generator` or a seed: always seeded.
    """
    array = np.asarray(mosaic, dtype=np.float64)
    if array.ndim != 2 or not np.all(np.isfinite(array)) or np.any(array < 0):
        raise VissimInputError("mosaic must be a 2-D array of finite linear values >= 0 (fraction of full well)")
    full_well = float(full_well_electrons)
    read_noise = float(read_noise_electrons)
    if not (math.isfinite(full_well) and full_well > 0):
        raise VissimInputError(f"full well must be a positive number of electrons, got {full_well_electrons!r}")
    if not (math.isfinite(read_noise) and read_noise >= 0):
        raise VissimInputError(f"read noise must be >= 0 electrons rms, got {read_noise_electrons!r}")
    if not isinstance(rng, np.random.Generator):
        if isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
            raise VissimInputError(f"rng must be a numpy Generator or an integer seed, got {rng!r}")
        rng = np.random.default_rng(int(rng))
    electrons = rng.poisson(array * full_well).astype(np.float64)
    if read_noise > 0:
        electrons += rng.normal(0.0, read_noise, array.shape)
    return (electrons / full_well).astype(np.float32)


def _level(value: Any, name: str) -> int:
    try:
        whole = not isinstance(value, bool) and int(value) == value and 0 <= int(value) <= 65535
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole:
        raise VissimInputError(f"{name} must be a whole number of data numbers in 0-65535 (DN), got {value!r}")
    return int(value)


def quantise(mosaic: Any, black_level: int = 2048, white_level: int = 15000, bits: int = 16) -> np.ndarray:
    """Linear mosaic (0 = black, 1 = white) to ``uint16`` data numbers, as the camera's ADC would.

    ``dn = round(black_level + value * (white_level - black_level))``, clipped to
    ``[0, white_level]``: a photosite saturates at the white level, and read noise can take it
    below black but not below 0.  ``bits`` is the ADC's depth; ``white_level`` must fit in it.
    The defaults are a 14-bit-like camera with a 2048 DN pedestal.
    """
    if isinstance(bits, bool) or int(bits) != bits or not 1 <= int(bits) <= 16:
        raise VissimInputError(f"bits must be a whole number in 1-16 (bits per sample), got {bits!r}")
    black, white = _level(black_level, "black level"), _level(white_level, "white level")
    if not black < white <= 2 ** int(bits) - 1:
        raise VissimInputError(
            f"need 0 <= black level < white level <= {2 ** int(bits) - 1} DN for {bits} bits, got black {black} DN, "
            f"white {white} DN"
        )
    array = np.asarray(mosaic, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        raise VissimInputError("mosaic has NaN or infinite values")
    dn = np.rint(black + array * (white - black))
    return np.clip(dn, 0, white).astype(np.uint16)


def _black_tags(black_level: int | Sequence[int]) -> list[tuple]:
    if np.ndim(black_level) == 0:
        return [(50714, "H", 1, (_level(black_level, "black level"),), True)]
    levels = [_level(b, "black level") for b in black_level]
    if len(levels) != 4:
        raise VissimInputError(f"give one black level or four (per 2 x 2 CFA position, raster order) DN, got {levels}")
    return [(50713, "H", 2, (2, 2), True), (50714, "H", 4, tuple(levels), True)]


def write_dng(
    path: str | os.PathLike[str],
    cfa_uint16: np.ndarray,
    *,
    black_level: int | Sequence[int],
    white_level: int,
    pattern: str,
    overwrite: bool = False,
    camera_model: str = DEFAULT_CAMERA_MODEL,
    exposure_s: float | None = None,
    provenance: dict[str, Any] | None = None,
) -> Path:
    """Write a ``uint16`` CFA mosaic as a minimal DNG 1.4 (see the module docstring); return the path.

    ``black_level`` is one value or four (per CFA position, raster order), in DN;
    ``white_level`` in DN; ``pattern`` the 2 x 2 cell (``"RGGB"``, ...).  Both sides must be at
    least 22 px, or LibRaw will not open the file.  ``provenance`` goes to
    the ImageDescription tag as JSON.  Written atomically; refuses to replace a file unless
    ``overwrite=True``.
    """
    cell = _pattern(pattern)
    cfa = np.asarray(cfa_uint16)
    if cfa.dtype != np.uint16 or cfa.ndim != 2:
        raise VissimInputError(f"the CFA mosaic must be a 2-D uint16 array, got {cfa.dtype} {cfa.shape}")
    if min(cfa.shape) < _LIBRAW_MIN_SIDE_PX:
        raise VissimInputError(
            f"the CFA mosaic is {size_text(cfa.shape)}; LibRaw (rawpy) refuses RAW images with a side "
            f"under {_LIBRAW_MIN_SIDE_PX} px"
        )
    white = _level(white_level, "white level")
    black_tags = _black_tags(black_level)
    if max(black_tags[-1][3]) >= white:
        raise VissimInputError(f"white level {white} DN must exceed the black level {black_tags[-1][3]} DN")
    identity = (1, 1, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1, 1, 1)
    tags = [
        (33421, "H", 2, (2, 2), True),  # CFARepeatPatternDim
        (33422, "B", 4, tuple(_CFA_COLOUR_CODE[c] for c in cell), True),  # CFAPattern
        (50706, "B", 4, (1, 4, 0, 0), True),  # DNGVersion 1.4
        (50707, "B", 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, "s", 0, str(camera_model), True),  # UniqueCameraModel
        *black_tags,  # [BlackLevelRepeatDim], BlackLevel
        (50717, "H", 1, (white,), True),  # WhiteLevel
        (50721, "2i", 9, identity, True),  # ColorMatrix1 (XYZ -> camera), identity
        (50728, "2I", 3, (1, 1, 1, 1, 1, 1), True),  # AsShotNeutral: no white balance
        (50778, "H", 1, (_ILLUMINANT_D65,), True),  # CalibrationIlluminant1: D65
        (274, "H", 1, (1,), True),  # Orientation: top-left, row 0 at the top
    ]
    if exposure_s is not None:
        seconds = float(exposure_s)
        if not (math.isfinite(seconds) and seconds > 0):
            raise VissimInputError(f"exposure time must be a positive number of seconds, got {exposure_s!r}")
        ratio = fractions.Fraction(seconds).limit_denominator(1_000_000)
        tags.append((33434, "2I", 1, (ratio.numerator, ratio.denominator), True))  # ExposureTime
    description = to_json(provenance) if provenance is not None else None
    path = Path(path)
    with atomic_output(path, overwrite=overwrite) as tmp:
        tifffile.imwrite(tmp, cfa, photometric=_PHOTOMETRIC_CFA, planarconfig=1, subfiletype=0,
                         extratags=tags, metadata=None, description=description, software="vissim")
    logger.debug("wrote DNG %s: %s px %s, black %s DN, white %d DN", path, cfa.shape, cell, black_level, white)
    return path
