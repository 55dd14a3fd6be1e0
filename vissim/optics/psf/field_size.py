"""How large a field a PSF needs: blur radius, and the energy that would fall outside a field.

`energy_outside_field` estimates the fraction of a PSF's energy outside a square field
before the PSF is computed: the PSF is modelled as the ray-optics PSF convolved with the
aberration-free pupil's Airy pattern.  Rays through a stratified pupil sample land at the
visual direction given by the wavefront slope; each ray's Airy pattern is integrated over the
square along a fan of directions, with the Airy pattern's exact radial tail
``1 - EE(r) = J0^2(pi r) + J1^2(pi r)`` (r in lambda/D; Born & Wolf §8.5.2), which falls as
2 / (pi^2 r): the Airy pattern leaves 1 % outside a square of half-width 18 lambda/D.

A defocused pupil's rim diffracts more light past the geometric edge than the Airy pattern
does: its Fresnel zone spreads the edge over about sqrt(2 N_F) lambda/D, N_F = the blur's
Fresnel number (waves of equivalent defocus).  The conservative estimate widens each ray's
Airy pattern by sqrt(1 + EDGE_BROADENING N_F); measured against computed PSFs from 0 to 16
waves of defocus, astigmatism and coma (``tests/test_psf_field.py``) it is 0.9-2.2 times
the true fraction outside.  `compute_psf` refuses on the energy it
measures; the conservative estimate sizes fields (`suggested_size_px`) and names the
size that would hold the PSF.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.rx.chromatic import chromatic_difference_of_refraction_diopters
from vissim.optics.pupil.rays import landing_arcmin, pupil_cell_centres
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront, wavelengths_for
from vissim.optics.pupil.wavefront import Wavefront, same_wavelength
from vissim.units import nm_to_mm, rad_to_arcmin

scipy_special = lazy_module("scipy.special")

__all__ = [
    "MAX_ENERGY_OUTSIDE",
    "leaves_too_much_outside",
    "load_size_tables",
    "energy_outside_field",
    "geometric_blur_radius_arcmin",
    "size_holding_px",
    "suggested_size_px",
]

#: Largest fraction of a PSF's energy that may fall outside its field: a blur kernel leaving more
#: is refused, a PSF image leaving more is computed with a warning.
MAX_ENERGY_OUTSIDE = 0.01


def leaves_too_much_outside(energy_in_field: float) -> bool:
    """True when a field holding ``energy_in_field`` of a PSF leaves more than `MAX_ENERGY_OUTSIDE` outside."""
    return 1.0 - energy_in_field > MAX_ENERGY_OUTSIDE
#: Rays per pupil side for the estimate (about 0.8 x this squared inside the pupil).
ESTIMATE_RAYS_PER_SIDE = 32
#: Directions over which each ray's diffraction pattern is integrated.
ESTIMATE_DIRECTIONS = 32
_AIRY_TABLE_LAMBDA_OVER_D = 64.0
#: Sizes searched for a field that holds the PSF.
SIZE_SEARCH_LIMIT_PX = 2**20
#: Widening of the diffraction pattern with the blur's Fresnel number (conservative estimate).
EDGE_BROADENING = 0.5


def _pupil_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A polar sample of the unit disc for slope maxima (deterministic)."""
    rho = np.sqrt(np.linspace(0.0, 1.0, n))
    theta = np.linspace(0.0, 2 * np.pi, 4 * n, endpoint=False)
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    return rr * np.cos(tt), rr * np.sin(tt)


def geometric_blur_radius_arcmin(wavefront: Wavefront, pupil_diameter_mm: float) -> float:
    """Largest ray deviation |grad W| over the pupil, in arcmin (tilt included)."""
    if not hasattr(wavefront, "coefficients_um"):  # an OPD map: its own slopes
        ux, uy = _pupil_points(48)
        sx, sy = wavefront.slopes_mrad(pupil_diameter_mm / 2.0 * ux, pupil_diameter_mm / 2.0 * uy)
        return float(rad_to_arcmin(1e-3 * np.max(np.hypot(sx, sy))))
    if not wavefront.coefficients_um:
        return 0.0
    return _blur_radius_cached(tuple(wavefront.coefficients_um.items()), wavefront.pupil_diameter_mm, float(pupil_diameter_mm))


@functools.lru_cache(maxsize=256)
def _blur_radius_cached(items: tuple, measured_mm: float, diameter_mm: float) -> float:
    ux, uy = _pupil_points(48)
    radius = diameter_mm / 2.0
    sx, sy = Wavefront(dict(items), measured_mm).slopes_mrad(radius * ux, radius * uy)
    return float(rad_to_arcmin(1e-3 * np.max(np.hypot(sx, sy))))


