"""The eye that has a prescription along its line of sight: the closed-form ametropic eye, corrected by the trace.

`ametropia.paraxial_ametropic_eye` solves the eye's length and cornea paraxially about its optical axis.
An eye whose visual axis is not its optical axis, or whose iris is decentred (Liou–Brennan: 5°, 0.5 mm),
has a refraction of its own along the visual axis that this solve does not see (−0.008 D of M and
−0.042 D of J0 at the spectacle plane for Liou–Brennan's −1.00 DS eye). `ametropic_eye` solves such an
eye again for the target minus that residual, read by `visual_axis_refraction` (the traced wavefront
from field (0, 0) by the one refraction rule, `refraction.eye_refraction`, at the spectacle plane, as
``vissim eye --rx`` reads it back), until it is the prescription to `VISUAL_AXIS_TOL_DIOPTERS` (two or
three solves); its cornea front is then toric for a spherical prescription too. Centred eyes are
solved once (their visual-axis refraction is the paraxial one).

This module sits above the trace (`traced_wavefront`), which sits above `ametropia` (through the spectacles'
paraxial optics): the closed form and its traced correction live apart so that neither imports back.
"""

from __future__ import annotations

import numpy as np

from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.ametropia import (far_point_vergence_matrix, paraxial_ametropic_eye, solve_inputs,
                                          solved_eye, with_source)
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.refraction import eye_refraction
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.rx.prescription import Prescription
from vissim.optics.eyes.defaults import DEFAULT_SPECTACLE_VERTEX_MM

__all__ = ["ametropic_eye", "visual_axis_refraction", "VISUAL_AXIS_TOL_DIOPTERS"]

#: An eye with a visual axis is solved until its traced refraction along it is the prescription to this, D
#: (each of the power matrix's entries, at the spectacle plane), in at most this many solves.
VISUAL_AXIS_TOL_DIOPTERS = 1e-4
_VISUAL_AXIS_MAX_SOLVES = 6
#: The entrance pupil the visual-axis refraction is traced over, mm (the curvature at its centre does
#: not depend on it: Liou–Brennan's reads the same to 1e-4 D at 1, 3 and 5 mm).
_VISUAL_AXIS_PUPIL_MM = 1.0


def visual_axis_refraction(eye: SchematicEye, wavelength_nm: float | None = None,
                           vertex_distance_mm: float | None = None) -> np.ndarray:
    """The eye's refraction at the corneal vertex (or the spectacle plane ``vertex_distance_mm`` in front of it)
    along its visual axis, 2 × 2 D: the paraxial refraction of the wavefront traced from field (0, 0) through a
    1 mm entrance pupil, by the one refraction rule (module doc)."""
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else checked_wavelength_nm(wavelength_nm)
    front = trace_eye_wavefront(eye, wavelength, (0.0, 0.0), pupil_mm=_VISUAL_AXIS_PUPIL_MM)
    return np.array(eye_refraction(front, vertex_distance_mm).paraxial.power_matrix())


def _off_axis_fixation(eye: SchematicEye) -> bool:
    return eye.visual_axis_deg != 0.0 or eye.stop_decentre_nasal_mm != 0.0


def ametropic_eye(eye: SchematicEye, rx: Prescription, vertex_distance_mm: float = DEFAULT_SPECTACLE_VERTEX_MM,
                  wavelength_nm: float | None = None, *, along_visual_axis: bool = True) -> SchematicEye:
    """``eye`` made to have the spectacle prescription ``rx`` worn ``vertex_distance_mm`` in front of its corneal
    vertex, at ``wavelength_nm`` (default: the model's reference wavelength), along its visual axis (module doc);
    ``along_visual_axis`` False: the paraxial solve only (the optical axis has the prescription). Refusals as
    `ametropia.paraxial_ametropic_eye`'s."""
    if not (along_visual_axis and _off_axis_fixation(eye)):
        return paraxial_ametropic_eye(eye, rx, vertex_distance_mm, wavelength_nm)
    rx, wavelength, rx_text, target = solve_inputs(eye, rx, vertex_distance_mm, wavelength_nm)
    solved, vitreous_mm = solved_eye(eye, target, rx.axis_deg, rx.cylinder_diopters != 0.0 or eye.surfaces[0].is_toric,
                                     wavelength, rx_text)
    k, wanted = target, np.array(rx.power_matrix())
    for _ in range(_VISUAL_AXIS_MAX_SOLVES):
        read = visual_axis_refraction(solved, wavelength, vertex_distance_mm)
        if np.max(np.abs(wanted - read)) <= VISUAL_AXIS_TOL_DIOPTERS:
            return with_source(eye, solved, rx_text, wavelength, vitreous_mm,
                               "; refraction along the visual axis (traced)")
        k = k + target - far_point_vergence_matrix(Prescription.from_power_matrix(read), vertex_distance_mm)
        solved, vitreous_mm = solved_eye(eye, k, Prescription.from_power_matrix(k).axis_deg, True, wavelength, rx_text)
    raise VissimInputError(f"prescription {rx_text}: the {eye.name} eye's refraction along its visual axis did not "
                           f"settle within {VISUAL_AXIS_TOL_DIOPTERS:g} dioptres in {_VISUAL_AXIS_MAX_SOLVES} solves")
