"""Sphero-cylinders: prescriptions, refractive errors and lens powers.

Three quantities share the sphere/cylinder/axis notation but mean different things, and
their signs differ.  vissim keeps them as distinct types so they cannot be mixed up:

* `Prescription` -- the **correcting lens** (what an optometrist writes), at the
  eye's or camera's principal plane.  A myope has a negative sphere.
* `RefractiveError` -- the **eye's refractive error** as excess dioptric power at
  the same plane.  A myope has a *positive* sphere here: ``error == -prescription``.
* `LensPower` -- the power of a physical lens, or the power a trial lens *adds* at the
  camera's principal plane (positive for a plus lens).  A camera with an added +2 D lens is
  made myopic: its prescription is the negative of the added power.

Axes follow TABO (degrees counter-clockwise from the examiner's right, facing the subject;
0 and 180 are the same meridian and vissim writes 180).  Cylinders are stored as written;
`SpheroCylinder.minus_cylinder` / `plus_cylinder` transpose.

Power vectors follow Thibos, Wheeler & Horner (1997)::

    M = S + C/2,  J0 = -(C/2) cos 2a,  J45 = -(C/2) sin 2a
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Self

from vissim.checks import AXIS_RANGE_DEG, MAX_POWER_DIOPTERS
from vissim.checks import describe
from vissim.checks import finite_number as _finite
from vissim.errors import VissimInputError, VissimTypeError

__all__ = ["prescription_from", "SpheroCylinder", "Prescription", "RefractiveError", "LensPower", "as_prescription",
           "parse_spherocylinder"]

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)"
_SPHERE = rf"(?P<sphere>{_NUMBER}|plano|pl)"
_CYL = rf"(?P<cyl>{_NUMBER})"
_AXIS = r"(?P<axis>[+-]?\d+(?:\.\d*)?)"
_RX_RE = re.compile(
    rf"""^\s*
    (?:
        {_SPHERE}\s*(?:ds|d|sph)?            # sphere, optionally "DS"
        (?:(?:\s*/\s*|\s*(?=[+-])|\s+){_CYL}\s*(?:dc|d|cyl)?\s*(?:[x×*@]|axis)\s*{_AXIS}\s*°?)?
      |
        (?P<cylonly>{_NUMBER})\s*(?:dc|cyl)\s*(?:[x×*@]|axis)\s*(?P<axisonly>[+-]?\d+(?:\.\d*)?)\s*°?
    )
    \s*$""",
    re.IGNORECASE | re.VERBOSE,
)


def _normalise_axis(axis_deg: float) -> float:
    """Map any angle onto TABO's (0, 180] (180 rather than 0 for the horizontal meridian)."""
    axis = math.fmod(axis_deg, 180.0)
    if axis < 0.0:
        axis += 180.0
    if axis <= 1e-9 or axis >= 180.0 - 1e-9:
        return 180.0
    return axis