def front_at_wavelength(wavefront, wavelength_nm: float, lca_reference_nm: float | None) -> Wavefront:
    """The front a PSF at ``wavelength_nm`` is of, decided here once:

    * a `SpectralWavefront`'s own front at that wavelength (it carries its own dispersion:
      ``lca_reference_nm`` is refused);
    * a `Wavefront` that knows its wavelength (traced or measured in that light): itself at that
      wavelength; at another only when told how to convert it, ``lca_reference_nm`` equal to its own
      wavelength (Thibos's chromatic defocus from there); anything else is refused, never silently
      used in the wrong light;
    * any other front (a prescription's): itself, with Thibos's chromatic defocus relative to
      ``lca_reference_nm`` added when that is given.
    """
    if isinstance(wavefront, SpectralWavefront):
        if lca_reference_nm is not None:
            raise VissimInputError(f"an LCA reference wavelength ({lca_reference_nm:g} nm) cannot be added to a "
                                   "spectral wavefront: each wavelength's front has its own dispersion")
        return wavefront.at(wavelength_nm)
    own = getattr(wavefront, "wavelength_nm", None)
    if own is not None:
        _check_conversion(own, wavelength_nm, lca_reference_nm)
    if lca_reference_nm is None:
        return wavefront
    converted = wavefront.with_defocus_diopters(chromatic_difference_of_refraction_diopters(wavelength_nm,
                                                                                            lca_reference_nm))
    return converted if own is None else dataclasses.replace(converted, wavelength_nm=wavelength_nm)


def _check_conversion(own_nm: float, wavelength_nm: float, lca_reference_nm: float | None) -> None:
    """Refuse a front known at ``own_nm`` used at ``wavelength_nm`` unless converted from its own wavelength."""
    if lca_reference_nm is not None and not same_wavelength(lca_reference_nm, own_nm):
        raise VissimInputError(f"the wavefront holds at {own_nm:g} nm: its chromatic defocus can only be taken from "
                               f"there (LCA reference {own_nm:g} nm), not from {lca_reference_nm:g} nm")
    if lca_reference_nm is None and not same_wavelength(own_nm, wavelength_nm):
        raise VissimInputError(f"the wavefront holds at {own_nm:g} nm, not at {wavelength_nm:g} nm: trace or measure "
                               f"it at {wavelength_nm:g} nm, or convert it by the eye's chromatic defocus "
                               f"(LCA reference {own_nm:g} nm)")


def suggested_size_px(
    wavefront: Wavefront,
    arcmin_per_px: float,
    *,
    pupil_diameter_mm: float | None = None,
    wavelength_nm: float | Sequence[float] | None = None,
    weights: Sequence[float] | None = None,
    lca_reference_nm: float | None = None,
    mode: str = "wave",
    minimum_px: int = 33,
) -> int:
    """The smallest odd field size (px, at least ``minimum_px``) that holds all but
    `MAX_ENERGY_OUTSIDE` of the PSF's energy (`energy_outside_field`); ``wavelength_nm`` defaults to a
    `SpectralWavefront`'s own wavelengths, else 550 nm."""
    diameter = wavefront.pupil_diameter_mm if pupil_diameter_mm is None else check_pupil_mm(pupil_diameter_mm)
    step = check_arcmin_per_px(arcmin_per_px)
    wavelength_nm = wavelengths_for(wavefront, wavelength_nm, DEFAULT_WAVELENGTH_NM)
    wavelengths = tuple(check_wavelength_nm(w) for w in np.atleast_1d(wavelength_nm))
    weights = (1.0,) * len(wavelengths) if weights is None else tuple(float(w) for w in weights)
    own = getattr(wavefront, "wavelength_nm", None)
    for wavelength in wavelengths if own is not None else ():
        _check_conversion(own, wavelength, lca_reference_nm)
    if hasattr(wavefront, "coefficients_um"):  # campaigns ask again and again for the same eyes
        return _suggested_size_cached(tuple(wavefront.coefficients_um.items()), wavefront.pupil_diameter_mm, diameter,
                                      step, wavelengths, weights, lca_reference_nm, mode, int(minimum_px))
    return _suggested_size(wavefront, diameter, step, wavelengths, weights, lca_reference_nm, mode, int(minimum_px))


