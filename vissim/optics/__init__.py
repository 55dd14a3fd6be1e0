"""The optics chain: prescription -> pupil function -> PSF -> image, one sub-package per stage.

* `rx`: spectacle prescriptions, trial lenses and their glass, accommodation, the eye's LCA, and the
  viewing setup (what a viewer focuses, through which pupil, with which magnification).
* `pupil`: the pupil function: OSA Zernike wavefronts, OPD maps, spectral wavefronts, the pupil's
  sampling for wave and geometric optics.
* `psf`: PSFs (`psf.compute`), the wave PSF's transform, a PSF's field size, OTF/MTF and Strehl.
* `blur`: images blurred in linear light (FFT convolution, on a device, field-dependent), resampling.
* `depth`: images blurred at many depths: RGB-D scenes and layered scenes.
* `eyes`: schematic eyes (Navarro, Escudero-Sanz, Arizona, Le Grand, Liou–Brennan), their
  media's dispersion, their paraxial optics, their traced wavefronts and what they see.
* `raytrace`: the exact real-ray trace (conics, biconics, GRIN, aiming) for lenses and eyes.
* `runtime`: where the numbers are computed: the array backend (CPU or GPU), threads, scratch arrays.

Importing a stage's package imports none of its modules. Nothing here imports Mitsuba, the bench
or the validation harness.
"""
