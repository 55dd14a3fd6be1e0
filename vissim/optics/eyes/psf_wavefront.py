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

Piston is dropped (it moves nothing); tilt is kept, so the PSF's origin is the chief ray's image
point (the centre of the reference sphere the OPD is taken against).
"""

from __future__ import annotations

from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.wavefront import DEFAULT_SAMPLES, trace_eye_wavefront
from vissim.optics.prescription import Prescription, as_prescription
from vissim.optics.wavefront import Wavefront

__all__ = ["eye_wavefront"]


def eye_wavefront(model: str, *, pupil_mm: float, wavelength_nm: float, rx=None, field_deg=(0.0, 0.0),
                  accommodation_diopters: float = 0.0, samples: int = DEFAULT_SAMPLES) -> Wavefront:
    """The wavefront (µm, OSA Zernikes over the ``pupil_mm`` entrance pupil) of the schematic eye
    ``model`` (a key of `models.EYE_MODELS`) with the prescription ``rx`` (a `Prescription` or its
    text; the correcting lens, as for the reduced eye) added (module doc).

    Examples
    --------
    >>> front = eye_wavefront("navarro-1985", pupil_mm=3.0, wavelength_nm=589.3, rx="-1.00")
    >>> front.pupil_diameter_mm
    3.0
    """
    eye = eye_model(model, accommodation_diopters)
    traced = trace_eye_wavefront(eye, wavelength_nm, field_deg, pupil_mm=pupil_mm, samples=samples)
    own = {key: value for key, value in traced.zernike_um.items() if key != (0, 0)}
    front = Wavefront(own, traced.entrance_pupil_mm)
    if rx is not None:
        rx = Prescription.parse(rx) if isinstance(rx, str) else as_prescription(rx)
        front = front + Wavefront.from_prescription(rx, front.pupil_diameter_mm)
    return front
