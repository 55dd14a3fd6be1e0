"""Wavefront aberrations: OSA Zernike coefficients over a stated pupil, and prescriptions.

A `Wavefront` holds coefficients in micrometres (``opd_um``) over the pupil diameter
on which they were measured.  Evaluating it inside a smaller pupil is exact (the
polynomials are evaluated at ``r / R_measured``); `Wavefront.rescaled` re-expresses the
same surface on the smaller pupil's own basis.

Prescription <-> second-order Zernike uses the standard formulas (Thibos et al. 2004; Dai
2008; ERRATA item 1), R the pupil radius in mm::

    c(2,0)  = -M   R^2 / (4 sqrt 3)
    c(2,2)  = -J0  R^2 / (2 sqrt 6)   = C R^2 cos 2a / (4 sqrt 6)
    c(2,-2) = -J45 R^2 / (2 sqrt 6)   = C R^2 sin 2a / (4 sqrt 6)

with (M, J0, J45) the power vector of the *correcting lens* (`Prescription`), so a
myopic eye (negative sphere) has c(2,0) > 0: its wavefront, leaving the eye, leads at the
pupil's edge (OSA sign: W > 0 is phase advance).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from vissim.checks import describe, finite_number
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError, VissimTypeError
from vissim.optics.rx.prescription import Prescription, as_prescription
from vissim.optics.pupil.zernike import nm_to_ansi_j, zernike_basis, zernike_gradient, zernike_keys, zernike_sum

__all__ = ["Wavefront", "WAVELENGTH_MATCH_NM", "same_wavelength", "prescription_to_zernike_um",
           "zernike_um_to_prescription", "parse_zernike_terms",
           "ring_fit_um"]

_SQRT3 = math.sqrt(3.0)
_SQRT6 = math.sqrt(6.0)


def _check_pupil(pupil_diameter_mm: float, name: str = "pupil diameter") -> float:
    return check_pupil_mm(pupil_diameter_mm, name)


def prescription_to_zernike_um(rx: Prescription, pupil_diameter_mm: float) -> dict[tuple[int, int], float]:
    """Second-order OSA coefficients (µm) of the eye that ``rx`` corrects, over the pupil."""
    rx = as_prescription(rx)
    radius_sq = (_check_pupil(pupil_diameter_mm) / 2.0) ** 2
    m, j0, j45 = rx.power_vector()
    return {
        (2, -2): -j45 * radius_sq / (2.0 * _SQRT6),
        (2, 0): -m * radius_sq / (4.0 * _SQRT3),
        (2, 2): -j0 * radius_sq / (2.0 * _SQRT6),
    }


def zernike_um_to_prescription(coefficients_um: Mapping[tuple[int, int], float], pupil_diameter_mm: float) -> Prescription:
    """The correcting lens from the second-order coefficients (higher orders ignored)."""
    radius_sq = (_check_pupil(pupil_diameter_mm) / 2.0) ** 2
    c2m2 = float(coefficients_um.get((2, -2), 0.0))
    c20 = float(coefficients_um.get((2, 0), 0.0))
    c22 = float(coefficients_um.get((2, 2), 0.0))
    return Prescription.from_power_vector(-4.0 * _SQRT3 * c20 / radius_sq, -2.0 * _SQRT6 * c22 / radius_sq,
                                          -2.0 * _SQRT6 * c2m2 / radius_sq)


_TERM_RE = re.compile(r"^\s*(?P<n>[+-]?\d+)\s*,\s*(?P<m>[+-]?\d+)\s*=\s*(?P<value>\S+)\s*$")


def parse_zernike_terms(text: str) -> dict[tuple[int, int], float]:
    """Parse ``"n,m=µm;n,m=µm"`` (e.g. ``"2,0=0.5;4,0=0.1"``); repeated terms add up."""
    if not isinstance(text, str) or not text.strip():
        raise VissimInputError("Zernike terms must look like '2,0=0.5;4,0=0.1' (n,m=coefficient in µm)")
    terms: dict[tuple[int, int], float] = {}
    for part in filter(None, (p.strip() for p in text.split(";"))):
        match = _TERM_RE.match(part)
        if match is None:
            raise VissimInputError(f"cannot read Zernike term {part!r}: expected 'n,m=µm' such as '2,0=0.5'")
        try:
            value = float(match.group("value"))
        except ValueError:
            raise VissimInputError(f"Zernike term {part!r}: {match.group('value')!r} is not a number of µm") from None
        if not math.isfinite(value):
            raise VissimInputError(f"Zernike term {part!r}: coefficient must be finite µm")
        key = (int(match.group("n")), int(match.group("m")))
        nm_to_ansi_j(*key)  # validates (n, m)
        terms[key] = terms.get(key, 0.0) + value
    return terms


def ring_fit_um(opd_um, pupil_diameter_mm: float, max_order: int, rings: int, spokes: int):
    """Least-squares OSA Zernike fit up to ``max_order`` of the surface ``opd_um(x_mm, y_mm)`` (µm) over a pupil.

    Sampled on ``rings`` equal-area rings of ``spokes`` points each; returns (the (n, m) keys, their µm).
    """
    keys = zernike_keys(max_order)
    rho = np.sqrt((np.arange(rings) + 0.5) / rings)  # equal-area rings
    theta = 2 * np.pi * (np.arange(spokes) + 0.5) / spokes
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    radius = pupil_diameter_mm / 2.0
    target = opd_um(radius * rr * np.cos(tt), radius * rr * np.sin(tt)).ravel()
    basis = zernike_basis(keys, rr * np.cos(tt), rr * np.sin(tt))
    solution, *_ = np.linalg.lstsq(basis, target, rcond=None)
    return keys, solution


def _zernike_key(key) -> tuple[int, int]:
    """A Zernike index ``(n, m)`` of whole numbers; anything else refused with what is accepted."""
    if (not isinstance(key, (tuple, list)) or len(key) != 2
            or not all(isinstance(k, (int, float, np.integer, np.floating)) and not isinstance(k, bool)
                       and float(k).is_integer() for k in key)):
        raise VissimTypeError(f"a Zernike term's key must be a tuple (n, m) of integers (OSA), got {describe(key)}")
    return int(key[0]), int(key[1])


@dataclass(frozen=True, eq=False)
class Wavefront:
    """OSA Zernike expansion of a wavefront error, in µm, over ``pupil_diameter_mm``.

    ``coefficients_um`` maps ``(n, m)`` to the coefficient in micrometres. ``wavelength_nm``: the
    light the front was traced or measured in, or None for a front that holds at any wavelength (a
    prescription's, the reduced eye's). A front that knows its wavelength is used at that wavelength
    only, unless told how to convert it (`vissim.optics.psf.field_size.front_at_wavelength`).

    Parameters
    ----------
    coefficients_um : mapping of (int, int) to float
        OSA/ANSI Zernike coefficients (radial order ``n``, azimuthal frequency ``m``) in µm;
        zeros are dropped.
    pupil_diameter_mm : float
        Diameter of the pupil over which the coefficients are defined, mm.
    wavelength_nm : float, optional
        The wavelength the coefficients hold at, nm (None: any).

    Examples
    --------
    >>> import vissim
    >>> vissim.Wavefront({(2, 0): 0.5, (4, 0): 0.1}, pupil_diameter_mm=6.0)
    Wavefront({(2,0)=0.5, (4,0)=0.1} um over 6 mm)
    """

    coefficients_um: Mapping[tuple[int, int], float]
    pupil_diameter_mm: float
    wavelength_nm: float | None = None
    _items: tuple = field(init=False, repr=False)

    def __post_init__(self) -> None:
        diameter = _check_pupil(self.pupil_diameter_mm, "measurement pupil diameter")
        if not isinstance(self.coefficients_um, Mapping):
            raise VissimTypeError("Wavefront's coefficients_um must be a mapping {(n, m): µm} of OSA Zernike terms, "
                                  f"got {describe(self.coefficients_um)}; for a prescription use "
                                  "Wavefront.from_prescription(rx, pupil_diameter_mm), for text Wavefront.parse(text, pupil_diameter_mm)")
        clean: dict[tuple[int, int], float] = {}
        for key, value in dict(self.coefficients_um).items():
            n, m = _zernike_key(key)
            nm_to_ansi_j(n, m)  # validates (n, m)
            value = finite_number(value, f"Zernike coefficient ({n},{m})", "µm")
            if value != 0.0:
                clean[(n, m)] = clean.get((n, m), 0.0) + value
        object.__setattr__(self, "coefficients_um", MappingProxyType(dict(sorted(clean.items()))))
        object.__setattr__(self, "pupil_diameter_mm", diameter)
        if self.wavelength_nm is not None:
            object.__setattr__(self, "wavelength_nm", checked_wavelength_nm(self.wavelength_nm, "wavefront's wavelength"))
        object.__setattr__(self, "_items", tuple(self.coefficients_um.items()))

    # -- construction -----------------------------------------------------------------
    @classmethod
    def from_prescription(cls, rx: Prescription, pupil_diameter_mm: float) -> Wavefront:
        """The wavefront error of an uncorrected eye whose correcting lens is ``rx``.

        Parameters
        ----------
        rx : Prescription
            The correcting lens (myope: negative sphere), D; TABO axis in degrees.
        pupil_diameter_mm : float
            Pupil diameter, mm.

        Returns
        -------
        Wavefront
            Defocus ``(2, 0)`` and astigmatism ``(2, ±2)`` coefficients in µm.

        Examples
        --------
        >>> import vissim
        >>> rx = vissim.Prescription.parse("-2.00 -1.00 x 180")
        >>> vissim.Wavefront.from_prescription(rx, pupil_diameter_mm=4.0)
        Wavefront({(2,0)=1.44338, (2,2)=-0.408248} um over 4 mm)
        """
        return cls(prescription_to_zernike_um(rx, pupil_diameter_mm), pupil_diameter_mm)

    @classmethod
    def parse(cls, text: str, pupil_diameter_mm: float) -> Wavefront:
        """Parse Zernike terms written ``"n,m=µm;n,m=µm"``; repeated terms add up.

        Parameters
        ----------
        text : str
            Terms such as ``"2,0=0.5;4,0=0.1"`` (OSA indices, coefficients in µm).
        pupil_diameter_mm : float
            Pupil over which the coefficients are defined, mm.

        Returns
        -------
        Wavefront

        Examples
        --------
        >>> import vissim
        >>> vissim.Wavefront.parse("2,0=0.5;4,0=0.1", pupil_diameter_mm=6.0)
        Wavefront({(2,0)=0.5, (4,0)=0.1} um over 6 mm)
        """
        return cls(parse_zernike_terms(text), pupil_diameter_mm)

    @classmethod
    def tilt(cls, image_shift_mrad, pupil_diameter_mm: float) -> Wavefront:
        """The tilt that moves the image by ``image_shift_mrad`` = (x, y) mrad of the visual field, OSA frame:
        c(1, 1), c(1, -1) = shift R / 2 µm over a pupil of radius R mm (`image_shift_mrad`'s inverse;
        docs/conventions.md, "Sign of the wavefront")."""
        radius = 0.5 * _check_pupil(pupil_diameter_mm)
        x, y = (float(v) for v in image_shift_mrad)
        return cls({(1, 1): 0.5 * x * radius, (1, -1): 0.5 * y * radius}, pupil_diameter_mm)

    @property
    def image_shift_mrad(self) -> tuple[float, float]:
        """Where a point is seen, minus where it is, by this front's tilt: (x, y) mrad of the visual field, OSA
        frame: 2 c(1, 1) / R, 2 c(1, -1) / R (R the pupil radius, mm; docs/conventions.md, "Sign of the
        wavefront"). The one place the tilt's image shift is written."""
        radius = 0.5 * self.pupil_diameter_mm
        return (2.0 * self.coefficients_um.get((1, 1), 0.0) / radius,
                2.0 * self.coefficients_um.get((1, -1), 0.0) / radius)

    @classmethod
    def zero(cls, pupil_diameter_mm: float) -> Wavefront:
        """A perfect (aberration-free) wavefront over a pupil of ``pupil_diameter_mm`` mm.

        Examples
        --------
        >>> import vissim
        >>> vissim.Wavefront.zero(3.0)
        Wavefront({} um over 3 mm)
        """
        return cls({}, pupil_diameter_mm)

    def __add__(self, other: Wavefront) -> Wavefront:
        if not isinstance(other, Wavefront):
            return NotImplemented
        if other.pupil_diameter_mm != self.pupil_diameter_mm:
            other = other.rescaled(self.pupil_diameter_mm) if other.pupil_diameter_mm > self.pupil_diameter_mm else other
            if other.pupil_diameter_mm != self.pupil_diameter_mm:
                raise VissimInputError(
                    f"cannot add wavefronts over {self.pupil_diameter_mm:g} mm and {other.pupil_diameter_mm:g} mm pupils"
                )
        merged = dict(self.coefficients_um)
        for key, value in other.coefficients_um.items():
            merged[key] = merged.get(key, 0.0) + value
        return Wavefront(merged, self.pupil_diameter_mm, _common_wavelength_nm(self, other))

    def with_defocus_diopters(self, extra_sphere_diopters: float) -> Wavefront:
        """Add a spherical *prescription* change (negative = more myopic eye) at this pupil."""
        return self + Wavefront.from_prescription(Prescription(extra_sphere_diopters), self.pupil_diameter_mm)

    # -- queries ----------------------------------------------------------------------
    def to_prescription(self) -> Prescription:
        return zernike_um_to_prescription(self.coefficients_um, self.pupil_diameter_mm)

    @property
    def max_order(self) -> int:
        return max((n for n, _ in self.coefficients_um), default=0)

    def opd_um(self, x_mm: np.ndarray, y_mm: np.ndarray) -> np.ndarray:
        """Wavefront error (µm) at pupil points in mm, OSA frame (+x examiner's right, +y up).

        Points outside the measurement pupil get the polynomial continuation; mask them.
        """
        x = np.asarray(x_mm, dtype=float)
        y = np.asarray(y_mm, dtype=float)
        radius = self.pupil_diameter_mm / 2.0
        return zernike_sum(self._items, x / radius, y / radius)

    def slopes_mrad(self, x_mm: np.ndarray, y_mm: np.ndarray, step_mm: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(dW/dx, dW/dy) in µm/mm = mrad: the expansion's exact derivatives (`zernike_gradient`); by central
        differences of step ``step_mm`` when it is given, or above the orders whose monomials hold."""
        x = np.asarray(x_mm, dtype=float)
        y = np.asarray(y_mm, dtype=float)
        radius = self.pupil_diameter_mm / 2.0
        gradient = zernike_gradient(self._items, x / radius, y / radius) if step_mm is None else None
        if gradient is not None:
            return gradient[0] / radius, gradient[1] / radius
        h = step_mm if step_mm is not None else 1e-5 * self.pupil_diameter_mm
        dwdx = (self.opd_um(x + h, y) - self.opd_um(x - h, y)) / (2.0 * h)
        dwdy = (self.opd_um(x, y + h) - self.opd_um(x, y - h)) / (2.0 * h)
        return dwdx, dwdy

    def rescaled(self, pupil_diameter_mm: float) -> Wavefront:
        """The same surface expanded over a smaller, concentric pupil (exact for polynomials).

        Solved by least squares on a polar grid dense enough for the highest order; a pupil
        larger than the measurement pupil is refused (extrapolation is not a measurement).
        """
        new = _check_pupil(pupil_diameter_mm, "calculation pupil diameter")
        if new > self.pupil_diameter_mm * (1 + 1e-12):
            raise VissimInputError(
                f"calculation pupil {new:g} mm is larger than the {self.pupil_diameter_mm:g} mm pupil "
                "the coefficients were measured over; Zernike coefficients cannot be extrapolated"
            )
        if not self._items or new == self.pupil_diameter_mm:
            return Wavefront(dict(self.coefficients_um), new, self.wavelength_nm)
        order = self.max_order
        keys, solution = ring_fit_um(self.opd_um, new, order, 2 * order + 4, 4 * order + 8)
        scale = max(1e-12, float(np.max(np.abs(solution))))
        return Wavefront({k: float(v) for k, v in zip(keys, solution) if abs(v) > 1e-13 * scale}, new,
                         self.wavelength_nm)

    def as_json(self) -> dict:
        record = {
            "pupil_diameter_mm": self.pupil_diameter_mm,
            "zernike_um": {f"{n},{m}": v for (n, m), v in self._items},
        }
        if self.wavelength_nm is not None:
            record["wavelength_nm"] = self.wavelength_nm
        return record

    def __repr__(self) -> str:
        terms = ", ".join(f"({n},{m})={v:.6g}" for (n, m), v in self._items)
        light = "" if self.wavelength_nm is None else f" at {self.wavelength_nm:g} nm"
        return f"Wavefront({{{terms}}} um over {self.pupil_diameter_mm:g} mm{light})"


#: Two wavelengths closer than this (nm) are one wavelength when fronts are matched to light.
WAVELENGTH_MATCH_NM = 1e-6


def same_wavelength(a_nm: float, b_nm: float) -> bool:
    """Whether two wavelengths (nm) are one, to `WAVELENGTH_MATCH_NM`."""
    return abs(a_nm - b_nm) <= WAVELENGTH_MATCH_NM


def _common_wavelength_nm(a: Wavefront, b: Wavefront) -> float | None:
    """The wavelength of the sum of two fronts: the one either knows; two different ones refused."""
    if a.wavelength_nm is None or b.wavelength_nm is None:
        return a.wavelength_nm if b.wavelength_nm is None else b.wavelength_nm
    if not same_wavelength(a.wavelength_nm, b.wavelength_nm):
        raise VissimInputError(f"cannot add a wavefront at {a.wavelength_nm:g} nm to one at {b.wavelength_nm:g} nm")
    return a.wavelength_nm
