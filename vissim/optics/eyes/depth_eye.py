"""A schematic eye for the depth blurs (`vissim.optics.depth.depth_map.blur_depth`): one field point, the traced eye.

`traced_depth_eye` builds the `vissim.optics.rx.viewing_setup.DepthViewer` that the depth blur sees every depth
through: the traced `Eye` (`eye_wavefront` at the field point and the wavelength: its prescription
as the ametropic eye, its spherical aberration, its own defocus at that wavelength and its
accommodation) as the viewer's ``extra_wavefront``, with no further prescription and the viewer's
own accommodation 0.

Why 0: a schematic eye's accommodation is physical, in its traced wavefront (the lens changes
shape), so it is already in the extra terms; the viewer then finds what the viewer focuses by its one
rule, ``in_focus_proximity_diopters = A - M`` with A = 0 and M the spherical equivalent of the
whole traced wavefront, and each depth adds its defocus to that wavefront as for
the reduced eye. A second accommodation in the viewer would count it twice.
"""

from __future__ import annotations

import logging

import numpy as np

from vissim.optics.eyes.eye import Eye, checked_eye
from vissim.optics.eyes.psf_wavefront import eye_wavefront
from vissim.optics.eyes.traced_wavefront import field_map
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.viewing_setup import DepthViewer

__all__ = ["traced_depth_eye"]

log = logging.getLogger(__name__)
#: A field map further than this from the identity (largest element) is warned about.
FIELD_MAP_WARN = 0.005


def traced_depth_eye(eye: Eye, *, wavelength_nm: float | None = None, field_deg=(0.0, 0.0)) -> DepthViewer:
    """The `DepthViewer` of the `Eye` ``eye`` (its prescription, accommodation and pupil) at one field point
    ``field_deg`` and ``wavelength_nm`` (default: the eye's reference wavelength) (module doc)."""
    eye = checked_eye(eye, "traced_depth_eye")
    traced = eye_wavefront(eye, wavelength_nm=wavelength_nm, field_deg=field_deg)
    stretch = float(np.max(np.abs(field_map(eye.optics, field_deg) - np.eye(2))))
    if stretch > FIELD_MAP_WARN:
        log.warning("at field (%g, %g) deg the eye's PSFs are up to %.1f %% wider than the depth blur draws them (the "
                    "oblique pupil's map to visual angle is not applied)", *field_deg, 100 * stretch)
    return DepthViewer(Prescription(0.0), traced.pupil_diameter_mm, 0.0, extra_wavefront=traced)
