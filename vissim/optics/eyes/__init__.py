"""Schematic eyes (issue 26): surface tables with their media's dispersion, and their paraxial optics.

* `media`: n(λ) of each model's media (Navarro 1985, Arizona, Le Grand, Liou–Brennan), with sources.
* `models`: `SchematicEye` tables and their builders; `EYE_MODELS` by command-line name.
* `paraxial`: ray-transfer matrices: power, f′, entrance pupil, refraction, retinal scale, LCA.
* `ametropia`: the eye that has a spectacle prescription (axial length, toric cornea front), in closed form.
* `spectacles`: trial and spectacle lenses before an eye, and the refraction that remains.

The real-ray trace through these surfaces lives elsewhere; this package is data and first-order optics.
"""
