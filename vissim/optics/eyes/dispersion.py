"""Dispersion of the schematic eyes' media: n(λ) for each model's formula, each with its source.

A `Medium` is plain data: a formula name, its coefficients and the source they come from;
`Medium.index(wavelength_nm)` evaluates it. A `GrinMedium` (Liou–Brennan's lens halves) holds
a polynomial n(z, r) at its reference wavelength and a dispersion shift added to it everywhere.

Formulas (λ_nm in nanometres, λ_um in micrometres):

* ``navarro-1985`` (Navarro, Santamaría & Bescós 1985, JOSA A 2:1273, eq. 5 and Table 3):
  n(λ) = a1·n(365) + a2·n_F + a3·n_C + a4·n(1014), a_i = A_i + B_i λ² + C_i/(λ² − λ0²) +
  D_i/(λ² − λ0²)², λ in µm, λ0² = 0.028. The paper's table has two misprints: B1 printed as
  −0.040352796 and A4 as +1.75835059. We read B1 = −0.40352796 and A4 = −1.75835059 because only
  then do the four weights sum to 1 at every wavelength (ΣA = 1, ΣB = ΣC = ΣD = 0 to 2e−7), so that
  a medium with one index at all four lines has that index everywhere, and a_i(λ_j) = δ_ij at
  the four reference lines (an interpolation formula); ISET3d, SpikeFinder and visisipy use the
  same reading. The lens n_F is 1.42625 (ISET3d ``navarroRefractiveIndices.m``), not 1.4263:
  with it the formula gives visisipy's lens 1.4222 at 543 nm and 1.42 at 589.3 nm to 4 decimals.
  The cornea: these four lines give 1.3760 at 589.3 nm (visisipy's 1.376). The 1985 model
  table's cornea index is printed 1.367, which we read as a transposition of 1.376, the value its
  own dispersion gives; a MATLAB model instead puts 1.3771 (Le Grand's cornea) there. Neither
  number is an input here: the cornea's index at any λ comes from the four lines above.
* ``arizona`` (Schwiegerling, *Field Guide to Visual and Ophthalmic Optics*, SPIE 2004, via the
  FRED/ISET3d Arizona files): linear in λ through n_d and the Abbe number V_d,
  n(λ) = n_d + (λ_nm − 589.3)(n_d − 1)/(V_d (486.1 − 656.3)).
* ``le-grand`` (ISET3d ``legrandRefractiveIndices``): n(λ) = n∞ + K/(λ_nm − 130).
* ``liou-brennan`` (Liou & Brennan 1997, JOSA A 14:1684; as coded in SpikeFinder
  ``LiouBrennanRefractiveIndices.cs``, whose later group-index step is not taken):
  n(λ) = n_555 + 0.0512 − 0.1455 λ_um + 0.0961 λ_um², the same shift for every medium.

  **Its LCA is small, and that is the formula's.** The same Δn(λ) in every medium leaves every
  internal index step, and so every internal surface's power, unchanged: only the air–cornea
  step and the media's reduced lengths t/n change with λ, and the eye's refraction changes by
  about Δn (1/r_cornea − 1/axial length), a reduced eye of the cornea's radius. From 450 to 650 nm
  Δn = 0.00796 and that is 0.69 D (traced: 0.687 D; 1.03 D from 400 to 700 nm), against 1.23–1.28 D
  measured (Thibos et al. 1992; Atchison & Smith 2005) and 1.05–1.35 D in the other models here.
  The formula is kept as the public code gives it; the paper's dispersion section is not in a
  stored source (only its first page is), so whether Liou & Brennan apply it this way is
  unconfirmed (docs/conventions.md, Dispersion).
"""

from __future__ import annotations

from dataclasses import dataclass

from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError

__all__ = ["Medium", "GrinMedium", "AIR", "NAVARRO_COEFFICIENTS", "NAVARRO_LINES_UM",
           "navarro_medium", "arizona_medium", "le_grand_medium", "liou_brennan_medium",
           "liou_brennan_shift", "FORMULAS"]

