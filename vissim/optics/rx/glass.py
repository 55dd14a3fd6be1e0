"""Dispersion of the trial lenses' glass: a two-term Cauchy fit to n_d and the Abbe number.

Spectacle crown (white ophthalmic crown glass): ``n_d = 1.523`` at the helium d line and Abbe
number ``V_d = 58.6``, the values ophthalmic-lens tables give for
standard crown (e.g. Jalie, *The Principles of Ophthalmic Lenses*; Schott's B 270 spectacle
crown is of this type).  ``V_d = (n_d - 1) / (n_F - n_C)`` with the Fraunhofer lines below.

The fit ``n(λ) = A + B / λ²`` passes through ``n_d`` at the d line and has ``n_F - n_C = (n_d - 1)
/ V_d`` exactly.  It is written ``n_d + B (1/λ² - 1/λ_d²)`` so that the d line returns ``n_d``
bit for bit: the bench's lenses are built with the fixed index 1.523
(`vissim.optics.rx.trial_lens.CROWN_GLASS_INDEX`, also Mitsuba's ``int_ior``), so a trace at
`D_LINE_NM` reproduces the render's glass exactly.  How good two Cauchy terms are: the same
fit to Schott N-BK7's n_d and V_d departs from its catalogue Sellmeier formula by at most 1.3e-4
in index over 400-700 nm (most at 700 nm), i.e. 0.03 % of the power of a lens.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vissim.checks import finite_number
from vissim.errors import VissimInputError
from vissim.optics.rx.conventions import CROWN_GLASS_INDEX

__all__ = ["D_LINE_NM", "F_LINE_NM", "C_LINE_NM", "CROWN_ABBE_NUMBER", "CauchyGlass", "SPECTACLE_CROWN",
           "crown_index", "glass_like_crown"]

#: Helium d, hydrogen F and C lines, nm (the reference wavelengths of n_d and V_d; ISO 7944).
D_LINE_NM = 587.5618
F_LINE_NM = 486.1327
C_LINE_NM = 656.2725
#: Abbe number V_d of spectacle crown (ophthalmic crown tables).
CROWN_ABBE_NUMBER = 58.6


@dataclass(frozen=True)
class CauchyGlass:
    """A glass of index ``n_d`` at the d line and Abbe number ``abbe_number``, as ``A + B/λ²`` (module doc)."""

    n_d: float
    abbe_number: float

    def __post_init__(self) -> None:
        n_d = finite_number(self.n_d, "refractive index n_d", "(dimensionless)")
        abbe = finite_number(self.abbe_number, "Abbe number", "(dimensionless)")
        if n_d <= 1.0:
            raise VissimInputError(f"refractive index n_d must exceed 1, got {n_d:g}")
        if abbe <= 0.0:
            raise VissimInputError(f"Abbe number must be > 0, got {abbe:g}")
        object.__setattr__(self, "n_d", n_d)
        object.__setattr__(self, "abbe_number", abbe)

    @property
    def b_nm2(self) -> float:
        """Cauchy B in nm²: ``(n_d - 1) / V_d / (1/λ_F² - 1/λ_C²)``."""
        return (self.n_d - 1.0) / self.abbe_number / (F_LINE_NM**-2 - C_LINE_NM**-2)

    @property
    def a(self) -> float:
        """Cauchy A (dimensionless): ``n_d - B / λ_d²``."""
        return self.n_d - self.b_nm2 / D_LINE_NM**2

    def index(self, wavelength_nm: float) -> float:
        """Refractive index at ``wavelength_nm`` (in air; exactly ``n_d`` at `D_LINE_NM`)."""
        wavelength = finite_number(wavelength_nm, "wavelength", "nm")
        if not 200.0 <= wavelength <= 2500.0:
            raise VissimInputError(f"wavelength must be within 200-2500 nm for a glass index, got {wavelength:g} nm")
        if wavelength == D_LINE_NM:
            return self.n_d
        return self.index_unchecked(wavelength)

    def index_unchecked(self, wavelength_nm):
        """`index` without its checks, for arrays of any kind (NumPy, Dr.Jit): the one Cauchy formula."""
        return self.n_d + self.b_nm2 * (wavelength_nm**-2 - D_LINE_NM**-2)


#: The bench's glass: spectacle crown at the bench's fixed index.
SPECTACLE_CROWN = CauchyGlass(CROWN_GLASS_INDEX, CROWN_ABBE_NUMBER)


def crown_index(wavelength_nm: float) -> float:
    """Index of spectacle crown (n_d 1.523, V_d 58.6) at ``wavelength_nm``; 1.523 at the d line."""
    return SPECTACLE_CROWN.index(wavelength_nm)


def glass_like_crown(n_d: float) -> CauchyGlass:
    """A glass of index ``n_d`` with crown's Abbe number: the dispersion assumed for a lens of another index."""
    if not math.isfinite(float(n_d)):
        raise VissimInputError(f"refractive index n_d must be finite, got {n_d!r}")
    return CauchyGlass(float(n_d), CROWN_ABBE_NUMBER)
