"""Trial lenses as geometry, shared by the DSLR and ATV benches.

`mesh` writes their surfaces as PLY meshes with exact normals (what Mitsuba renders); `trace`
traces rays through the same analytic surfaces exactly, for optical path lengths.
"""
