"""Measurements on schematic-eye renders, each against an independent prediction:

* `focus`: chromatic focus -- the trial sphere that focuses a letter best at 450, 550 and 650 nm,
  against the eye's LCA and the crown lens's dispersion;
* `edge`: a slanted edge's MTF (ISO 12233-style) against the trace's geometric MTF;
* `wide`: a chart over 0-20° against the field-dependent blur and a single on-axis PSF.

`scenes` edits the eye render's scene (a chart of one's own, dispersive lenses) and computes the chart
as the sensor's pixels see it.  Run all three from the repository's root (``__main__``), which prints the numbers:

    PYTHONPATH=$PWD python -m scripts.eye_studies [focus] [edge] [wide]

Studies, not part of the vissim package: they use its public API and the eye render, and their
tests are tests/validation/test_eye_studies.py.
"""

from .edge import SlantedEdge, slanted_edge
from .focus import ChromaticFocus, chromatic_focus
from .wide import WideChart, wide_chart

__all__ = ["ChromaticFocus", "chromatic_focus", "SlantedEdge", "slanted_edge", "WideChart", "wide_chart"]