@dataclass(frozen=True)
class SpheroCylinder:
    """Sphere, cylinder and TABO axis; the common machinery of the three power types.

    Parameters
    ----------
    sphere_diopters : float
        Sphere power in dioptres.
    cylinder_diopters : float
        Cylinder power in dioptres.
    axis_deg : float
        Cylinder axis in degrees, TABO, 0-180 inclusive (stored in (0, 180]).  Ignored and
        stored as 180 when the cylinder is zero.
    """

    sphere_diopters: float
    cylinder_diopters: float = 0.0
    axis_deg: float = 180.0

    def __post_init__(self) -> None:
        for name in ("sphere_diopters", "cylinder_diopters", "axis_deg"):
            if isinstance(getattr(self, name), (str, bytes)):
                raise VissimTypeError(f"{type(self).__name__}'s {name} must be a number, got {describe(getattr(self, name))}; "
                                      f"read written notation with {type(self).__name__}.parse('-2.00 -1.25 x 180')")
        sphere = _finite(self.sphere_diopters, "sphere", "dioptres")
        cyl = _finite(self.cylinder_diopters, "cylinder", "dioptres")
        axis = _finite(self.axis_deg, "axis", "degrees")
        low, high = AXIS_RANGE_DEG
        if not low <= axis <= high:
            raise VissimInputError(f"axis must be within {low:g}-{high:g} degrees (TABO), got {axis:g} deg")
        object.__setattr__(self, "sphere_diopters", sphere + 0.0)
        object.__setattr__(self, "cylinder_diopters", cyl + 0.0)
        object.__setattr__(self, "axis_deg", 180.0 if cyl == 0.0 else _normalise_axis(axis))

    # -- notation ---------------------------------------------------------------------
    @classmethod
    def parse(cls, text: str) -> Self:
        """Parse a written sphero-cylinder; see `parse_spherocylinder` for the notations.

        Parameters
        ----------
        text : str
            Sphere and cylinder in dioptres, TABO axis in degrees, e.g. ``"-2.00 -1.25 x 180"``.

        Returns
        -------
        The same class (`Prescription`, ...), as written (cylinder sign kept).

        Examples
        --------
        >>> import vissim
        >>> rx = vissim.Prescription.parse("-2.00/-1.25x180")
        >>> rx.sphere_diopters, rx.cylinder_diopters, rx.axis_deg
        (-2.0, -1.25, 180.0)
        >>> print(rx)
        -2.00 -1.25 x 180
        """
        sphere, cyl, axis = parse_spherocylinder(text)
        return cls(sphere, cyl, axis)

    def __str__(self) -> str:
        return self.format()

    def format(self, decimals: int = 2) -> str:
        """Written form, e.g. ``-2.00 -1.25 x 180`` (clinical: 2 decimals; more for optics).

        A cylinder that rounds to 0 at ``decimals`` is written as none: ``S DS`` with S the spherical
        equivalent (the same whichever cylinder sign the power is written in), and no axis (a
        near-zero cylinder's axis is noise: −1.00 DS read back from a traced eye is not
        ``-1.00 -0.00 x 137``). A sphere that rounds to 0 is written ``plano``.
        """
        sphere, cylinder = self.sphere_diopters, self.cylinder_diopters
        if round(cylinder, decimals) == 0:
            sphere, cylinder = self.spherical_equivalent_diopters, 0.0
        written = "plano" if round(sphere, decimals) == 0 else f"{sphere:+.{decimals}f}"
        if cylinder == 0:
            return f"{written} DS"
        return f"{written} {cylinder:+.{decimals}f} x {self.axis_deg:.{max(0, decimals - 2)}f}"

    def format_exact(self, most_decimals: int = 6) -> str:
        """The shortest `format` (2 decimals or more, up to ``most_decimals``) that reads back as this power,
        e.g. ``-3.00 DS`` and ``+0.125 DS``."""
        for decimals in range(2, most_decimals):
            written = self.format(decimals)
            read_back = Prescription.parse(written).power_matrix()
            if all(abs(a - b) <= 1e-9 for row, mine in zip(read_back, self.power_matrix()) for a, b in zip(row, mine)):
                return written
        return self.format(most_decimals)

    # -- transposition ----------------------------------------------------------------
    def transposed(self) -> Self:
        """The same power written with the opposite cylinder sign."""
        if self.cylinder_diopters == 0:
            return self
        return type(self)(self.sphere_diopters + self.cylinder_diopters, -self.cylinder_diopters,
                          _normalise_axis(self.axis_deg + 90.0))

    def minus_cylinder(self) -> Self:
        return self.transposed() if self.cylinder_diopters > 0 else self

    def plus_cylinder(self) -> Self:
        return self.transposed() if self.cylinder_diopters < 0 else self

    # -- power vectors ----------------------------------------------------------------
    @property
    def spherical_equivalent_diopters(self) -> float:
        return self.sphere_diopters + self.cylinder_diopters / 2.0

    def power_vector(self) -> tuple[float, float, float]:
        """(M, J0, J45) in dioptres, Thibos, Wheeler & Horner (1997)."""
        two_axis = math.radians(2.0 * self.axis_deg)
        half_cyl = self.cylinder_diopters / 2.0
        vector = (self.sphere_diopters + half_cyl, -half_cyl * math.cos(two_axis), -half_cyl * math.sin(two_axis))
        # cos/sin of multiples of 90 deg leave ~1e-16 residues; they are exact zeros.
        return tuple(0.0 if abs(v) < 1e-13 * (1.0 + abs(half_cyl)) else v for v in vector)

    @classmethod
    def from_power_vector(cls, m_diopters: float, j0_diopters: float, j45_diopters: float) -> Self:
        """Inverse of `power_vector`, in minus-cylinder form."""
        m = _finite(m_diopters, "M", "dioptres")
        j0 = _finite(j0_diopters, "J0", "dioptres")
        j45 = _finite(j45_diopters, "J45", "dioptres")
        magnitude = math.hypot(j0, j45)
        if magnitude < 1e-12:
            return cls(m, 0.0, 180.0)
        cyl = -2.0 * magnitude
        axis = math.degrees(0.5 * math.atan2(j45, j0)) % 180.0
        return cls(m - cyl / 2.0, cyl, axis)

    def meridian_power(self, meridian_deg: float) -> float:
        """Power acting in the given meridian (a ray fan spread along it), dioptres.

        ``S + C sin^2(meridian - axis)``: the cylinder has no power along its axis.
        """
        delta = math.radians(meridian_deg - self.axis_deg)
        return self.sphere_diopters + self.cylinder_diopters * math.sin(delta) ** 2

    def power_matrix(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Dioptric power matrix (Long 1976; Keating 1981) in the TABO x (right) / y (up) frame."""
        m, j0, j45 = self.power_vector()
        return ((m + j0, j45), (j45, m - j0))

    @classmethod
    def from_power_matrix(cls, matrix) -> Self:
        """Inverse of `power_matrix` (the antisymmetric part, if any, is dropped)."""
        (fxx, fxy), (fyx, fyy) = matrix
        off = 0.5 * (float(fxy) + float(fyx))
        return cls.from_power_vector(0.5 * (fxx + fyy), 0.5 * (fxx - fyy), off)

    def is_close(self, other: SpheroCylinder, tol_diopters: float = 1e-9) -> bool:
        """Same power (whatever the cylinder sign it is written in)."""
        return all(abs(a - b) <= tol_diopters for a, b in zip(self.power_vector(), other.power_vector()))

    def __neg__(self) -> Self:
        return type(self)(-self.sphere_diopters, -self.cylinder_diopters, self.axis_deg)


@dataclass(frozen=True)
class Prescription(SpheroCylinder):
    """The correcting lens at the eye's (camera's) principal plane; a myope's sphere is < 0.

    See ``docs/conventions.md`` for the sign, axis and power-vector conventions, and
    `parse` for written prescriptions (``"-2.00 -1.25 x 180"``).  The eye's refractive
    error, of the opposite sign, is `refractive_error`.

    Parameters
    ----------
    sphere_diopters : float
        Sphere, dioptres (D); negative for a myope.
    cylinder_diopters : float, optional
        Cylinder, D, either sign (default 0); `minus_cylinder` and `plus_cylinder`
        give the two transposed forms.
    axis_deg : float, optional
        Cylinder axis, degrees, TABO (0-180, stored in (0, 180]; 180 when the cylinder is 0).

    Examples
    --------
    >>> import vissim
    >>> rx = vissim.Prescription(-2.0, -1.25, 180)
    >>> str(rx), rx.spherical_equivalent_diopters
    ('-2.00 -1.25 x 180', -2.625)
    >>> [round(p, 4) + 0.0 for p in rx.power_vector()]  # M, J0, J45 in D
    [-2.625, 0.625, 0.0]
    """

    def refractive_error(self) -> RefractiveError:
        """The eye's excess power that this lens corrects (opposite sign)."""
        return RefractiveError(-self.sphere_diopters, -self.cylinder_diopters, self.axis_deg)


