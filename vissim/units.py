"""Unit conversions; each conversion lives in exactly one function here."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "ARCMIN_PER_RAD",
    "arcmin_to_rad",
    "rad_to_arcmin",
    "nm_to_mm",
    "nm_to_um",
    "cyc_per_rad_to_cyc_per_deg",
    "mrad_to_arcmin",
]

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi


def arcmin_to_rad(arcmin):
    return np.asarray(arcmin, dtype=float) / ARCMIN_PER_RAD if np.ndim(arcmin) else float(arcmin) / ARCMIN_PER_RAD


def rad_to_arcmin(rad):
    return np.asarray(rad, dtype=float) * ARCMIN_PER_RAD if np.ndim(rad) else float(rad) * ARCMIN_PER_RAD


def mrad_to_arcmin(mrad):
    """Wavefront slopes in µm/mm are milliradians; this gives arcmin."""
    return rad_to_arcmin(np.asarray(mrad, dtype=float) * 1e-3 if np.ndim(mrad) else float(mrad) * 1e-3)


def nm_to_mm(nm: float) -> float:
    return float(nm) * 1e-6


def nm_to_um(nm: float) -> float:
    return float(nm) * 1e-3


def cyc_per_rad_to_cyc_per_deg(cyc_per_rad):
    return np.asarray(cyc_per_rad, dtype=float) * (math.pi / 180.0)
