"""Prescription recovery: the refraction a capture shows, fitted with the Fourier model.

* :mod:`vissim.fit.forward` -- the forward model: a sharp reference blurred by the geometric
  (analytic) or wave PSF of a 2 x 2 defocus matrix, magnified and shifted; one FFT of the
  reference, reused for every evaluation.
* :mod:`vissim.fit.power_model` -- how the fitted power vector sets the defocus and the
  magnification: tied to a trial lens on the bench, a free magnification, or none.
* :mod:`vissim.fit.rx_fit` -- the fit itself (:func:`~vissim.fit.rx_fit.fit_rx`): input checks,
  multi-started least squares in power vectors, the sign and axis decisions, 95 % intervals,
  and the result record (:class:`~vissim.fit.rx_fit.RxFit`, ``as_json()``).
"""
