"""Prescription recovery: the refraction a capture shows, fitted with the Fourier model.

* `vissim.fit.forward` -- the forward model: a sharp reference blurred by the geometric
  (analytic) or wave PSF of a 2 x 2 defocus matrix, magnified and shifted; one FFT of the
  reference, reused for every evaluation.
* `vissim.fit.power_model` -- how the fitted power vector sets the defocus and the
  magnification: tied to a trial lens on the bench, a free magnification, or none.
* `vissim.fit.rx_fit` -- the fit itself (`fit_rx`): the method, and its stages in order.
* `vissim.fit.inputs` -- the input checks (images, sampling, pupil, modes).
* `vissim.fit.problem` -- the least-squares problem: parameters <-> model image and residual.
* `vissim.fit.stages` -- the multi-started least squares: the blur alone, each sign, the wave refinement.
* `vissim.fit.statistics` -- covariances (sandwich), the candidates' ranking, the residual.
* `vissim.fit.decisions` -- the thresholds and the sign, axis, resolution and failure decisions.
* `vissim.fit.result` -- the result record (`RxFit`, ``as_json()``) and its solutions (`Solution`).
* `vissim.fit.capture` -- a bench capture: its setup from provenance, the campaign's entry, theory beside the fit.
"""