#: Navarro 1985 Table 3: rows i = 1..4 of (A_i, B_i, C_i, D_i), misprints read as the module says.
NAVARRO_COEFFICIENTS = (
    (0.66147196, -0.40352796, -0.28046790, 0.03385979),
    (-4.20146383, 2.73508956, 1.50543784, -0.11593235),
    (6.29834237, -4.69409935, -1.57508650, 0.10293038),
    (-1.75835059, 2.36253794, 0.35011657, -0.02085782),
)
#: The four lines of Navarro's reference indices, µm: 365 nm, F (486.1), C (656.3), 1014 nm.
NAVARRO_LINES_UM = (0.365, 0.4861, 0.6563, 1.014)
_NAVARRO_LAMBDA0_SQ_UM2 = 0.028


def _navarro(coefficients: tuple[float, ...], wavelength_nm: float) -> float:
    lam2 = (wavelength_nm * 1e-3) ** 2
    x = lam2 - _NAVARRO_LAMBDA0_SQ_UM2
    weights = (a + b * lam2 + c / x + d / x ** 2 for a, b, c, d in NAVARRO_COEFFICIENTS)
    return sum(w * n for w, n in zip(weights, coefficients))


def _arizona(coefficients: tuple[float, ...], wavelength_nm: float) -> float:
    n_d, v_d = coefficients
    return n_d + (wavelength_nm - 589.3) * (n_d - 1.0) / (v_d * (486.1 - 656.3))


def _le_grand(coefficients: tuple[float, ...], wavelength_nm: float) -> float:
    n_inf, k_nm = coefficients
    return n_inf + k_nm / (wavelength_nm - 130.0)


def liou_brennan_shift(wavelength_nm: float) -> float:
    """Liou–Brennan's n(λ) − n_555, the same for every medium of that eye. Taken literally, it is
    4.9e-5 (not 0) at 555 nm, the rounding of its coefficients; we keep the formula as printed."""
    lam = wavelength_nm * 1e-3
    return 0.0512 - 0.1455 * lam + 0.0961 * lam ** 2


def _liou_brennan(coefficients: tuple[float, ...], wavelength_nm: float) -> float:
    return coefficients[0] + liou_brennan_shift(wavelength_nm)


def _constant(coefficients: tuple[float, ...], wavelength_nm: float) -> float:
    return coefficients[0]


#: Formula name -> n(coefficients, λ_nm).
FORMULAS = {"navarro-1985": _navarro, "arizona": _arizona, "le-grand": _le_grand,
            "liou-brennan": _liou_brennan, "constant": _constant}


@dataclass(frozen=True)
class Medium:
    """A homogeneous medium: ``formula`` (a key of `FORMULAS`) with its ``coefficients``.

    ``coefficients``: navarro-1985, the indices at 365, 486.1, 656.3 and 1014 nm; arizona,
    (n_d, V_d); le-grand, (n∞, K in nm); liou-brennan, (n at 555 nm,); constant, (n,).
    """

    name: str
    formula: str
    coefficients: tuple[float, ...]
    source: str = ""

    def index(self, wavelength_nm: float) -> float:
        """The refractive index at ``wavelength_nm``."""
        return FORMULAS[self.formula](self.coefficients, checked_wavelength_nm(wavelength_nm))


