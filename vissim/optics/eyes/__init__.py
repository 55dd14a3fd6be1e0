"""Schematic eyes: surface tables with their media's dispersion, paraxial optics, ametropia and the traced wavefront.

* `media`: n(λ) of each model's media (Navarro 1985, Arizona, Le Grand, Liou–Brennan), with sources.
* `models`: `SchematicEye` tables and their builders; `EYE_MODELS` by command-line name.
* `paraxial`: ray-transfer matrices: power, f′, entrance pupil, refraction, retinal scale, LCA.
* `ametropia`: the eye that has a spectacle prescription (axial length, toric cornea front), in closed form.
* `spectacles`: trial and spectacle lenses before an eye, and the refraction that remains.
* `surfaces`: a model as surfaces of the exact trace (`vissim.optics.raytrace`), in the eye's frame.
* `wavefront`: the traced wavefront over the entrance pupil at a field point and a wavelength.
* `retina_map`: where a visual direction's chief ray lands on the retina, r(θ): the eye sensor's film
  map, read by the render and the eye bench's ray self-check alike.
* `refraction`: paraxial and minimum-RMS refraction from that wavefront, at the cornea or a spectacle plane.
* `psf_wavefront`: `eye_wavefront`, the traced eye's Zernikes with a prescription's added over the
  entrance pupil: what ``vissim psf --eye-model`` computes its PSF from.
* `lca`: the longitudinal chromatic aberration curve, traced, beside the paraxial one, Thibos's
  chromatic eye and Atchison & Smith 2005.
* `report`: one eye's record at a field point and a wavelength (``vissim eye``): power, pupils,
  Zernikes, refraction and MTF, with an optional prescription and lenses in front.
"""
