"""Point-spread functions from the pupil function, alias-safe at any angular sampling.

`compute` holds `compute_psf`, `PSF` and `strehl_ratio` (wave or geometric optics); `wave` the
pupil's Fourier transform by matrix products or one FFT; `field_size` how large a field a PSF
needs (blur radius, energy outside the field); `metrics` what a sampled PSF gives: OTF, MTF,
encircled energy. Importing this package imports none of its modules.
"""
