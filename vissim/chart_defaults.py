"""The charts' defaults, readable without NumPy (the command line's help shows them): what `vissim.charts`
draws unless told otherwise."""

from __future__ import annotations

__all__ = ["POLARITIES", "DEFAULT_LETTER_SEED", "MM_PER_INCH", "PAPER_REFLECTANCE", "INK_REFLECTANCE",
           "DEMO_PRESCRIPTIONS"]

POLARITIES = ("black-on-white", "white-on-black")
DEFAULT_LETTER_SEED = 2015
MM_PER_INCH = 25.4

#: Linear reflectances of laser-printed paper and toner ink (the charts' defaults).
PAPER_REFLECTANCE = 0.9
INK_REFLECTANCE = 0.04

#: The demonstration's two eyes (`vissim.chart_demo`): its chart blurred through each of these errors.
DEMO_PRESCRIPTIONS = {"myopia": "-2.00 DS", "astigmatism": "-2.00 DC x 90"}
