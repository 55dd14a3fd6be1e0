"""Depth scenes: letter charts at several distances and a tilted chart, seen by an eye or the DSLR.

`scene` places the panels, `viewers` says who looks (an eye or the DSLR camera), `textures`
prints the charts, `scene_dict` builds the Mitsuba scene dict and `scene_files` reads the
TOML scene files.
"""
