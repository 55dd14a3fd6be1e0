"""The eye's defaults, said once: every command, render, campaign and API entry point reads them here.

``tests/test_eye_defaults.py`` finds any other literal default for these in the package.
"""

from __future__ import annotations

from vissim.optics.trial_lens import SPECTACLE_VERTEX_DISTANCE_MM

__all__ = ["DEFAULT_EYE_MODEL", "DEFAULT_EYE_PUPIL_MM", "DEFAULT_SPECTACLE_VERTEX_MM"]

#: The schematic eye used when none is named: Navarro, Santamaria & Bescos 1985.
DEFAULT_EYE_MODEL = "navarro-1985"
#: The entrance-pupil diameter (mm) of an eye whose pupil is not given: a photopic pupil, the
#: diameter of the measured human wavefronts (Jaeken & Artal 2012, Polans et al. 2015).
DEFAULT_EYE_PUPIL_MM = 4.0
#: Where a spectacle prescription is measured: this far in front of the corneal vertex, mm.
DEFAULT_SPECTACLE_VERTEX_MM = SPECTACLE_VERTEX_DISTANCE_MM
