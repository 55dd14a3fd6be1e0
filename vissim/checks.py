"""Validation of inputs: one clear error naming the bad value and its unit; memory refused before it is asked for."""

from __future__ import annotations

import math
import os

from vissim.errors import VissimInputError

__all__ = ["finite_number", "positive_number", "arcmin_per_px", "MAX_ARCMIN_PER_PX", "pupil_diameter_mm", "size_px",
           "samples_per_pixel", "MAX_SPP", "WAVELENGTH_RANGE_NM", "wavelength_nm", "MAX_SAMPLER_SEED", "MAX_POWER_DIOPTERS", "available_memory_bytes",
           "format_bytes", "check_allocation"]


def finite_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float; NaN (and infinity unless ``allow_inf``) refused."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be a number in {unit}, got {value!r}") from None
    if math.isnan(number) or (math.isinf(number) and not allow_inf):
        raise VissimInputError(f"{name} must be finite (in {unit}), got {value!r}")
    return number


def positive_number(value, name: str, unit: str, *, allow_inf: bool = False) -> float:
    """A finite (or, with ``allow_inf``, infinite) number > 0."""
    number = finite_number(value, name, unit, allow_inf=allow_inf)
    if number <= 0.0:
        raise VissimInputError(f"{name} must be a positive number of {unit}, got {value!r}")
    return number


#: Wavelengths a PSF may be computed at (nm): the near UV to the near IR.
WAVELENGTH_RANGE_NM = (200.0, 2000.0)


def wavelength_nm(value, name: str = "wavelength") -> float:
    """A wavelength within `WAVELENGTH_RANGE_NM`."""
    number = finite_number(value, name, "nm")
    low, high = WAVELENGTH_RANGE_NM
    if not low <= number <= high:
        raise VissimInputError(f"{name} must be within {low:g}-{high:g} nm, got {value!r} nm")
    return number


def available_memory_bytes() -> int:
    """Memory this process may still allocate, bytes: Linux's MemAvailable, else physical memory."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not Linux
        return 1 << 62


def format_bytes(n_bytes: float) -> str:
    """``n_bytes`` in binary units: '1.66 TiB'."""
    value = float(n_bytes)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if value < 1024.0 or unit == "EiB":
            return f"{value:.3g} {unit}"
        value /= 1024.0
    raise AssertionError("unreachable")  # pragma: no cover


def check_allocation(n_bytes: float, what: str) -> None:
    """Refuse, before allocating, a request whose estimated peak memory the machine cannot hold.

    ``what`` names the request and its size ('a 100000 x 100000 px render'); the error says
    how much memory it would need and how much is available.
    """
    try:
        needed = float(n_bytes)
    except OverflowError:  # an integer estimate beyond any float
        needed = math.inf
    available = available_memory_bytes()
    if not math.isfinite(needed) or needed > available:
        shown = f"{format_bytes(needed)} of memory" if math.isfinite(needed) else "more memory than any machine has"
        raise VissimInputError(f"{what} would need {shown}; this machine has {format_bytes(available)} available")


#: Angular samplings vissim takes, arcmin per pixel (the thesis's is 1): finer ones need more
#: memory than any machine has (checked by `check_allocation`), coarser ones are no image.
MIN_ARCMIN_PER_PX, MAX_ARCMIN_PER_PX = 1e-6, 60.0


def arcmin_per_px(value, name: str = "angular sampling") -> float:
    """An angular pixel size within [`MIN_ARCMIN_PER_PX`, `MAX_ARCMIN_PER_PX`] (1 degree)."""
    step = positive_number(value, name, "arcmin per pixel")
    if not MIN_ARCMIN_PER_PX <= step <= MAX_ARCMIN_PER_PX:
        raise VissimInputError(
            f"{name} must be within {MIN_ARCMIN_PER_PX:g}-{MAX_ARCMIN_PER_PX:g} arcmin per pixel, got {step:g}")
    return step


#: Pupil diameters vissim takes, mm: an eye's are 1-9, the thesis camera's 3.6.
MIN_PUPIL_MM, MAX_PUPIL_MM = 0.01, 1000.0


def pupil_diameter_mm(value, name: str = "pupil diameter") -> float:
    """A pupil diameter within [`MIN_PUPIL_MM`, `MAX_PUPIL_MM`] mm."""
    pupil = positive_number(value, name, "mm")
    if not MIN_PUPIL_MM <= pupil <= MAX_PUPIL_MM:
        raise VissimInputError(f"{name} must be within {MIN_PUPIL_MM:g}-{MAX_PUPIL_MM:g} mm, got {pupil:g} mm")
    return pupil


def size_px(value, name: str = "size_px") -> tuple[int, int]:
    """An image size (rows, cols) in whole pixels >= 1."""
    try:
        size = tuple(int(v) for v in value)
    except (TypeError, ValueError):
        size = ()
    if len(size) != 2 or min(size) < 1 or tuple(value) != size:
        raise VissimInputError(f"{name} must be (rows, cols) in whole pixels >= 1, got {value!r}")
    return size  # type: ignore[return-value]


#: Most samples per pixel a render takes (Mitsuba counts them in 32 bits; 65536 spp of the
#: thesis bench takes hours on 2 cores).
MAX_SPP = 1 << 16


#: Sampler seeds are 32-bit.
MAX_SAMPLER_SEED = 2**32 - 1


def samples_per_pixel(value, name: str = "spp") -> int:
    """A whole number of samples per pixel in 1-`MAX_SPP`."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value) or not 1 <= value <= MAX_SPP:
        raise VissimInputError(f"{name} must be a whole number of samples per pixel in 1-{MAX_SPP}, got {value!r}")
    return int(value)


#: Largest lens power vissim reads from a user, dioptres (a 1 mm focal length: far beyond any
#: eye or trial lens). Results computed from inputs may exceed it.
MAX_POWER_DIOPTERS = 1000.0
