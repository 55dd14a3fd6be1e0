"""The `Wavefront` a PSF of an `Eye` is computed from: the eye traced, and the light's vergence.

`eye_wavefront` and `eye_spectral_wavefront` take an `Eye` (`vissim.optics.eyes.eye`):

* the eye's own aberrations: the OSA Zernikes of `traced_wavefront.trace_eye_wavefront` (orders up to 8,
  µm) of the eye's optics (the ametropic eye when it has a prescription: its axial length and toric
  cornea, with the higher orders they bring) over its **entrance pupil**, at ``wavelength_nm``, at
  ``field_deg`` and its accommodation: the model's spherical aberration, its dispersion (the eye's
  own defocus at that wavelength, in place of Thibos's formula) and its field dependence;
* plus the light's vergence at the entrance pupil, ``vergence_diopters`` (V: −1/d for an object d
  metres in front of the entrance pupil, plus what lenses in front add, as `ViewingSetup`'s
  vergence), as the second-order Zernikes of an eye whose correcting lens is −V, added over the
  same pupil. Zero (the default) is a distant object seen without lenses.

Piston is dropped (it moves nothing); tilt is kept. The PSF's origin is the image point of the chief
ray at the eye's reference wavelength (the centre of the reference sphere the OPD is taken against
at that wavelength): at another wavelength the front carries, as tilt, its chief ray's offset from
that point (the transverse chromatic aberration, below), so one wavelength's PSF and a spectrum's
are in one frame, and the renderer maps its film through that wavelength's chief rays too.

`eye_spectral_wavefront` traces the eye at each of several wavelengths over one entrance pupil
(``pupil_mm`` at every wavelength; the iris that gives it differs by the cornea's dispersion, 0.5 %
from 400 to 700 nm in Navarro's eye: 2.648 and 2.661 mm for a 3 mm pupil)
and returns a `SpectralWavefront`: each wavelength's front has its own defocus (the eye's traced
longitudinal chromatic aberration) and aberrations, with the vergence added to each as above. **Transverse
chromatic aberration**: each wavelength's chief ray (through the iris centre) lands at its own
retinal point; that point's offset from the chief ray's point at the eye's reference wavelength is seen at the field angle whose reference-wavelength chief ray would land
there: the offset through the inverse of the retina's local mm per degree, the 2 × 2 derivative of
the traced chief ray's retinal point by the field angle (`retinal_jacobian_mm_per_deg`, central
differences of ±`JACOBIAN_STEP_DEG`; on axis it is the paraxial `paraxial.retinal_mm_per_deg`, and
it falls off axis: 13 % lower radially at 20° in Navarro's eye). That visual angle is added to the
wavelength's front as tilt: a tilt c(1,1), c(1,−1) µm over a pupil of radius R mm moves the PSF by
+2c/R mrad along +x, +y of the visual field, OSA frame (docs/conventions.md, "Sign of the wavefront
and of the pupil phase"); the image's inversion is in the derivative (a field angle towards +x lands
towards −x). All fronts' PSFs are then centred on the reference wavelength's chief ray image point,
so a polychromatic PSF off axis shows the TCA.

**Off axis** the fronts' pupil coordinates lie in the entrance-pupil plane, oblique to the beam: the
`SpectralWavefront` carries the traced front's ``field_map`` (`traced_wavefront.field_map`: 1/cos θ at θ from
the axis that plane is normal to), through which `vissim.compute_psf` draws its PSFs in visual angle;
the TCA's tilt is the slope that map sends to the chief rays' offset. `eye_wavefront` returns one
`Wavefront`, which cannot carry the map: its PSF off axis is in the slopes' angles (6 % narrower at
20°); `eye_spectral_wavefront` with one wavelength is the same front with its map.
"""

from __future__ import annotations


import numpy as np

