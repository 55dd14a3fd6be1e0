"""Trial lenses as geometry, shared by the DSLR, eye and ATV benches.

`mesh` writes their surfaces as PLY meshes with exact normals (what Mitsuba renders); `trace`
traces rays through the same analytic surfaces exactly, for optical path lengths; `holder` says
where the DSLR and eye benches place them, how wide and thick they are and how they enter a scene.
"""
