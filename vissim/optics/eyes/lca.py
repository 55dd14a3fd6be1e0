"""The longitudinal chromatic aberration (LCA) curve of a schematic eye, traced, beside two human references.

The LCA is the chromatic difference of refraction: the eye's refraction at the corneal vertex at
each wavelength minus that at a reference wavelength (by default the model's own), in dioptres, as
a far point's vergence (the correcting lens's sign): negative in the blue, where the eye is myopic.
Four columns, each referred to the same wavelength:

* **traced** (``traced_diopters``): the **paraxial** refraction of the traced wavefront
  (`refraction.eye_refraction`: the wavefront's curvature at the pupil centre, every Zernike
  order's ρ² term) over the entrance pupil given (`LCA_PUPIL_MM`, 1 mm, unless one is given), at the
  field point given (default 0, 0); ``traced_minimum_rms_diopters`` is the minimum-RMS one
  (second-order Zernikes only) over the same pupil, which spherical aberration moves with the pupil.
  The iris is fixed across wavelengths: a given entrance pupil is converted to the iris once, at
  the reference wavelength, by real rays (`traced_wavefront.iris_from_entrance_pupil_mm`).
* **paraxial** (``paraxial_diopters``): the y-nu matrices of `paraxial.refraction_diopters`,
  separate code from the real-ray trace (its oracle on axis for a centred eye).
* **Thibos** (``thibos_diopters``): the "chromatic eye", Thibos, Ye, Zhang & Bradley 1992, Appl.
  Opt. 31:3594, Eq. 5 (`vissim.optics.rx.chromatic`).
* **Atchison & Smith 2005** (``atchison_smith_diopters``): their Cauchy fit to the human eye's
  measured LCA, JOSA A 22:29-37, Eq. 5, R(λ) = 1.60911 − 6.70941×10⁵/λ² + 5.55334×10¹⁰/λ⁴ −
  5.59998×10¹⁵/λ⁶, λ in nm (`ATCHISON_SMITH_2005_EQ5`; as quoted, "Equation 5 from Atchison &
  Smith 2005", in a public AOSLO wavelength script). It is ≈ 0 near 590 nm and −1.673 D at 405.7 nm,
  where the reference page's point digitised from their Fig. 1 reads −1.68.

The schematic eyes are not tuned to either reference; the differences are reported as they come.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.checks import ATCHISON_SMITH_RANGE_NM
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.rx.chromatic import chromatic_difference_of_refraction_diopters
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.paraxial import refraction_diopters
from vissim.optics.eyes.refraction import eye_refraction
from vissim.spectra import SPECTRUM_STEP_NM, named_spectrum
from vissim.optics.eyes.traced_wavefront import iris_from_entrance_pupil_mm, trace_eye_wavefront

__all__ = ["LCA_WAVELENGTHS_NM", "LCA_STEP_NM", "LCA_PUPIL_MM", "LCA_SAMPLES", "ATCHISON_SMITH_2005_EQ5",
           "atchison_smith_2005_diopters", "LcaRow", "LcaCurve", "lca_curve"]

#: The curve's wavelengths: the sampled spectra's (`vissim.spectra`: 400-700 nm in steps of `LCA_STEP_NM`).
LCA_STEP_NM = SPECTRUM_STEP_NM
LCA_WAVELENGTHS_NM = named_spectrum("equal-energy")[0]
#: The entrance pupil the traced curve is read over when none is given, mm: small, so that the
#: minimum-RMS refraction is close to the paraxial one too.
LCA_PUPIL_MM = 1.0
#: Samples across the iris for each wavelength's trace (the refraction moves < 1e-9 D from 17 to 65).
LCA_SAMPLES = 17
#: Atchison & Smith 2005, Eq. 5: R(λ) = a0 + a2/λ² + a4/λ⁴ + a6/λ⁶, D, λ in nm.
ATCHISON_SMITH_2005_EQ5 = (1.60911, -6.70941e5, 5.55334e10, -5.59998e15)


def _atchison_smith(wavelength_nm: float) -> float:
    w = checked_wavelength_nm(wavelength_nm)
    low, high = ATCHISON_SMITH_RANGE_NM
    if not low <= w <= high:
        raise VissimInputError(f"wavelength {w:g} nm is outside the {low:g}-{high:g} nm of Atchison & Smith's fit")
    a0, a2, a4, a6 = ATCHISON_SMITH_2005_EQ5
    return a0 + a2 / w ** 2 + a4 / w ** 4 + a6 / w ** 6


def atchison_smith_2005_diopters(wavelength_nm: float, reference_nm: float) -> float:
    """Atchison & Smith's (2005, Eq. 5) chromatic difference of refraction at ``wavelength_nm``
    relative to ``reference_nm``, D (negative in the blue)."""
    return _atchison_smith(wavelength_nm) - _atchison_smith(reference_nm)


@dataclass(frozen=True)
class LcaRow:
    """One wavelength of the curve, each column re the curve's reference wavelength, D (module doc)."""

    wavelength_nm: float
    traced_diopters: float
    traced_minimum_rms_diopters: float
    paraxial_diopters: float
    thibos_diopters: float
    atchison_smith_diopters: float


