"""A measured eye as surfaces: its base eye with a phase plane that gives it the measured wavefront.

The render traces surfaces, not Zernike tables, so a measured eye (`measured_eye`) is rendered as its base
eye with a phase plane (`vissim.optics.raytrace.phase.PhasePlane`, the "Zernike phase" surface of optical
design programs) in the entrance pupil's plane, centred where the chief ray of the chart's field crosses it.
Its optical path is the difference between the measured eye's front and the base eye's own at that field,
pupil and wavelength, with OSA's sign (a path φ added makes the front −φ):

    φ(x, y) = −(W_measured − W_base)(x, y),

sampled at every traced ray of the base eye inside the entrance pupil and fitted by a polynomial in x and y
of degree `PHASE_DEGREE` (the data's orders reach 4 in Jaeken & Artal, 5 in Polans et al.; the base eye's
higher orders are smooth).  The measured front is over the beam's plane (`measured_eye` module doc); it is
read at each ray's point carried into that plane, so the plane gives the rendered eye the measured front
over its own entrance pupil.  The iris is the base eye's: its entrance pupil is a circle normal to the axis,
which the beam's plane sees foreshortened by cos θ off axis, where the simulations' pupil is the data's
circle in the beam's plane (`measured_eye` module doc): at 20° and 30° the rendered pupil is 6 % and 13 %
narrower across the field's meridian than the simulated one.  The plane is
fitted at one field (the chart's) and one wavelength and serves the whole image: a 32 arcmin image moves its
rays over the plane by less than a few micrometres.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from vissim.optics.eyes.measured.measured_eye import measured_front
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.pupil.zernike import fit_zernike_um, zernike_monomials
from vissim.optics.raytrace.phase import PhasePlane

__all__ = ["MeasuredPhase", "measured_phase_plane", "PHASE_DEGREE"]

log = logging.getLogger(__name__)

#: The phase plane's polynomial degree in x and y.
PHASE_DEGREE = 8


@dataclass(frozen=True)
class MeasuredPhase:
    """A measured eye's phase plane at ``field_deg`` and ``wavelength_nm``; ``fit_residual_um``: the RMS of the
    polynomial fit of the front difference over the entrance pupil."""

    plane: PhasePlane
    field_deg: tuple[float, float]
    wavelength_nm: float
    fit_residual_um: float

    def as_json(self) -> dict:
        return {"plane_z_mm": self.plane.vertex_z_mm, "centre_mm": list(self.plane.centre_mm),
                "radius_mm": self.plane.radius_mm, "degree": PHASE_DEGREE, "field_deg": list(self.field_deg),
                "wavelength_nm": self.wavelength_nm, "fit_residual_um": self.fit_residual_um}


def measured_phase_plane(eye, field_deg, wavelength_nm: float) -> MeasuredPhase:
    """The phase plane (module doc) of the measured `Eye` ``eye`` at the chart's ``field_deg`` (OSA, deg) in
    light of ``wavelength_nm``."""
    field = tuple(float(f) for f in field_deg)
    base = eye.optics
    trace = trace_eye_wavefront(base, float(wavelength_nm), field, pupil_mm=eye.pupil_diameter_mm, iris_mm=eye.iris_mm)
    measured = measured_front(trace, eye.measured, base, traced=(trace,))
    radius = 0.5 * trace.entrance_pupil_mm
    difference_um = -(np.asarray(measured.opd_um) - np.asarray(trace.opd_um))  # φ, µm; fitted inside the pupil
    coefficients, residual_um = fit_zernike_um(trace.x_mm, trace.y_mm, difference_um, trace.entrance_pupil_mm,
                                               PHASE_DEGREE)
    table = zernike_monomials(coefficients)  # the same polynomial in u = x / R, v = y / R
    terms = tuple((p, q, 1e-3 * float(table[p, q])) for p in range(len(table)) for q in range(len(table))
                  if p + q <= PHASE_DEGREE)
    plane = PhasePlane(trace.entrance_pupil_position_mm, tuple(trace.chief_entrance_pupil_mm), radius, terms,
                       name=f"{eye.model} phase plane")
    log.info("%s at (%g, %g) deg, %g nm: phase plane fitted to %.2g um RMS", eye.model, *field, wavelength_nm,
             residual_um)
    return MeasuredPhase(plane, field, float(wavelength_nm), residual_um)
