"""vissim: simulate and validate how refractive errors blur what an eye or a camera sees.

The names a user needs are importable from here; each loads its module on first use, so
``import vissim`` stays light and never imports Mitsuba (only rendering does).

* Prescriptions and wavefronts: `Prescription`, `parse_spherocylinder`,
  `Wavefront`.
* Spectra: `eye_spectral_wavefront` (the eye traced at each wavelength), `SpectralWavefront`,
  `named_spectrum` (e.g. the photopic V(λ) spectrum).
* Eyes: `Eye` and `build_eye` (a schematic model at its accommodation, with its pupil and the
  prescription it has); `eye_wavefront` (an eye's traced wavefront); `blur_eye` (an image seen by an
  eye, its PSF varying over the field).
* PSFs and their metrics: `compute_psf`, `PSF`, `strehl_ratio`,
  `mtf`, `otf`, `diffraction_mtf`, `frequencies_cyc_per_deg`.
* Images: `blur_image`, and scenes with depth: `blur_depth`; charts: `etdrs_chart_spec`, `single_letter_spec`,
  `render_chart_angular`, `render_chart_print`.
* Rendering the bench with Mitsuba (imported only when a render runs): `DslrBench`,
  `render_bench`.
* Fitting a prescription to a capture: `fit_rx`, `RxFit`.
* Validation campaigns: `load_campaign`, `run_campaign`.
* ATV data: `load_subject`, `load_directory`, `analyse_subject`,
  `fit_quadratic`.
"""

import importlib as _importlib
import logging as _logging

__version__ = "0.1.0"

_logging.getLogger(__name__).addHandler(_logging.NullHandler())

#: Public name -> the module that defines it (loaded on first access).
_PUBLIC = {
    "Prescription": "vissim.optics.rx.prescription",
    "parse_spherocylinder": "vissim.optics.rx.prescription",
    "Wavefront": "vissim.optics.pupil.wavefront",
    "Eye": "vissim.optics.eyes.eye",
    "build_eye": "vissim.optics.eyes.eye",
    "eye_wavefront": "vissim.optics.eyes.psf_wavefront",
    "eye_spectral_wavefront": "vissim.optics.eyes.psf_wavefront",
    "SpectralWavefront": "vissim.optics.pupil.spectral_wavefront",
    "named_spectrum": "vissim.spectra",
    "blur_eye": "vissim.optics.eyes.field_blur",
    "PSF": "vissim.optics.psf.compute",
    "compute_psf": "vissim.optics.psf.compute",
    "strehl_ratio": "vissim.optics.psf.compute",
    "mtf": "vissim.optics.psf.metrics",
    "otf": "vissim.optics.psf.metrics",
    "diffraction_mtf": "vissim.optics.psf.metrics",
    "frequencies_cyc_per_deg": "vissim.optics.psf.metrics",
    "blur_image": "vissim.optics.blur.convolve",
    "blur_depth": "vissim.optics.depth.depth_map",
    "etdrs_chart_spec": "vissim.charts",
    "single_letter_spec": "vissim.charts",
    "render_chart_angular": "vissim.charts",
    "render_chart_print": "vissim.charts",
    "DslrBench": "vissim.bench.dslr.bench",
    "render_bench": "vissim.render.run",
    "fit_rx": "vissim.fit.rx_fit",
    "RxFit": "vissim.fit.result",
    "load_campaign": "vissim.validation.engine.loader",
    "run_campaign": "vissim.validation.engine.runner",
    "load_subject": "vissim.atv.data",
    "load_directory": "vissim.atv.data",
    "analyse_subject": "vissim.atv.analysis",
    "fit_quadratic": "vissim.atv.analysis",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'vissim' has no attribute {name!r}")
    value = getattr(_importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    """The public names only (``__all__``), not the helpers this module imports."""
    return sorted(__all__)
