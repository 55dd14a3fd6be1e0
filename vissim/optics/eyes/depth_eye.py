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

import logging

import numpy as np

from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.psf_wavefront import eye_wavefront
from vissim.optics.eyes.wavefront import field_map
from vissim.optics.prescription import prescription_from
from vissim.optics.setup import Eye

__all__ = ["traced_depth_eye"]

log = logging.getLogger(__name__)
#: A field map further than this from the identity (largest element) is warned about.
FIELD_MAP_WARN = 0.005


def traced_depth_eye(model: str, rx, *, pupil_mm: float, wavelength_nm: float, accommodation_diopters: float = 0.0,
                     field_deg=(0.0, 0.0)) -> Eye:
    """The `Eye` of the schematic eye ``model`` with prescription ``rx`` (a `Prescription` or its text), accommodated
    ``accommodation_diopters`` (within the model's range), at one field point ``field_deg`` (module doc)."""
    prescription = prescription_from(rx)
    traced = eye_wavefront(model, pupil_mm=pupil_mm, wavelength_nm=wavelength_nm, field_deg=field_deg,
                           accommodation_diopters=accommodation_diopters)
    stretch = float(np.max(np.abs(field_map(eye_model(model, accommodation_diopters), field_deg) - np.eye(2))))
    if stretch > FIELD_MAP_WARN:
        log.warning("at field (%g, %g) deg the eye's PSFs are up to %.1f %% wider than the depth blur draws them (the "
                    "oblique pupil's map to visual angle is not applied)", *field_deg, 100 * stretch)
    return Eye(prescription, traced.pupil_diameter_mm, 0.0, extra_wavefront=traced)
