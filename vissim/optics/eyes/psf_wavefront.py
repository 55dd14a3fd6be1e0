"""The `Wavefront` a PSF of a schematic eye is computed from: the traced eye plus a prescription.

`eye_wavefront` is the one place that decides how ``--eye-model`` and ``--rx`` combine (in
``vissim psf`` and in the Python API):

* the eye's own aberrations: the OSA Zernikes of `wavefront.trace_eye_wavefront` (orders up to 8,
  µm) over the **entrance pupil** ``pupil_mm``, at ``wavelength_nm``, at ``field_deg`` and
  ``accommodation_diopters``: the model's spherical aberration, its dispersion (the eye's own
  defocus at that wavelength, in place of Thibos's formula) and its field dependence;
* plus the prescription's second-order Zernikes, `Wavefront.from_prescription` over the same
  entrance pupil, added to them.

Why added, and not the ametropic eye of ``vissim eye --rx`` (`ametropia.ametropic_eye`): in
``psf`` (and ``blur``) ``--rx`` is the correcting lens at the eye's principal plane
(docs/conventions.md, "Prescriptions"), the wavefront error ``Wavefront.from_prescription``
writes, for the reduced eye and the schematic eye alike. Added over the same entrance pupil, the
same ``--rx`` adds the same defocus and astigmatism whichever eye is chosen, so changing
``--eye-model`` changes only the eye's own aberrations. The ametropic eye (axial length solved at a
spectacle plane, toric cornea) is the physical eye that has the prescription; its higher-order
aberrations differ from the emmetropic model's by its longer or shorter vitreous, which this sum
leaves out. ``vissim eye --rx`` reports that eye.

Piston is dropped (it moves nothing); tilt is kept. The PSF's origin is the image point of the chief
ray at the model's reference wavelength (the centre of the reference sphere the OPD is taken against
at that wavelength): at another wavelength the front carries, as tilt, its chief ray's offset from
that point (the transverse chromatic aberration, below), so one wavelength's PSF and a spectrum's
are in one frame, and the renderer maps its film through that wavelength's chief rays too.

`eye_spectral_wavefront` traces the eye at each of several wavelengths over one entrance pupil
(``pupil_mm`` at every wavelength; the iris that gives it differs by the cornea's dispersion, 0.5 %
from 400 to 700 nm in Navarro's eye: 2.648 and 2.661 mm for a 3 mm pupil)
and returns a `SpectralWavefront`: each wavelength's front has its own defocus (the eye's traced
longitudinal chromatic aberration) and aberrations, with ``rx`` added to each as above. **Transverse
chromatic aberration**: each wavelength's chief ray (through the iris centre) lands at its own
retinal point; that point's offset from the chief ray's point at the reference wavelength (the
model's, unless given) is seen at the field angle whose reference-wavelength chief ray would land
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
`SpectralWavefront` carries the traced front's ``field_map`` (`wavefront.field_map`: 1/cos θ at θ from
the axis that plane is normal to), through which `vissim.compute_psf` draws its PSFs in visual angle;
the TCA's tilt is the slope that map sends to the chief rays' offset. `eye_wavefront` returns one
`Wavefront`, which cannot carry the map: its PSF off axis is in the slopes' angles (6 % narrower at
20°); `eye_spectral_wavefront` with one wavelength is the same front with its map.
"""

from __future__ import annotations


import numpy as np

from vissim.checks import MAX_FIELD_DEG
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.wavefront import DEFAULT_SAMPLES, EyeWavefront, trace_eye_wavefront
from vissim.optics.prescription import Prescription, prescription_from
from vissim.optics.spectral_wavefront import SpectralWavefront
from vissim.optics.wavefront import Wavefront
from vissim.units import deg_to_mrad

__all__ = ["eye_wavefront", "eye_spectral_wavefront", "traced_spectral_wavefront", "chromatic_offset_deg",
           "retinal_jacobian_mm_per_deg", "JACOBIAN_STEP_DEG"]

#: The iris grid (samples across) of a trace made only for its chief ray and pupil.
ANCHOR_SAMPLES = 9
#: Field step (deg) of the central differences that give the retina's local mm per degree.
JACOBIAN_STEP_DEG = 0.1


def eye_wavefront(model: str, *, pupil_mm: float, wavelength_nm: float, rx=None, field_deg=(0.0, 0.0),
                  accommodation_diopters: float = 0.0, samples: int = DEFAULT_SAMPLES) -> Wavefront:
    """The wavefront (µm, OSA Zernikes over the ``pupil_mm`` entrance pupil) of the schematic eye
    ``model`` (a key of `models.EYE_MODELS`) with the prescription ``rx`` (a `Prescription` or its
    text; the correcting lens, as for the reduced eye) added, its tilt placing the PSF relative to the
    chief ray's image point at the model's reference wavelength (module doc).

    Examples
    --------
    >>> front = eye_wavefront("navarro-1985", pupil_mm=3.0, wavelength_nm=589.3, rx="-1.00")
    >>> front.pupil_diameter_mm
    3.0
    """
    rx = _checked_rx(rx)  # before the traces
    eye = eye_model(model, accommodation_diopters)
    spectral = traced_spectral_wavefront(eye, [wavelength_nm], field_deg, pupil_mm=pupil_mm, samples=samples)
    return _with_rx(spectral.fronts[0], rx)


def _own_front(traced: EyeWavefront) -> Wavefront:
    """The traced Zernikes without piston, over the entrance pupil."""
    return Wavefront({key: value for key, value in traced.zernike_um.items() if key != (0, 0)},
                     traced.entrance_pupil_mm)


def _checked_rx(rx) -> Prescription | None:
    if rx is None:
        return None
    return prescription_from(rx)