@functools.lru_cache(maxsize=1024)
def _suggested_size_cached(items, measured_mm, diameter, step, wavelengths, weights, lca_reference_nm, mode, minimum_px):
    return _suggested_size(Wavefront(dict(items), measured_mm), diameter, step, list(wavelengths), list(weights),
                           lca_reference_nm, mode, minimum_px)


def _suggested_size(wavefront, diameter, step, wavelengths, weights, lca_reference_nm, mode, minimum_px) -> int:
    start = minimum_px | 1  # the smallest odd size allowed
    fans = _ray_fans(wavefront, diameter, wavelengths, weights, mode, lca_reference_nm)
    if _outside_of(fans, step, start) <= MAX_ENERGY_OUTSIDE:
        return start
    return _search_size(fans, diameter, wavelengths, step, start, MAX_ENERGY_OUTSIDE)


def load_size_tables() -> None:
    """Build the tables `suggested_size_px` reads (once per process; SciPy's special functions imported), so a
    caller can have them made on another thread while it works."""
    _airy_tail_table()


@functools.cache
def _airy_tail_table() -> tuple[np.ndarray, np.ndarray]:
    r = np.linspace(0.0, _AIRY_TABLE_LAMBDA_OVER_D, 20001)
    return r, np.square(scipy_special.j0(np.pi * r)) + np.square(scipy_special.j1(np.pi * r))


def airy_tail(r_lambda_over_d: np.ndarray) -> np.ndarray:
    """Fraction of an Airy pattern's energy beyond radius r (lambda/D): J0^2 + J1^2 of pi r (Rayleigh).

    Tabulated to 64 lambda/D, beyond which it is its asymptote 2 / (pi^2 r) to 0.2 % relative.
    """
    r, tail = _airy_tail_table()
    x = np.asarray(r_lambda_over_d, dtype=float)
    far = (2.0 / np.pi**2) / np.maximum(x, r[-1])
    position = np.fmin(np.fmax(x, 0.0), r[-1]) * ((len(r) - 1) / r[-1])  # NaN to 0; a uniform table: the cell by division
    cell = np.minimum(position.astype(np.intp), len(r) - 2)
    fraction = position - cell
    near = tail[cell] * (1.0 - fraction) + tail[cell + 1] * fraction
    return np.where(np.isnan(x), np.nan, np.where(x < r[-1], near, far))


def rim_widening(blur_arcmin: float, lambda_over_d_arcmin: float) -> float:
    """How much wider than the Airy pattern a defocused rim spreads light: sqrt(1 + EDGE_BROADENING N_F),
    N_F = the blur's Fresnel number (waves of equivalent defocus, blur / (4 lambda/D))."""
    return math.sqrt(1.0 + EDGE_BROADENING * blur_arcmin / lambda_over_d_arcmin / 4.0)


def airy_tail_radius_lambda_over_d(fraction: float) -> float:
    """The radius (lambda/D) beyond which ``fraction`` of an Airy pattern lies: its tail 2 / (pi^2 r)."""
    return 2.0 / (math.pi**2 * fraction)


