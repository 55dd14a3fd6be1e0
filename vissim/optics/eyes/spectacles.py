"""Spectacle and trial lenses in front of a schematic eye: the refraction that remains (paraxial).

**Lenses** are the DSLR bench's `vissim.optics.rx.trial_lens.TrialLens`, ordered from the object to
the eye, the last one's back vertex ``vertex_distance_mm`` in front of the corneal front vertex
(12 mm by default), touching or ``lens_gap_mm`` apart (validated as a `TrialLensSetup`):

* a thin lens (``refractive_index`` None) has its marked power at every wavelength (an ideal lens);
* a thick lens acts through its own surfaces: the front surface that gives its marked back vertex
  power, its back surface and its reduced thickness, in glass of its n_d with crown's Abbe number
  (`vissim.optics.rx.glass.glass_like_crown`, as the bench's trace `vissim.bench.lenses.trace`): at λ
  each surface's power scales by (n(λ) − 1)/(n_d − 1) and the thickness is divided by n(λ); at
  the d line it is `TrialLens.ray_transfer_matrix` exactly. The bench's step that makes thin lenses
  crown lenses of realistic thickness lives in the bench layer (`vissim.bench.lenses.mesh`); pass
  such lenses here directly.

**Residual refraction**, for an object at infinity: the correcting thin lens that remains with
these lenses worn, exactly (4 × 4 generalized paraxial matrices, `vissim.optics.eyes.ametropia`),
named by its plane:

* `SPECTACLE` (the over-refraction): a thin lens touching the front of the first lens (the
  spectacle plane itself with no lens or thin ones): B⁻¹ A of the system from that plane to the retina;
* `CORNEA` (a contact lens over the spectacles): K − L, K the eye's own corneal refraction and
  L = −C A⁻¹ the vergence the lenses give at the cornea to light from infinity.

**Traced lenses** (`lens_surfaces`): a thick lens as its two surfaces for the exact trace, in the
eye's frame (`vissim.optics.eyes.surfaces`; light along +z, the corneal vertex at 0, so the lenses
lie at z < 0): front and back curvature matrices K = F / (n_d − 1) / 1000 per mm of the bench's
`vissim.optics.rx.trial_lens.lens_surface_curvatures_per_mm` (a `MatrixSag`; x, y are the TABO frame
in both frames, so a cylinder's axis is the same), glass of the lens's n_d with crown's Abbe
number at the traced wavelength, as `vissim.bench.lenses.trace.bench_surfaces`. Thin lenses
have no surfaces: make them crown lenses of realistic thickness first (the bench's
`realistic_center_thickness_mm`, e.g. `vissim.bench.atv.tube.atv_trial_lens`). No clear aperture
is checked. `system_entrance_pupil_mm` is the iris imaged through the cornea and the lenses
(paraxial, the mean of the two principal meridians), and `system_retinal_mm_per_deg` the retinal
image per degree of field seen through the lenses (the chief ray through that pupil).

Both are negative when the eye with its lenses is myopic. Three uses, one function: an ametropic
eye uncorrected (no lens) or corrected (`spectacle_lens` of its prescription), and an emmetropic
eye with blur induced by a trial lens (the thesis's experiment on an eye).
"""

from __future__ import annotations

import math

import numpy as np

from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.ametropia import CORNEA, SPECTACLE, ParaxialRefraction, eye_ray_matrix, refraction_from_matrix
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.paraxial import matrix_to_surface, mean_meridian_eye
from vissim.optics.rx.glass import glass_like_crown
from vissim.optics.rx.prescription import Prescription, as_prescription
from vissim.optics.raytrace import MatrixSag, Surface
from vissim.optics.rx.trial_lens import (SPECTACLE_VERTEX_DISTANCE_MM, TrialLens, TrialLensSetup, lens_surface_curvatures_per_mm,
                                      refraction_matrix,
                                      transfer_matrix)
from vissim.units import mm_to_m

__all__ = ["CORNEA", "SPECTACLE", "spectacle_lens", "lens_ray_matrix", "lenses_to_cornea_matrix",
           "residual_refraction", "lens_surfaces", "system_entrance_pupil_mm", "system_retinal_mm_per_deg"]

_I2 = np.eye(2)


def spectacle_lens(rx: Prescription) -> TrialLens:
    """The thin spectacle lens of prescription ``rx`` (its power is the prescription's)."""
    rx = as_prescription(rx)
    return TrialLens(rx.sphere_diopters, rx.cylinder_diopters, rx.axis_deg)


def lens_ray_matrix(lens: TrialLens, wavelength_nm: float) -> np.ndarray:
    """4 × 4 ray matrix (m, D) of ``lens`` from its front to its back vertex at ``wavelength_nm`` (module doc)."""
    wavelength = checked_wavelength_nm(wavelength_nm)
    if lens.is_thin:
        return refraction_matrix(lens.marked_power.power_matrix())
    n_d = lens.refractive_index
    n = glass_like_crown(n_d).index(wavelength)
    scale = (n - 1.0) / (n_d - 1.0)
    front = scale * np.asarray(lens.front_surface_power_matrix())
    back = scale * lens.back_surface_diopters * _I2
    return refraction_matrix(back) @ transfer_matrix(mm_to_m(lens.center_thickness_mm) / n) @ refraction_matrix(front)


def lenses_to_cornea_matrix(setup: TrialLensSetup, wavelength_nm: float) -> np.ndarray:
    """4 × 4 ray matrix (m, D) from the first lens's front vertex to the corneal vertex (identity with no lens)."""
    system = np.eye(4)
    for position, lens in enumerate(setup.lenses):
        if position:
            system = transfer_matrix(mm_to_m(setup.lens_gap_mm)) @ system
        system = lens_ray_matrix(lens, wavelength_nm) @ system
    return transfer_matrix(mm_to_m(setup.vertex_distance_mm)) @ system


