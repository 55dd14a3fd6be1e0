"""Scene builders for the virtual optical benches: plain dicts and meshes, no Mitsuba import.

One subpackage per bench -- `dslr` (the thesis's camera bench), `atv` (the ATV tube) and
`depth` (charts at several distances) -- over `lenses` (the trial lenses' meshes and exact
trace, shared by the DSLR and the ATV) and `scene_toml` (every bench's scene-file checks).
"""
