"""Eyes: the `Eye` object, schematic surface tables with their media's dispersion, paraxial optics, ametropia,
the traced wavefront and what an eye sees.

* `eye`: `Eye` (a model at its accommodation, its pupil, the prescription it has, its reference
  wavelength) and `build_eye`, the one place a model's name becomes an eye; `defaults`: the eye's
  defaults, said once.

* `dispersion`: n(λ) of each model's media (Navarro 1985, Arizona, Le Grand, Liou–Brennan), with sources.
* `models`: `SchematicEye` tables and their builders; `EYE_MODELS` by command-line name.
* `paraxial`: ray-transfer matrices: power, f′, entrance pupil, refraction, retinal scale, LCA.
* `ametropia`: the eye that has a spectacle prescription (axial length, toric cornea front), in closed form;
  `fixation`: that eye corrected along its visual axis by the trace (the one callers use).
* `spectacles`: trial and spectacle lenses before an eye, and the refraction that remains.
* `surfaces`: a model as surfaces of the exact trace (`vissim.optics.raytrace`), in the eye's frame.
* `traced_wavefront`: the traced wavefront over the entrance pupil at a field point and a wavelength.
* `retina_map`: where rays land on the retina: the chief rays' r(θ) (the eye sensor's film map, read by the
  render and the ray PSF alike) and `ray_psf`, a chart point's rays through a lens and the eye, binned as the
  film sees them (the eye bench's geometric self-check).
* `refraction`: paraxial and minimum-RMS refraction from that wavefront, at the cornea or a spectacle plane.
* `psf_wavefront`: `eye_wavefront`, an `Eye`'s traced Zernikes with the light's vergence added over
  the entrance pupil: what ``vissim psf --eye-model`` computes its PSF from.
* `viewing`: `EyeView`, an eye looking at a chart through a trial lens: the lens's effect, the
  reduced and schematic setups, the chart as seen.
* `lca`: the longitudinal chromatic aberration curve, traced, beside the paraxial one, Thibos's
  chromatic eye and Atchison & Smith 2005.
* `report`: one eye's record at a field point and a wavelength (``vissim eye``): power, pupils,
  Zernikes, refraction and MTF, with an optional prescription and lenses in front.
* `simulations`: what an eye looking at a chart sees, simulated (reduced, thesis, schematic; `simulate_view`).
* `measured/`: real eyes: measured human wavefronts (Jaeken & Artal 2012, Polans et al. 2015) on a base eye.
"""
