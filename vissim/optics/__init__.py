"""The optics chain: prescription -> wavefront -> PSF -> image.

* :mod:`~vissim.optics.prescription`: spectacle prescriptions, refractive errors, power vectors.
* :mod:`~vissim.optics.zernike`, :mod:`~vissim.optics.wavefront`: OSA Zernike wavefronts over a pupil.
* :mod:`~vissim.optics.trial_lens`: trial lenses in front of a camera or an eye (ray-transfer matrices).
* :mod:`~vissim.optics.chromatic`, :mod:`~vissim.optics.accommodation`: the eye's LCA and focus.
* :mod:`~vissim.optics.psf`, :mod:`~vissim.optics.psf_metrics`: PSF, OTF/MTF, Strehl.
* :mod:`~vissim.optics.blur`, :mod:`~vissim.optics.depth` (with :mod:`~vissim.optics.pullpush`):
  images blurred in linear light, at one depth or many.

Nothing here imports Mitsuba, the bench or the validation harness.
"""