from vissim.checks import MAX_TRACE_FIELD_DEG
from vissim.checks import eye_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.eye import Eye, checked_eye
from vissim.optics.eyes.measured.measured_eye import beam_field_map, measured_front
from vissim.optics.eyes.refraction import BEAM_PLANE, ENTRANCE_PUPIL_PLANE, chief_ray_stretch
from vissim.optics.eyes.traced_wavefront import (CHIEF_RAY_SAMPLES, DEFAULT_SAMPLES, EyeWavefront, field_direction,
                                                trace_eye_wavefront, trace_eye_wavefronts)
from vissim.optics.rx.prescription import Prescription
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import deg_to_mrad

__all__ = ["eye_wavefront", "eye_spectral_wavefront", "vergence_front", "traced_spectral_wavefront", "chromatic_offset_deg",
           "retinal_jacobian_mm_per_deg", "JACOBIAN_STEP_DEG"]

#: Field step (deg) of the central differences that give the retina's local mm per degree.
JACOBIAN_STEP_DEG = 0.1


def eye_wavefront(eye: Eye, *, wavelength_nm: float | None = None, field_deg=(0.0, 0.0), vergence_diopters=0.0,
                  samples: int = DEFAULT_SAMPLES) -> Wavefront:
    """The wavefront (µm, OSA Zernikes over the eye's entrance pupil, at ``wavelength_nm``, default the eye's
    reference wavelength) of the `Eye` ``eye`` traced at ``field_deg``, with the light's
    ``vergence_diopters`` at the entrance pupil added (module doc), its tilt placing the PSF relative to the
    chief ray's image point at the eye's reference wavelength. The front knows its wavelength.

    Examples
    --------
    >>> from vissim.optics.eyes.eye import build_eye
    >>> front = eye_wavefront(build_eye("navarro-1985", pupil_diameter_mm=3.0, rx="-1.00"))
    >>> front.pupil_diameter_mm, front.wavelength_nm
    (3.0, 589.3)
    """
    eye = checked_eye(eye, "eye_wavefront")
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else wavelength_nm
    spectral = eye_spectral_wavefront(eye, wavelengths_nm=[wavelength], field_deg=field_deg,
                                      vergence_diopters=vergence_diopters, samples=samples)
    return spectral.fronts[0]


def _own_front(traced: EyeWavefront) -> Wavefront:
    """The traced Zernikes without piston, over the entrance pupil."""
    return Wavefront({key: value for key, value in traced.zernike_um.items() if key != (0, 0)},
                     traced.entrance_pupil_mm, traced.wavelength_nm)


def vergence_front(vergence_diopters, pupil_diameter_mm: float, beam_direction=(0.0, 0.0, 1.0), *,
                   pupil_plane: str = ENTRANCE_PUPIL_PLANE) -> Wavefront | None:
    """The wavefront error the light's vergence at the entrance pupil adds (D: a scalar, or a 2 x 2 TABO
    matrix; the object's −1/d plus what lenses in front add): that of an eye whose correcting lens is −V, V
    across the beam ``beam_direction`` (optical-axis frame). Its coordinates are the entrance-pupil plane's, which
    an oblique beam crosses stretched 1/cos θ along the field: there the curvature is S V S, S the inverse of
    `refraction.chief_ray_stretch` (cos θ along the field, 1 across), so the refraction over the pupil seen along
    the chief ray reads V back; a front over the plane normal to the beam (``pupil_plane`` `BEAM_PLANE`: a
    measured eye's) sees it unstretched, as `refraction.eye_refraction` reads such a front. None for zero vergence."""
    matrix = _vergence_matrix(vergence_diopters)
    if not np.any(matrix):
        return None
    squeeze = np.eye(2) if pupil_plane == BEAM_PLANE else np.linalg.inv(chief_ray_stretch(beam_direction))
    return Wavefront.from_prescription(Prescription.from_power_matrix(-(squeeze @ matrix @ squeeze)),
                                       pupil_diameter_mm)


