"""Where a trial or spectacle lens sits and what it is made of: the numbers every command's help and every
bench share, in a module that imports nothing (a command's help reads them without loading numpy)."""

from __future__ import annotations

__all__ = ["SPECTACLE_VERTEX_DISTANCE_MM", "CORNEA_TO_ENTRANCE_PUPIL_MM", "EYE_VERTEX_DISTANCE_MM", "CROWN_GLASS_INDEX"]

#: Refractive index of ophthalmic crown glass (nd), the default for thick trial lenses.
CROWN_GLASS_INDEX = 1.523
#: An eye's trial or spectacle lens: 12 mm from the cornea (clinical practice, 12-14 mm) and the
#: entrance pupil 3 mm behind the cornea, so 15 mm from the lens's back vertex to the pupil, where
#: vissim's eye has its thin lens (docs/conventions.md, "Defaults").  A camera's default is the
#: thesis bench's measured THESIS_VERTEX_DISTANCE_MM, to its principal plane.
SPECTACLE_VERTEX_DISTANCE_MM = 12.0
CORNEA_TO_ENTRANCE_PUPIL_MM = 3.0
EYE_VERTEX_DISTANCE_MM = SPECTACLE_VERTEX_DISTANCE_MM + CORNEA_TO_ENTRANCE_PUPIL_MM
