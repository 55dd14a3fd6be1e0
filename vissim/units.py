"""Unit and frame conversions; each conversion lives in exactly one function here."""

from __future__ import annotations

import math

from vissim.lazy_import import lazy_module

np = lazy_module("numpy")  # conversions of arrays import NumPy; the command line's help reads numbers only

__all__ = ["xy_matrix_to_image_rowcol", "ARCMIN_PER_RAD", "ARCMIN_PER_DEG", "deg_to_mrad", "arcmin_to_rad", "rad_to_arcmin", "nm_to_mm", "nm_to_um",
           "cyc_per_rad_to_cyc_per_deg", "CYC_PER_DEG_PER_CYC_PER_RAD", "mrad_to_arcmin", "MM_PER_M", "mm_to_m", "m_to_mm", "diopters_to_mm",
           "diopters_to_per_mm", "REC709_LUMINANCE", "osa_xy_to_image_colrow", "image_colrow_to_osa_xy"]

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
ARCMIN_PER_DEG = 60.0


def arcmin_to_rad(arcmin):
    return np.asarray(arcmin, dtype=float) / ARCMIN_PER_RAD if np.ndim(arcmin) else float(arcmin) / ARCMIN_PER_RAD


def rad_to_arcmin(rad):
    return np.asarray(rad, dtype=float) * ARCMIN_PER_RAD if np.ndim(rad) else float(rad) * ARCMIN_PER_RAD


def mrad_to_arcmin(mrad):
    """Wavefront slopes in µm/mm are milliradians; this gives arcmin."""
    return rad_to_arcmin(np.asarray(mrad, dtype=float) * 1e-3 if np.ndim(mrad) else float(mrad) * 1e-3)


def deg_to_mrad(deg):
    """Degrees of visual angle to milliradians (a wavefront slope in µm/mm)."""
    return np.radians(np.asarray(deg, dtype=float)) * 1e3 if np.ndim(deg) else math.radians(float(deg)) * 1e3


def nm_to_mm(nm: float) -> float:
    return float(nm) * 1e-6


def nm_to_um(nm: float) -> float:
    return float(nm) * 1e-3


#: Cycles per degree in one cycle per radian (a degree is pi/180 rad).
CYC_PER_DEG_PER_CYC_PER_RAD = math.pi / 180.0


def cyc_per_rad_to_cyc_per_deg(cyc_per_rad):
    return np.asarray(cyc_per_rad, dtype=float) * CYC_PER_DEG_PER_CYC_PER_RAD


MM_PER_M = 1000.0
#: Rec. 709 / sRGB luminance weights of linear R, G, B.
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)


def _number(x):
    """Floats and numpy values as they are; other scalars as float, sequences as float arrays."""
    if isinstance(x, (float, int)) and not isinstance(x, bool):
        return float(x) if isinstance(x, int) else x
    if isinstance(x, (np.ndarray, np.generic)):
        return x
    return np.asarray(x, dtype=float) if np.ndim(x) else float(x)


def mm_to_m(mm):
    return _number(mm) / MM_PER_M


def m_to_mm(m):
    return _number(m) * MM_PER_M


def diopters_to_mm(diopters):
    """Focal length, or distance of a vergence, in mm: 1000 / D."""
    return MM_PER_M / _number(diopters)


def diopters_to_per_mm(diopters):
    """Dioptres (1/m) as curvature or power per mm."""
    return _number(diopters) / MM_PER_M


def osa_xy_to_image_colrow(x, y):
    """Image offsets (col, row) of a TABO/OSA pupil point or direction (x, y): (-x, -y).

    The observer faces the examiner's way round (x mirrored) and rows grow down
    (``docs/conventions.md``, "Pupil coordinates").
    """
    return -x, -y


def image_colrow_to_osa_xy(col, row):
    """The TABO/OSA (x, y) of image offsets (col, row): the map is its own inverse."""
    return osa_xy_to_image_colrow(col, row)


def xy_matrix_to_image_rowcol(matrix_xy) -> np.ndarray:
    """A 2 x 2 matrix acting on TABO/OSA (x, y) as the same map on image (row, col) offsets.

    With (col, row) = S (x, y), S the diagonal signs of `osa_xy_to_image_colrow`, the
    matrix becomes S m S^-1 on (col, row), then its axes swap to (row, col).
    """
    m = np.asarray(matrix_xy, dtype=float)
    signs = np.array(osa_xy_to_image_colrow(1.0, 1.0))
    colrow = m * np.outer(signs, signs)
    return np.array([[colrow[1, 1], colrow[1, 0]], [colrow[0, 1], colrow[0, 0]]])