def _vergence_matrix(vergence_diopters) -> np.ndarray:
    try:
        value = np.asarray(vergence_diopters, dtype=float)
    except (TypeError, ValueError):
        value = np.full(1, np.nan)
    matrix = value * np.eye(2) if value.ndim == 0 else value
    if matrix.shape != (2, 2) or not np.all(np.isfinite(matrix)) or abs(matrix[0, 1] - matrix[1, 0]) > 1e-9:
        raise VissimInputError(f"the light's vergence must be dioptres or a symmetric 2 x 2 matrix of dioptres, got "
                               f"{vergence_diopters!r}")
    return matrix


def _with_vergence(front: Wavefront, vergence: Wavefront | None) -> Wavefront:
    return front if vergence is None else front + vergence


def retinal_jacobian_mm_per_deg(eye, wavelength_nm: float, field_deg, *, iris_mm: float,
                                lenses=None) -> np.ndarray:
    """d(chief ray's retinal point x, y, mm) / d(field angle x, y, deg) at ``field_deg``: a 2 × 2 matrix by
    central differences of ±`JACOBIAN_STEP_DEG` (one-sided at ±`MAX_TRACE_FIELD_DEG`) of chief rays traced
    through the ``iris_mm`` iris (and ``lenses``) at ``wavelength_nm``. About −(mm per degree) × I near the axis."""
    columns = []
    for axis in (0, 1):
        low = max(field_deg[axis] - JACOBIAN_STEP_DEG, -MAX_TRACE_FIELD_DEG)
        high = min(field_deg[axis] + JACOBIAN_STEP_DEG, MAX_TRACE_FIELD_DEG)
        points = []
        for value in (low, high):
            field = [float(v) for v in field_deg]
            field[axis] = value
            traced = trace_eye_wavefront(eye, wavelength_nm, tuple(field), iris_mm=iris_mm, samples=CHIEF_RAY_SAMPLES, max_order=2,
                                         lenses=lenses)
            points.append(np.array(traced.image_point_mm[:2]))
        columns.append((points[1] - points[0]) / (high - low))
    return np.stack(columns, axis=1)


def chromatic_offset_deg(traced: EyeWavefront, reference: EyeWavefront, jacobian_mm_per_deg) -> tuple[float, float]:
    """The visual angle (deg, OSA x and y of the visual field) at which ``traced``'s chief ray image point is
    seen relative to ``reference``'s: their retinal offset (mm) through the inverse of the retina's local
    ``jacobian_mm_per_deg`` (`retinal_jacobian_mm_per_deg`; module doc)."""
    offset_mm = np.subtract(traced.image_point_mm[:2], reference.image_point_mm[:2])
    x, y = np.linalg.solve(np.asarray(jacobian_mm_per_deg, dtype=float), offset_mm)
    return float(x), float(y)


def eye_spectral_wavefront(eye: Eye, *, wavelengths_nm, field_deg=(0.0, 0.0), vergence_diopters=0.0,
                           samples: int = DEFAULT_SAMPLES) -> SpectralWavefront:
    """The `SpectralWavefront` of the `Eye` ``eye`` traced at each of ``wavelengths_nm`` over its entrance
    pupil, the light's ``vergence_diopters`` added to each, with its transverse chromatic aberration as tilt
    relative to the chief ray at the eye's reference wavelength (module doc).

    Examples
    --------
    >>> from vissim.optics.eyes.eye import build_eye
    >>> s = eye_spectral_wavefront(build_eye("navarro-1985", pupil_diameter_mm=3.0), wavelengths_nm=[450, 650],
    ...                            field_deg=(10, 0))
    >>> s.wavelengths_nm, s.reference_wavelength_nm
    ((450.0, 650.0), 589.3)
    """
    eye = checked_eye(eye, "eye_spectral_wavefront")
    _vergence_matrix(vergence_diopters)  # before the traces
    traced = traced_spectral_wavefront(eye.optics, wavelengths_nm, field_deg, samples=samples, measured=eye.measured,
                                       **eye.pupil)
    plane = BEAM_PLANE if eye.measured is not None else ENTRANCE_PUPIL_PLANE  # a measured front's (`measured_eye`)
    vergence = vergence_front(vergence_diopters, traced.pupil_diameter_mm, field_direction(eye.optics, field_deg),
                              pupil_plane=plane)
    return traced.map(lambda front: _with_vergence(front, vergence))


