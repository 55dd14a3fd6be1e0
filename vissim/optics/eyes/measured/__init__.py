"""Real eyes: measured human wavefronts across the visual field (Jaeken & Artal 2012, Polans et al. 2015), as eyes.

`datasets` loads the package's data files (checked by sha256 and shape) into vissim's field convention;
`measured_eye` makes one subject's eye an `Eye` whose monochromatic wavefront is the measured one;
`phase_plane` gives the base eye a phase plane that makes its traced wavefront the measured one (how the eye
bench renders a measured eye); `population` evaluates many of them under the same conditions and summarises
the spread; `published` holds the published fits of measured human MTFs.
"""
