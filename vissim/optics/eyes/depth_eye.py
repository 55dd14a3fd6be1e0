"""A schematic eye for the depth blurs (`vissim.optics.depth.blur_depth`): one field point, the traced eye.

`traced_depth_eye` builds the `vissim.optics.setup.Eye` that the depth blur sees every depth
through: the prescription ``rx`` (the eye's correcting lens, not worn, as for the reduced eye),
the traced eye (`eye_wavefront` at the field point, the wavelength and the accommodation: its
spherical aberration, its own defocus at that wavelength and its accommodation) as the Eye's
``extra_wavefront``, and the Eye's own accommodation 0.

Why 0: a schematic eye's accommodation is physical, in its traced wavefront (the lens changes
shape), so it is already in the extra terms; the Eye then finds what the viewer focuses by its one
rule, ``in_focus_proximity_diopters = A - M`` with A = 0 and M the spherical equivalent of the
whole wavefront (rx + the traced eye), and each depth adds its defocus to that wavefront as for
the reduced eye. A second accommodation in the Eye would count it twice.
"""

from __future__ import annotations

from vissim.optics.eyes.psf_wavefront import eye_wavefront
from vissim.optics.prescription import prescription_from
from vissim.optics.setup import Eye

__all__ = ["traced_depth_eye"]


def traced_depth_eye(model: str, rx, *, pupil_mm: float, wavelength_nm: float, accommodation_diopters: float = 0.0,
                     field_deg=(0.0, 0.0)) -> Eye:
    """The `Eye` of the schematic eye ``model`` with prescription ``rx`` (a `Prescription` or its text), accommodated
    ``accommodation_diopters`` (within the model's range), at one field point ``field_deg`` (module doc)."""
    prescription = prescription_from(rx)
    traced = eye_wavefront(model, pupil_mm=pupil_mm, wavelength_nm=wavelength_nm, field_deg=field_deg,
                           accommodation_diopters=accommodation_diopters)
    return Eye(prescription, traced.pupil_diameter_mm, 0.0, extra_wavefront=traced)