def traced_spectral_wavefront(eye, wavelengths_nm, field_deg=(0.0, 0.0), *, pupil_mm=None, iris_mm=None,
                              lenses=None, samples: int = DEFAULT_SAMPLES,
                              reference_wavelength_nm=None, measured=None) -> SpectralWavefront:
    """The `SpectralWavefront` of the `SchematicEye` ``eye`` (lenses in front, if given, as
    `trace_eye_wavefront` takes them), its TCA as tilt (module doc), field angles in front of the lenses.

    The pupil: ``pupil_mm`` (the eye's entrance pupil) at every wavelength, or, for ``iris_mm``, the
    entrance pupil it gives at the reference wavelength. With lenses in front the system's pupil may
    differ between wavelengths by their dispersion; every front is then re-expanded
    (`Wavefront.rescaled`) over the smallest. ``measured``: a `MeasuredWavefront` whose aberrations replace the
    base eye's own in every front (`vissim.optics.eyes.measured.measured_eye`).
    """
    reference = (eye.reference_wavelength_nm if reference_wavelength_nm is None
                 else eye_wavelength_nm(reference_wavelength_nm, "reference wavelength"))
    try:
        wavelengths = sorted({eye_wavelength_nm(w) for w in wavelengths_nm})
    except TypeError:
        raise VissimInputError(f"wavelengths must be a list of nm, got {wavelengths_nm!r}") from None
    if not wavelengths:
        raise VissimInputError("a spectral wavefront needs at least one wavelength, got none")
    # the reference's chief ray and pupil only, unless its front is wanted too (they do not depend on the grid)
    wanted = reference in wavelengths
    anchor = trace_eye_wavefront(eye, reference, field_deg, pupil_mm=pupil_mm, iris_mm=iris_mm,
                                 samples=samples if wanted else CHIEF_RAY_SAMPLES, max_order=8 if wanted else 2,
                                 lenses=lenses)
    others = [w for w in wavelengths if w != reference]
    others = dict(zip(others, trace_eye_wavefronts(eye, others, field_deg, pupil_mm=anchor.eye_entrance_pupil_mm,
                                                   samples=samples, lenses=lenses) if others else []))
    traced = [anchor if w == reference else others[w] for w in wavelengths]
    jacobian = (None if wavelengths == [reference] else
                retinal_jacobian_mm_per_deg(eye, reference, field_deg, iris_mm=anchor.iris_mm, lenses=lenses))
    common = min(t.entrance_pupil_mm for t in traced)
    slopes_to_angle = np.asarray(anchor.field_map) if measured is None else beam_field_map(anchor)
    fronts = []
    for t in traced:
        front = _own_front(t if measured is None else measured_front(t, measured, eye, samples=samples, traced=traced))
        if t is not anchor:  # the tilt whose slope the field map sends to the chief rays' visual-angle offset
            offset_mrad = np.linalg.solve(slopes_to_angle, deg_to_mrad(chromatic_offset_deg(t, anchor, jacobian)))
            front = front + Wavefront.tilt(offset_mrad, front.pupil_diameter_mm)
        fronts.append(front if front.pupil_diameter_mm == common else front.rescaled(common))
    field = tuple(float(v) for v in field_deg)
    return SpectralWavefront(tuple(wavelengths), tuple(fronts), reference,
                             f"{eye.name} traced at each wavelength, field ({field[0]:g}, {field[1]:g}) deg, "
                             f"accommodation {eye.accommodation_diopters:g} D; tilt: each chief ray's image point "
                             f"seen from {reference:g} nm's", tuple(tuple(float(v) for v in row) for row in slopes_to_angle))
