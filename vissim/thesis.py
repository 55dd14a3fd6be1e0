"""The thesis's numbers (Krueger 2015), each with where the thesis gives it; the one place they live.

Benches, campaigns, captures, charts and the command line import them from here.  The chart
distance is also the charts' viewing distance (three feet): in metres it is
``vissim.units.mm_to_m(THESIS_CHART_DISTANCE_MM)``.
"""

__all__ = ["THESIS_FOCAL_LENGTH_MM", "THESIS_F_NUMBER", "THESIS_CHART_DISTANCE_MM", "THESIS_VERTEX_DISTANCE_MM",
           "THESIS_EYE_FOCAL_LENGTH_MM", "THESIS_TILE_SHAPE_PX"]

#: The DSLR's lens: 18 mm (sections 4.1, 4.4).
THESIS_FOCAL_LENGTH_MM = 18.0
#: Its aperture: f/5 (section 4.4).
THESIS_F_NUMBER = 5.0
#: The chart at three feet from the camera, 914.4 mm (section 4.1, Eq. 4.1).
THESIS_CHART_DISTANCE_MM = 914.4
#: The trial lenses 10 mm in front of the camera (section 4.4.1, Eq. 4.10-4.13).
THESIS_VERTEX_DISTANCE_MM = 10.0
#: The simplified eye's focal length, 18 mm / 1.333 (section 4.4, Table 4.1).
THESIS_EYE_FOCAL_LENGTH_MM = 13.5
#: The letter tiles, 113 px wide x 133 px tall at 1 arcmin/px, as (rows, cols) (docs/ERRATA.md item 8).
THESIS_TILE_SHAPE_PX = (133, 113)
