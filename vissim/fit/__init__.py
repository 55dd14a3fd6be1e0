"""Prescription recovery: the refraction a capture shows, fitted with the Fourier model.

* `vissim.fit.forward` -- the forward model: a sharp reference blurred by the geometric
  (analytic) or wave PSF of a 2 x 2 defocus matrix, magnified and shifted; one FFT of the
  reference, reused for every evaluation.
* `vissim.fit.power_model` -- how the fitted power vector sets the defocus and the
  magnification: tied to a trial lens on the bench, a free magnification, or none.
* `vissim.fit.rx_fit` -- the fit itself (`fit_rx`): input checks,
  multi-started least squares in power vectors, the sign and axis decisions, 95 % intervals,
  and the result record (`RxFit`, ``as_json()``).
"""
