"""The optics chain: prescription -> wavefront -> PSF -> image.

* `prescription`: spectacle prescriptions, refractive errors, power vectors.
* `zernike`, `wavefront`: OSA Zernike wavefronts over a pupil.
* `trial_lens`: trial lenses in front of a camera or an eye (ray-transfer matrices).
* `raytrace`: the exact real-ray trace (conics, biconics, GRIN, aiming) for lenses and eyes.
* `chromatic`, `accommodation`: the eye's LCA and focus.
* `psf`, `psf_metrics`: PSF, OTF/MTF, Strehl.
* `eyes/`: schematic eyes (Navarro, Escudero-Sanz, Arizona, Le Grand, Liou–Brennan), their
  media's dispersion and their paraxial optics.
* `blur`, `depth` (with `pullpush`):
  images blurred in linear light, at one depth or many.

Nothing here imports Mitsuba, the bench or the validation harness.
"""