def _rays(wavefront: Wavefront, diameter_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """Landing offsets (col, row) in arcmin of the pupil grid's cell centres (`ESTIMATE_RAYS_PER_SIDE` a side)."""
    return landing_arcmin(wavefront, diameter_mm, *pupil_cell_centres(ESTIMATE_RAYS_PER_SIDE))


def _inside_fraction(col, row, low, high, lambda_over_d):
    """Mean fraction of each ray's diffraction pattern inside the square [low, high]^2 (arcmin)."""
    if lambda_over_d is None:  # ray optics: the ray is in or out
        return float(np.mean((col >= low) & (col <= high) & (row >= low) & (row <= high)))
    phi = (np.arange(ESTIMATE_DIRECTIONS) + 0.5) * (2 * np.pi / ESTIMATE_DIRECTIONS)
    dx, dy = np.cos(phi)[None, :], np.sin(phi)[None, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # slab intersection with the square
        tx = np.stack([(low - col[:, None]) / dx, (high - col[:, None]) / dx])
        ty = np.stack([(low - row[:, None]) / dy, (high - row[:, None]) / dy])
    enter = np.maximum(np.maximum(tx.min(axis=0), ty.min(axis=0)), 0.0)
    leave = np.minimum(tx.max(axis=0), ty.max(axis=0))
    inside = np.where(leave > enter, airy_tail(enter / lambda_over_d) - airy_tail(leave / lambda_over_d), 0.0)
    return float(np.mean(inside))


def energy_outside_field(
    wavefront: Wavefront,
    diameter_mm: float,
    wavelengths_nm: Sequence[float],
    weights: Sequence[float],
    arcmin_per_px: float,
    size_px: int,
    *,
    mode: str = "wave",
    lca_reference_nm: float | None = None,
    conservative: bool = True,
) -> float:
    """Estimated fraction of the (weighted) PSF's energy outside a ``size_px`` field.

    ``conservative``: widen each ray's diffraction pattern for the rim's Fresnel diffraction
    (see the module docstring), so the estimate is not below the PSF's; otherwise the plain
    ray-optics-times-Airy model, which can be well below it for a defocused pupil.
    """
    fans = _ray_fans(wavefront, diameter_mm, wavelengths_nm, weights, mode, lca_reference_nm, conservative)
    return _outside_of(fans, arcmin_per_px, size_px)


class _Fan(NamedTuple):
    """One wavelength's rays: its weight, their landing offsets (arcmin), their diffraction spread (arcmin; None in
    ray optics) and the widest landing, the geometric blur radius (arcmin)."""

    weight: float
    col: np.ndarray
    row: np.ndarray
    spread: float | None
    blur_arcmin: float


def _ray_fans(wavefront, diameter_mm, wavelengths_nm, weights, mode, lca_reference_nm, conservative=True) -> list:
    """Each wavelength's `_Fan`: what `energy_outside_field` needs whatever the field's size."""
    fans = []
    for w, weight in zip(wavelengths_nm, weights):
        front = front_at_wavelength(wavefront, w, lca_reference_nm)
        col, row = _rays(front, diameter_mm)
        blur = geometric_blur_radius_arcmin(front, diameter_mm)
        spread = None
        if mode == "wave":
            lambda_over_d = float(rad_to_arcmin(nm_to_mm(w) / diameter_mm))
            spread = lambda_over_d * (rim_widening(blur, lambda_over_d) if conservative else 1.0)
        fans.append(_Fan(weight, col, row, spread, blur))
    return fans


def _outside_of(fans: list, arcmin_per_px: float, size_px: int) -> float:
    """The weighted fraction of the ``fans``' energy outside a ``size_px`` field."""
    low = -(size_px // 2 + 0.5) * arcmin_per_px  # pixel edges; the origin is at [N//2, N//2]
    high = (size_px - size_px // 2 - 0.5) * arcmin_per_px
    outside = sum(f.weight * (1.0 - _inside_fraction(f.col, f.row, low, high, f.spread)) for f in fans)
    return outside / sum(f.weight for f in fans)


def size_holding_px(wavefront, diameter_mm, wavelengths_nm, weights, arcmin_per_px, size_px, *, mode="wave",
                    lca_reference_nm=None, fraction: float = MAX_ENERGY_OUTSIDE) -> int:
    """Smallest odd size > ``size_px`` whose field leaves at most ``fraction`` of the energy outside
    (conservative estimate); ``size_px`` itself is taken to be too small."""
    fans = _ray_fans(wavefront, diameter_mm, wavelengths_nm, weights, mode, lca_reference_nm)
    return _search_size(fans, diameter_mm, wavelengths_nm, arcmin_per_px, size_px, fraction)


def _search_size(fans, diameter_mm, wavelengths_nm, arcmin_per_px, size_px, fraction) -> int:
    """`size_holding_px` with the rays already landed (``fans``, `_ray_fans`)."""
    def too_small(n):
        return _outside_of(fans, arcmin_per_px, n) > fraction
    # First guess: the blur plus the Airy tail's radius for ``fraction``, widened as the estimate is.
    blur = max(f.blur_arcmin for f in fans)
    widest = float(rad_to_arcmin(nm_to_mm(max(wavelengths_nm)) / diameter_mm))
    reach = blur + airy_tail_radius_lambda_over_d(fraction) * widest * rim_widening(blur, widest)
    guess = int(2 * math.ceil(reach / arcmin_per_px))
    low, high = size_px, max(size_px, 3)
    if guess > size_px and too_small(guess // 2):
        low = guess // 2
    high = max(high, guess if guess > low else high)
    while too_small(high):
        if high >= SIZE_SEARCH_LIMIT_PX:
            return SIZE_SEARCH_LIMIT_PX + 1  # more than any PSF vissim computes: the caller refuses
        low, high = high, min(2 * high, SIZE_SEARCH_LIMIT_PX)
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if too_small(middle) else (low, middle)
    return high + (1 - high % 2)
