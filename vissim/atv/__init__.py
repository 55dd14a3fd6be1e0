"""The absolute threshold for vision (thesis Ch. 5, Appendix A).

* `vissim.atv.data` -- participant data files (one JSON per subject): loading, and the
  recomputation of the thesis's own summary numbers (records in `vissim.atv.records`,
  schema parsing in `vissim.atv.schema`).
* `vissim.atv.analysis` -- quadratic fit of minimum visible vs trial-lens power, its
  confidence band, the vertex and its confidence interval (Fieller, delta method).
* `vissim.atv.report` -- thesis-style figures and the Markdown/HTML report.
* `vissim.atv.procedure` -- the two-phase threshold procedure (Listing 5.1) against an
  `Observer`, and a simulated (psychometric) observer.
* `vissim.atv.interactive` -- a person as the observer: a one-pixel window or a prompt.
* `vissim.atv.virtual` -- a virtual subject in the ATV tube: Fourier retinal image of one
  phone pixel, detection by spatial summation, the whole experiment simulated.

Intensities are display code values in [0, 1] (``*_code``), as in the thesis; ERRATA item 9:
they are not photometric, so the virtual experiment converts them through a display gamma.
"""
