"""The ATV tube of thesis section 5.4: one lit phone pixel seen through an 8 D lens.

`tube` holds its geometry, `paraxial` its first-order theory, `scene` its Mitsuba scene dict,
`spot` the spot metrics every ATV method reports and `scene_files` its TOML scene files.
"""