@dataclass(frozen=True)
class RefractiveError(SpheroCylinder):
    """The eye's excess dioptric power at its principal plane; a myope's sphere is > 0."""

    def prescription(self) -> Prescription:
        """The correcting lens at the principal plane (opposite sign)."""
        return Prescription(-self.sphere_diopters, -self.cylinder_diopters, self.axis_deg)


@dataclass(frozen=True)
class LensPower(SpheroCylinder):
    """Power of a lens, or the power a lens adds at a plane; a plus lens is > 0."""

    def prescription_of_camera(self) -> Prescription:
        """A perfect camera with this much power added needs the opposite lens to see sharply."""
        return Prescription(-self.sphere_diopters, -self.cylinder_diopters, self.axis_deg)


def as_prescription(value) -> Prescription:
    """``value``, which must be a `Prescription` (a `RefractiveError` has the opposite sign)."""
    if isinstance(value, RefractiveError):
        raise VissimTypeError("got the eye's RefractiveError where its Prescription (correcting lens) is expected; "
                        "convert explicitly with .prescription()")
    if not isinstance(value, Prescription):
        hint = "; read written notation with vissim.Prescription.parse(text)" if isinstance(value, str) else ""
        raise VissimTypeError(f"expected a Prescription (the correcting lens), got {describe(value)}{hint}")
    return value


