"""The DSLR bench of thesis section 4.4: a camera focused on a chart through trial lenses.

`bench` holds its geometry and Mitsuba scene dict, `scene_files` its TOML scene files,
`traced_wavefront` the wavefront its lenses add (exact trace) and `wave_truth` the chart
imaged through that wavefront by wave optics.
"""
