"""Scene builders for the virtual optical benches: plain dicts and meshes, no Mitsuba import.

One subpackage per bench -- `dslr` (the thesis's camera bench), `eye` (a letter seen by a
schematic eye), `atv` (the ATV tube) and `depth` (charts at several distances) -- over `lenses`
(the trial lenses' meshes, exact trace and the holder's rules, shared by the DSLR, eye and ATV
benches), `scene_parts` (the chart, film and integrator of the DSLR and eye benches' scenes) and
`scene_toml` (every bench's scene-file checks).
"""