def prescription_from(value) -> Prescription:
    """A `Prescription`, or its written notation (`Prescription.parse`), as the eye functions take ``rx``."""
    return Prescription.parse(value) if isinstance(value, str) else as_prescription(value)


def parse_spherocylinder(text: str) -> tuple[float, float, float]:
    """Parse the notations people write into ``(sphere_D, cylinder_D, axis_deg)``.

    Accepted: ``-2.00 -1.25 x 180``, ``-2.00/-1.25x180``, ``+1.50 DS``, ``plano -0.75 x 90``,
    ``+0.50 +1.00 x 90``, ``-2.00 DS -1.25 DC x 180``, ``+2.00 DC x 90`` (a pure cylinder),
    ``plano``; ``x``, ``×`` or ``@`` before the axis; any spacing.

    Parameters
    ----------
    text : str
        A sphero-cylinder as written on a prescription: sphere and cylinder in dioptres, axis in
        degrees (TABO, 0-180).

    Returns
    -------
    sphere_diopters, cylinder_diopters, axis_deg : float
        As written: the cylinder's sign is kept (no transposition); the axis is 180 when none is
        given (a sphere, or a cylinder written without one).

    Raises
    ------
    VissimInputError
        Text that is not a prescription (the message names what is wrong), an axis outside
        0-180 degrees or a power beyond the library's limit.

    See Also
    --------
    Prescription.parse : the same text into a `Prescription`.

    Examples
    --------
    >>> import vissim
    >>> vissim.parse_spherocylinder("-2.00 -1.25 x 180")
    (-2.0, -1.25, 180.0)
    >>> vissim.parse_spherocylinder("+1.50 DS")
    (1.5, 0.0, 180.0)
    >>> vissim.parse_spherocylinder("plano -0.75 @ 90")
    (0.0, -0.75, 90.0)
    """
    if not isinstance(text, str):
        raise VissimTypeError(f"a prescription must be text such as '-2.00 -1.25 x 180', got {describe(text)}")
    cleaned = re.sub(r"(?i)(?<=\d)\s*ds\b", " DS", text.strip())
    match = _RX_RE.match(cleaned)
    if match is None:
        raise VissimInputError(_explain_bad_rx(text))
    if match.group("cylonly") is not None:
        sphere, cyl, axis_text = 0.0, float(match.group("cylonly")), match.group("axisonly")
    else:
        sphere_text = match.group("sphere")
        sphere = 0.0 if sphere_text.lower() in ("plano", "pl") else float(sphere_text)
        cyl_text, axis_text = match.group("cyl"), match.group("axis")
        cyl = float(cyl_text) if cyl_text is not None else 0.0
    axis = float(axis_text) if axis_text is not None else 180.0
    if not 0.0 <= axis <= 180.0:
        raise VissimInputError(f"axis {axis:g} deg in {text!r} is outside 0-180 degrees (TABO)")
    if max(abs(sphere), abs(cyl)) > MAX_POWER_DIOPTERS:
        raise VissimInputError(f"prescription {text!r} exceeds +-{MAX_POWER_DIOPTERS:g} dioptres")
    return sphere, cyl, axis


def _explain_bad_rx(text: str) -> str:
    example = "e.g. '-2.00 -1.25 x 180', '+1.50 DS' or 'plano -0.75 x 90'"
    if re.search(r"[x×@]\s*$", text.strip(), re.IGNORECASE):
        return f"prescription {text!r} has an 'x' but no axis in degrees ({example})"
    if re.fullmatch(rf"\s*(?:{_NUMBER}|plano|pl)\s*(?:ds)?\s*/?\s*{_NUMBER}\s*(?:dc)?\s*", text, re.IGNORECASE):
        return f"prescription {text!r} has a cylinder but no axis in degrees ({example})"
    return f"cannot read prescription {text!r}: expected sphere [cylinder x axis] in dioptres/degrees ({example})"