def residual_refraction(eye: SchematicEye, lenses=(), vertex_distance_mm: float = SPECTACLE_VERTEX_DISTANCE_MM, *,
                        lens_gap_mm: float = 0.0, wavelength_nm: float | None = None,
                        plane: str = SPECTACLE) -> ParaxialRefraction:
    """The refraction that remains with ``lenses`` (TrialLens, object to eye) worn in front of ``eye``,
    at ``plane`` (`SPECTACLE` or `CORNEA`, module doc), at ``wavelength_nm`` (default: the model's
    reference wavelength), for an object at infinity.

    With no lens the `SPECTACLE` refraction is the eye's at ``vertex_distance_mm`` in front of it.
    """
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else checked_wavelength_nm(wavelength_nm)
    if plane not in (SPECTACLE, CORNEA):
        raise VissimInputError(f"refraction plane must be {SPECTACLE!r} or {CORNEA!r}, got {plane!r}")
    setup = TrialLensSetup(lenses, vertex_distance_mm, math.inf, lens_gap_mm)
    front_to_cornea = lenses_to_cornea_matrix(setup, wavelength)
    eye_matrix = eye_ray_matrix(eye, wavelength)
    if plane == SPECTACLE:
        system = eye_matrix @ front_to_cornea
        residual = np.linalg.solve(system[:2, 2:], system[:2, :2])
        return refraction_from_matrix(residual, SPECTACLE, setup.vertex_distance_mm + _lens_span_mm(setup), wavelength)
    eye_k = np.linalg.solve(eye_matrix[:2, 2:], eye_matrix[:2, :2])
    a, c = front_to_cornea[:2, :2], front_to_cornea[2:, :2]
    lens_vergence = -c @ np.linalg.inv(a)
    return refraction_from_matrix(eye_k - lens_vergence, CORNEA, 0.0, wavelength)


def _lens_span_mm(setup: TrialLensSetup) -> float:
    """Lens thicknesses and gaps: from the first lens's front vertex to the last one's back vertex, mm."""
    return setup.span_mm - setup.vertex_distance_mm if setup.lenses else 0.0


def _thick(lens: TrialLens) -> TrialLens:
    if lens.is_thin:
        raise VissimInputError(f"trial lens {lens.marked_power} is thin (no index, 0 mm thick): the trace needs a "
                               "real lens; make it one of realistic centre thickness first")
    return lens


def lens_surfaces(setup: TrialLensSetup) -> tuple[Surface, ...]:
    """The lenses of ``setup`` (object to eye) as surfaces of the eye's frame, the last back vertex
    ``setup.vertex_distance_mm`` in front of the cornea (module doc)."""
    lenses = [_thick(lens) for lens in setup.lenses]
    z = -setup.vertex_distance_mm - sum(lens.center_thickness_mm for lens in lenses) - setup.lens_gap_mm * (
        len(lenses) - 1)
    surfaces = []
    for i, lens in enumerate(lenses):
        front, back = lens_surface_curvatures_per_mm(lens)
        glass = glass_like_crown(lens.refractive_index).index
        surfaces.append(Surface(MatrixSag(front), z, glass, name=f"lens {i + 1} front"))
        z += lens.center_thickness_mm
        surfaces.append(Surface(MatrixSag(back), z, 1.0, name=f"lens {i + 1} back"))
        z += setup.lens_gap_mm
    return tuple(surfaces)


def system_entrance_pupil_mm(eye: SchematicEye, setup: TrialLensSetup, wavelength_nm: float) -> tuple[float, float]:
    """(position behind the corneal vertex, paraxial magnification iris -> pupil) of the iris imaged
    through the cornea and ``setup``'s lenses, mm; the mean of the principal meridians (module doc)."""
    wavelength = checked_wavelength_nm(wavelength_nm)
    lenses = lenses_to_cornea_matrix(setup, wavelength)
    lens_scalar = _mean_meridian(lenses)
    (a, b), (c, d) = matrix_to_surface(mean_meridian_eye(eye), eye.stop_index, wavelength)
    to_stop = np.array([[a, b / 1000.0], [c * 1000.0, d]]) @ lens_scalar  # (m, D)
    a, b = to_stop[0]
    start_mm = setup.span_mm if setup.lenses else setup.vertex_distance_mm  # the matrix's first plane
    return 1000.0 * b / a - start_mm, 1.0 / a


def _mean_meridian(matrix: np.ndarray) -> np.ndarray:
    """The 2 x 2 scalar matrix of a 4 x 4 one's mean meridian: each 2 x 2 block's half trace."""
    return np.array([[np.trace(matrix[:2, :2]), np.trace(matrix[:2, 2:])],
                     [np.trace(matrix[2:, :2]), np.trace(matrix[2:, 2:])]]) / 2.0


def system_retinal_mm_per_deg(eye: SchematicEye, setup: TrialLensSetup, wavelength_nm: float) -> float:
    """Retinal image height per degree of field in front of ``setup``'s lenses, mm: the paraxial chief
    ray through the system's entrance pupil carried to the retina's vertex plane (mean meridian)."""
    wavelength = checked_wavelength_nm(wavelength_nm)
    (a, b), _ = _mean_meridian(eye_ray_matrix(eye, wavelength) @ lenses_to_cornea_matrix(setup, wavelength))
    start_mm = setup.span_mm if setup.lenses else setup.vertex_distance_mm
    pupil_m = mm_to_m(system_entrance_pupil_mm(eye, setup, wavelength)[0] + start_mm)
    return 1000.0 * abs(b - a * pupil_m) * math.pi / 180.0