def _with_rx(front: Wavefront, rx: Prescription | None) -> Wavefront:
    if rx is None:
        return front
    return front + Wavefront.from_prescription(rx, front.pupil_diameter_mm)


def retinal_jacobian_mm_per_deg(eye, wavelength_nm: float, field_deg, *, iris_mm: float,
                                lenses=None) -> np.ndarray:
    """d(chief ray's retinal point x, y, mm) / d(field angle x, y, deg) at ``field_deg``: a 2 × 2 matrix by
    central differences of ±`JACOBIAN_STEP_DEG` (one-sided at ±`MAX_FIELD_DEG`) of chief rays traced
    through the ``iris_mm`` iris (and ``lenses``) at ``wavelength_nm``. About −(mm per degree) × I near the axis."""
    columns = []
    for axis in (0, 1):
        low = max(field_deg[axis] - JACOBIAN_STEP_DEG, -MAX_FIELD_DEG)
        high = min(field_deg[axis] + JACOBIAN_STEP_DEG, MAX_FIELD_DEG)
        points = []
        for value in (low, high):
            field = [float(v) for v in field_deg]
            field[axis] = value
            traced = trace_eye_wavefront(eye, wavelength_nm, tuple(field), iris_mm=iris_mm, samples=9, max_order=2,
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


def eye_spectral_wavefront(model: str, *, pupil_mm: float, wavelengths_nm, rx=None, field_deg=(0.0, 0.0),
                           accommodation_diopters: float = 0.0, samples: int = DEFAULT_SAMPLES,
                           reference_wavelength_nm: float | None = None) -> SpectralWavefront:
    """The `SpectralWavefront` of the schematic eye ``model`` traced at each of ``wavelengths_nm`` over the
    ``pupil_mm`` entrance pupil, ``rx`` added to each, with its transverse chromatic aberration as tilt
    relative to the chief ray at ``reference_wavelength_nm`` (default: the model's) (module doc).

    Examples
    --------
    >>> s = eye_spectral_wavefront("navarro-1985", pupil_mm=3.0, wavelengths_nm=[450, 650], field_deg=(10, 0))
    >>> s.wavelengths_nm, s.reference_wavelength_nm
    ((450.0, 650.0), 589.3)
    """
    rx = _checked_rx(rx)  # before the traces
    eye = eye_model(model, accommodation_diopters)
    traced = traced_spectral_wavefront(eye, wavelengths_nm, field_deg, pupil_mm=pupil_mm, samples=samples,
                                       reference_wavelength_nm=reference_wavelength_nm)
    return traced.map(lambda front: _with_rx(front, rx))


def traced_spectral_wavefront(eye, wavelengths_nm, field_deg=(0.0, 0.0), *, pupil_mm=None, iris_mm=None,
                              lenses=None, samples: int = DEFAULT_SAMPLES,
                              reference_wavelength_nm=None) -> SpectralWavefront:
    """The `SpectralWavefront` of the `SchematicEye` ``eye`` (lenses in front, if given, as
    `trace_eye_wavefront` takes them), its TCA as tilt (module doc), field angles in front of the lenses.

    The pupil: ``pupil_mm`` (the eye's entrance pupil) at every wavelength, or, for ``iris_mm``, the
    entrance pupil it gives at the reference wavelength. With lenses in front the system's pupil may
    differ between wavelengths by their dispersion; every front is then re-expanded
    (`Wavefront.rescaled`) over the smallest.
    """
    reference = (eye.reference_wavelength_nm if reference_wavelength_nm is None
                 else checked_wavelength_nm(reference_wavelength_nm, "reference wavelength"))
    try:
        wavelengths = sorted({checked_wavelength_nm(w) for w in wavelengths_nm})
    except TypeError:
        raise VissimInputError(f"wavelengths must be a list of nm, got {wavelengths_nm!r}") from None
    if not wavelengths:
        raise VissimInputError("a spectral wavefront needs at least one wavelength, got none")
    # the reference's chief ray and pupil only, unless its front is wanted too (they do not depend on the grid)
    wanted = reference in wavelengths
    anchor = trace_eye_wavefront(eye, reference, field_deg, pupil_mm=pupil_mm, iris_mm=iris_mm,
                                 samples=samples if wanted else ANCHOR_SAMPLES, max_order=8 if wanted else 2,
                                 lenses=lenses)
    pupil = anchor.eye_entrance_pupil_mm
    traced = [anchor if w == reference else
              trace_eye_wavefront(eye, w, field_deg, pupil_mm=pupil, samples=samples, lenses=lenses)
              for w in wavelengths]
    jacobian = (None if wavelengths == [reference] else
                retinal_jacobian_mm_per_deg(eye, reference, field_deg, iris_mm=anchor.iris_mm, lenses=lenses))
    common = min(t.entrance_pupil_mm for t in traced)
    fronts = []
    for t in traced:
        front = _own_front(t)
        if t is not anchor:  # the tilt whose slope the field map sends to the chief rays' visual-angle offset
            offset_mrad = np.linalg.solve(np.asarray(anchor.field_map), deg_to_mrad(chromatic_offset_deg(t, anchor, jacobian)))
            front = front + Wavefront.tilt(offset_mrad, front.pupil_diameter_mm)
        fronts.append(front if front.pupil_diameter_mm == common else front.rescaled(common))
    field = tuple(float(v) for v in field_deg)
    return SpectralWavefront(tuple(wavelengths), tuple(fronts), reference,
                             f"{eye.name} traced at each wavelength, field ({field[0]:g}, {field[1]:g}) deg, "
                             f"accommodation {eye.accommodation_diopters:g} D; tilt: each chief ray's image point "
                             f"seen from {reference:g} nm's", anchor.field_map)
