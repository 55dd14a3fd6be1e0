"""Measurements on schematic-eye renders, each against an independent prediction:

* `focus`: chromatic focus -- the trial sphere that focuses a letter best at 450, 550 and 650 nm,
  against the eye's LCA and the crown lens's dispersion;
* `edge`: a slanted edge's MTF (ISO 12233-style) against the trace's geometric MTF;
* `wide`: a chart over 0-20° against the field-dependent blur and a single on-axis PSF.

`scenes` edits the eye render's scene (a chart of one's own, dispersive lenses) and computes the chart
as the sensor's pixels see it.  ``scripts/eye_studies.py`` runs all three and prints the numbers.
"""

from vissim.validation.eye_studies.edge import SlantedEdge, slanted_edge
from vissim.validation.eye_studies.focus import ChromaticFocus, chromatic_focus
from vissim.validation.eye_studies.wide import WideChart, wide_chart

__all__ = ["ChromaticFocus", "chromatic_focus", "SlantedEdge", "slanted_edge", "WideChart", "wide_chart"]