@dataclass(frozen=True)
class LcaCurve:
    """An eye's LCA curve (module doc): ``rows`` over ``reference_nm``; the traced columns over an
    entrance pupil ``entrance_pupil_mm`` across (at the reference wavelength) behind an iris ``iris_mm``,
    at ``field_deg``."""

    model: str
    reference_nm: float
    entrance_pupil_mm: float
    iris_mm: float
    pupil_given: str
    field_deg: tuple[float, float]
    rows: tuple[LcaRow, ...]

    def as_json(self) -> dict:
        """``reference_wavelength_nm``, the pupil and field, what each column is, and ``rows``: one
        object per wavelength with the `LcaRow` fields."""
        return {"reference_wavelength_nm": self.reference_nm,
                "pupil": {"entrance_pupil_mm": self.entrance_pupil_mm, "iris_mm": self.iris_mm,
                          "given": self.pupil_given},
                "field_deg": list(self.field_deg),
                "refraction_plane": "corneal vertex",
                "columns": {"traced_diopters": "paraxial refraction of the traced wavefront over the pupil",
                            "traced_minimum_rms_diopters": "minimum-RMS refraction of the traced wavefront over "
                                                           "the pupil",
                            "paraxial_diopters": "paraxial (y-nu) refraction on axis",
                            "thibos_diopters": "Thibos et al. 1992 chromatic eye",
                            "atchison_smith_diopters": "Atchison & Smith 2005, JOSA A 22:29, Eq. 5"},
                "rows": [{"wavelength_nm": r.wavelength_nm, "traced_diopters": r.traced_diopters,
                          "traced_minimum_rms_diopters": r.traced_minimum_rms_diopters,
                          "paraxial_diopters": r.paraxial_diopters, "thibos_diopters": r.thibos_diopters,
                          "atchison_smith_diopters": r.atchison_smith_diopters} for r in self.rows]}


def _traced_m(eye: SchematicEye, wavelength_nm: float, field_deg, iris_mm: float) -> tuple[float, float, float]:
    """(paraxial M, minimum-RMS M, the entrance pupil's diameter), D, D, mm: traced at one wavelength."""
    wavefront = trace_eye_wavefront(eye, wavelength_nm, field_deg, iris_mm=iris_mm, samples=LCA_SAMPLES)
    refraction = eye_refraction(wavefront)
    return (refraction.paraxial.power_vector()[0], refraction.minimum_rms.power_vector()[0],
            float(wavefront.entrance_pupil_mm))


def lca_curve(eye: SchematicEye, wavelengths_nm=LCA_WAVELENGTHS_NM, *, pupil_mm=None, iris_mm=None,
              reference_nm=None, field_deg=(0.0, 0.0)) -> LcaCurve:
    """The `LcaCurve` of ``eye`` at ``wavelengths_nm`` re ``reference_nm`` (default the model's
    reference wavelength). Give the entrance pupil ``pupil_mm`` or the iris ``iris_mm``, or neither
    (`LCA_PUPIL_MM` entrance pupil)."""
    reference = eye.reference_wavelength_nm if reference_nm is None else checked_wavelength_nm(reference_nm)
    wavelengths = [checked_wavelength_nm(w) for w in np.atleast_1d(wavelengths_nm)]
    if pupil_mm is None and iris_mm is None:
        pupil_mm = LCA_PUPIL_MM
    if iris_mm is None:
        iris, given = iris_from_entrance_pupil_mm(eye, float(pupil_mm), reference), "entrance pupil"
    else:
        iris, given = float(iris_mm), "iris"
    field = tuple(float(v) for v in field_deg)
    traced_ref, rms_ref, pupil_ref = _traced_m(eye, reference, field, iris)
    paraxial_ref = refraction_diopters(eye, reference)
    rows = []
    for w in wavelengths:
        traced, rms, _ = _traced_m(eye, w, field, iris)
        rows.append(LcaRow(w, traced - traced_ref, rms - rms_ref, float(refraction_diopters(eye, w) - paraxial_ref),
                           chromatic_difference_of_refraction_diopters(w, reference),
                           atchison_smith_2005_diopters(w, reference)))
    return LcaCurve(eye.name, reference, pupil_ref, iris, given, field, tuple(rows))
