"""The eye's defaults, said once: every command, render, campaign and API entry point reads them here.

``tests/test_eye_defaults.py`` finds any other literal default for these in the package.
"""

from __future__ import annotations

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.optics.rx.conventions import SPECTACLE_VERTEX_DISTANCE_MM

__all__ = ["MEASURED_DATASET_NAMES", "MEASURED_EYE_SPELLING", "DEFAULT_EYE_MODEL", "DEFAULT_EYE_PUPIL_MM", "DEFAULT_SPECTACLE_VERTEX_MM", "DEFAULT_EYE_LIGHT_NM",
           "PHOTOPIC_FOCUS_NM", "PHOTOPIC_STEP_NM", "DEFAULT_CHART_DISTANCE_M", "DEFAULT_LETTER",
           "DEFAULT_LETTER_LOGMAR", "DEFAULT_EYE_ARCMIN_PER_PX", "DEFAULT_EYE_SIZE_PX",
           "POPULATION_LETTER_LOGMAR", "POPULATION_ARCMIN_PER_PX",
           "POPULATION_LETTER_SIZE_PX", "POPULATION_CORRECTIONS", "POPULATION_CORRECTION", "POPULATION_FIELD_DEG", "POPULATION_PUPILS_MM", "POPULATION_MTF_CYC_PER_DEG"]

#: The schematic eye used when none is named: Navarro, Santamaria & Bescos 1985.
DEFAULT_EYE_MODEL = "navarro-1985"
#: The entrance-pupil diameter (mm) of an eye whose pupil is not given: a photopic pupil, the
#: diameter of the measured human wavefronts (Jaeken & Artal 2012, Polans et al. 2015).
DEFAULT_EYE_PUPIL_MM = 4.0
#: Where a spectacle prescription is measured: this far in front of the corneal vertex, mm.
DEFAULT_SPECTACLE_VERTEX_MM = SPECTACLE_VERTEX_DISTANCE_MM
#: The light an eye is shown when none is named (a render, a campaign item): vissim's one default wavelength, nm.
#: The eye's own reference wavelength (its paraxial numbers, its prescription's light) is its model's.
DEFAULT_EYE_LIGHT_NM = DEFAULT_WAVELENGTH_NM
#: White light: where the reduced eye and the thesis are in focus (V(λ)'s peak), and its sampling, nm.
PHOTOPIC_FOCUS_NM, PHOTOPIC_STEP_NM = 555.0, 25.0
#: The chart: one Sloan letter, its size (a 16 arcmin letter of 3.2 arcmin strokes), its distance (m).
DEFAULT_LETTER, DEFAULT_LETTER_LOGMAR, DEFAULT_CHART_DISTANCE_M = "K", 0.5, 6.0
#: The eye's image: pixel size (arcmin) and size (rows, columns): twice the default letter.
DEFAULT_EYE_ARCMIN_PER_PX, DEFAULT_EYE_SIZE_PX = 0.5, (64, 64)
#: A population's letter: near the acuity of a good eye (6/7.5; a 6.3 arcmin letter of 1.26 arcmin strokes),
#: where eyes differ, drawn at 0.25 arcmin per pixel over 96 x 96 (24 arcmin: the letter and its blur).
POPULATION_LETTER_LOGMAR, POPULATION_ARCMIN_PER_PX, POPULATION_LETTER_SIZE_PX = 0.1, 0.25, 96
#: A population's correction states (beside spectacles given as a prescription), and its default pupils (mm:
#: the published fits' 3 and the data's 4) and MTF frequencies (cycles/deg).
POPULATION_CORRECTIONS = ("uncorrected", "sphero-cylinder", "accommodating")
#: A population's default correction (the published fits' own: best corrected) and field (the fovea).
POPULATION_CORRECTION, POPULATION_FIELD_DEG = "sphero-cylinder", (0.0, 0.0)
POPULATION_PUPILS_MM, POPULATION_MTF_CYC_PER_DEG = (3.0, 4.0), (5.0, 10.0, 20.0, 30.0)
#: How a measured eye is spelled (`vissim.optics.eyes.measured.measured_eye`), for help texts and refusals.
MEASURED_EYE_SPELLING = "jaeken-artal-2012:SUBJECT:right|left or polans-2015:SUBJECT"
#: The measured-wavefront datasets vissim ships (`vissim.optics.eyes.measured.datasets`, whose files they name).
MEASURED_DATASET_NAMES = ("jaeken-artal-2012", "polans-2015")