@dataclass(frozen=True)
class GrinMedium:
    """A gradient-index lens segment: n(z, r) = Σ_k z_coefficients[k]·z^k + r2_coefficient·r², plus
    ``formula``'s dispersion shift (for liou-brennan, `liou_brennan_shift`) added everywhere.

    z (mm) is measured along the axis from the segment's front plane (its first vertex), r (mm)
    from the axis; the polynomial is the index at ``reference_wavelength_nm``.
    """

    name: str
    z_coefficients: tuple[float, ...]
    r2_coefficient: float
    reference_wavelength_nm: float
    formula: str = "liou-brennan"
    source: str = ""

    def shift(self, wavelength_nm: float) -> float:
        """n(λ) − n_reference (the formula as printed), the same at every point of the segment."""
        wavelength = checked_wavelength_nm(wavelength_nm)
        if self.formula != "liou-brennan":
            raise VissimInputError(f"GRIN dispersion formula {self.formula!r} is not known")
        return liou_brennan_shift(wavelength)

    def axial_index(self, z_mm: float, wavelength_nm: float) -> float:
        """n(z, 0) at ``wavelength_nm``."""
        return sum(c * z_mm ** k for k, c in enumerate(self.z_coefficients)) + self.shift(wavelength_nm)

    def index(self, z_mm: float, r_mm: float, wavelength_nm: float) -> float:
        """n(z, r) at ``wavelength_nm``."""
        return self.axial_index(z_mm, wavelength_nm) + self.r2_coefficient * r_mm ** 2


#: Air, n = 1 at every wavelength (the object space of every eye here).
AIR = Medium("air", "constant", (1.0,), "taken as 1")

_NAVARRO_SOURCE = ("Navarro, Santamaria & Bescos 1985, JOSA A 2:1273, Table 3 reference indices "
                   "(lens n_F 1.42625 as ISET3d navarroRefractiveIndices.m)")
_NAVARRO_LINES = {
    "cornea": (1.3975, 1.3807, 1.37405, 1.3668),
    "aqueous": (1.3593, 1.3422, 1.3354, 1.3278),
    "lens": (1.4492, 1.42625, 1.4175, 1.4097),
    "vitreous": (1.3565, 1.3407, 1.3341, 1.3273),
}
_ARIZONA = {"cornea": (1.377, 57.1), "aqueous": (1.337, 61.3), "lens": (1.42, 51.9), "vitreous": (1.336, 61.1)}
_LE_GRAND = {"cornea": (1.3610, 7.4147), "aqueous": (1.3221, 7.0096), "lens": (1.3999, 9.2492),
             "vitreous": (1.3208, 6.9806)}


def _known(table: dict, medium: str, model: str) -> tuple[float, ...]:
    if medium not in table:
        raise VissimInputError(f"{model} has no medium {medium!r}; it has {', '.join(table)}")
    return table[medium]


def navarro_medium(medium: str, index_increment: float = 0.0) -> Medium:
    """Navarro 1985's ``medium`` (cornea, aqueous, lens, vitreous), ``index_increment`` added to all
    four reference indices (the accommodated lens, as ISET3d does)."""
    lines = tuple(n + index_increment for n in _known(_NAVARRO_LINES, medium, "Navarro 1985"))
    return Medium(medium, "navarro-1985", lines, _NAVARRO_SOURCE)


def arizona_medium(medium: str, n_d: float | None = None) -> Medium:
    """The Arizona eye's ``medium``; ``n_d`` replaces the table's (the accommodated lens)."""
    table_n_d, v_d = _known(_ARIZONA, medium, "the Arizona eye")
    return Medium(medium, "arizona", (table_n_d if n_d is None else n_d, v_d),
                  "Schwiegerling 2004 (Field Guide), n_d and V_d as in ISET3d arizonaRefractiveIndices.m")


def le_grand_medium(medium: str, index_increment: float = 0.0) -> Medium:
    """Le Grand's ``medium`` with ISET3d's n∞ + K/(λ − 130); ``index_increment`` is added to n∞."""
    n_inf, k_nm = _known(_LE_GRAND, medium, "the Le Grand eye")
    return Medium(medium, "le-grand", (n_inf + index_increment, k_nm),
                  "Le Grand & El Hage 1980 indices; dispersion n_inf + K/(lambda - 130) from ISET3d")


def liou_brennan_medium(medium: str, n_555: float) -> Medium:
    """A homogeneous Liou–Brennan medium of index ``n_555`` at 555 nm."""
    return Medium(medium, "liou-brennan", (n_555,), "Liou & Brennan 1997, JOSA A 14:1684 (dispersion eq.)")
