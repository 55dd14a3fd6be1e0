"""Point-spread functions from wavefronts, alias-safe at any angular sampling.

Wave optics (`vissim.optics.psf.wave`): the generalised pupil ``P exp(i k W)``, sampled
as cell averages on as many cells as the wavefront's steepest slope needs, is Fourier
transformed (matrix transform or FFT, whichever is cheaper) and ``PSF = |transform|^2``
(Goodman 2005, Ch. 6), on an internal grid finer than the Nyquist interval lambda/(2D), and
then *integrated* over the requested output pixels (ERRATA item 6); the integration is exact,
done as the pixel's sinc in the Fourier domain.  ``pixel="sample"`` gives instead the
band-limited point samples, whose DFT is the OTF: the exact kernel for blurring a
*well-sampled* image (see `vissim.optics.blur.convolve`).  A blur kernel (``normalise="field"``,
unit sum over the field) whose field would leave more than
`MAX_ENERGY_OUTSIDE` of the energy outside raises
`FieldTooSmallError` with the size that would hold it, since truncating a
kernel changes the blur; a PSF image (``normalise="total"``) is computed for any field, sums to
the energy the field holds, and logs a warning beyond that fraction.  Nothing wraps around
silently.

Geometric optics: rays through a stratified pupil sample land at the visual direction given
by the wavefront slope; their histogram on the output pixels is the ray-optics PSF of the
same wavefront (no diffraction), for comparison with a ray tracer.

Orientation (``docs/conventions.md``): ``psf.data[row, col]`` is in the observer's visual
field, row 0 at the top (+y up = decreasing row), columns increasing to the observer's right;
the origin (chief ray) is at ``[N//2, N//2]``.  The OSA pupil frame has +x at the examiner's
right, i.e. the observer's left, so a pupil point (x, y) maps to image (col, row) offsets of
(-x, -y); a wavefront slope dW/dx > 0 displaces light toward the observer's *left*.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM, MAX_PSF_SIZE_PX
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import instance_of, number_array
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.errors import FieldTooSmallError, VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.psf.field_size import (
    MAX_ENERGY_OUTSIDE,
    front_at_wavelength,
    leaves_too_much_outside,
    airy_tail,
    energy_outside_field,
    geometric_blur_radius_arcmin,
    size_holding_px,
    suggested_size_px,
)
from vissim.optics.psf.wave import PsfSampling, plan_wave_psf, to_output_pixels, wave_psf
from vissim.optics.pupil.grid import generalised_pupil, opd_on_points_um, pupil_grid
from vissim.optics.pupil.rays import histogram_on_edges, landing_arcmin, ray_count, stratified_pupil_rays
from vissim.optics.blur.resample import SUBPIXELS_PER_PX
from vissim.optics.pupil.opd_map import OpdMap
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront, field_map_stretch, field_mapped, wavelengths_for
from vissim.optics.pupil.wavefront import Wavefront
from vissim.progress import Progress
from vissim.units import nm_to_mm, nm_to_um, rad_to_arcmin

scipy_fft = lazy_module("scipy.fft")

__all__ = [
    "NORMALISATIONS",
    "PIXEL_MODES",
    "PSF",
    "PsfSampling",
    "compute_psf",
    "geometric_blur_radius_arcmin",
    "psf_sampling",
    "strehl_ratio",
    "suggested_size_px",
]

log = logging.getLogger(__name__)

#: The Fourier simulator's revision: campaign item keys include it, so that results of an older
#: core are recomputed, not reused.  Change it whenever a change moves simulated numbers.
SIMULATOR_REVISION = "4 (issue 12: float32 by default; cell-averaged pupil, matrix or FFT, 1 % field rule)"
#: How output pixels relate to the continuous PSF (see `to_output_pixels`).
PIXEL_MODES = ("integrate", "sample")
#: What a PSF's ``data`` is normalised to: "field" (unit sum over the field, a blur kernel) or
#: "total" (unit total energy, so it sums to ``energy_in_field``: a PSF image).
NORMALISATIONS = ("field", "total")
#: A field is refused before computing when the plain estimate exceeds this many times `MAX_PSF_SIZE_PX`.
PLAIN_ESTIMATE_MARGIN = 1.5


@dataclass(frozen=True, eq=False)
class PSF:
    """A PSF with its sampling, origin at ``[N//2, N//2]``; ``data`` sums to `data_sum`.

    Made by `compute_psf` (or `PSF.from_array` for a kernel of your own); used by
    `vissim.blur_image` and the metrics (`vissim.mtf`, `vissim.otf`).

    Attributes
    ----------
    data : ndarray of float, shape (N, N)
        Read-only. ``[row, col]``: row 0 at the top (+y up), columns to the observer's right;
        the chief ray at ``[N//2, N//2]``; sums to 1 over the field (``normalisation="field"``)
        or to ``energy_in_field`` (``"total"``).
    arcmin_per_px : float
        Sampling, arcmin per pixel (both axes); the field is ``N * arcmin_per_px`` arcmin.
    wavelengths_nm, weights : tuple of float
        The wavelengths (nm) and their relative spectral weights (one wavelength: weight 1).
    pupil_diameter_mm : float
        The pupil the PSF was computed for, mm.
    mode : str
        ``"wave"`` (diffraction), ``"geometric"`` (ray optics) or ``"user"`` (`from_array`).
    energy_in_field : float
        Fraction of the energy through the pupil that lands inside the field (<= 1 up to the
        light the pupil sampling folds back: at most 0.2 %, ``docs/conventions.md``).
    wavefront : Wavefront, OpdMap or SpectralWavefront
        The aberration the PSF is of (a `SpectralWavefront`: one front per wavelength).
    lca_reference_nm : float or None
        In-focus wavelength of the eye's longitudinal chromatic aberration, if modelled (Thibos);
        None for a `SpectralWavefront`, whose fronts carry their own dispersion.
    sampling : tuple
        The internal pupil and field sampling per wavelength (`psf_sampling`).
    pixel : {"integrate", "sample"}
        ``"integrate"``: each value is the PSF integrated over its pixel (what a sensor
        records); ``"sample"``: point samples of the continuous PSF (a convolution kernel).
    normalisation : {"field", "total"}
        ``"field"``: ``data`` sums to 1 over the field (a blur kernel); ``"total"``: to the
        PSF's total energy, so ``data`` sums to ``energy_in_field`` (a PSF image).

    Examples
    --------
    >>> import vissim
    >>> psf = vissim.compute_psf(vissim.Wavefront.zero(3.0), arcmin_per_px=0.5, size_px=64)
    >>> psf.size_px, psf.field_arcmin, psf.pupil_diameter_mm, psf.mode
    ((64, 64), 32.0, 3.0, 'wave')
    """

    data: np.ndarray
    arcmin_per_px: float
    wavelengths_nm: tuple[float, ...]
    weights: tuple[float, ...]
    pupil_diameter_mm: float
    mode: str
    energy_in_field: float
    wavefront: Wavefront
    lca_reference_nm: float | None = None
    sampling: tuple = field(default=(), repr=False)
    pixel: str = "integrate"  # "integrate" (sensor values) or "sample" (convolution kernel)
    normalisation: str = "field"  # "field" (a kernel, unit sum) or "total" (an image, sums to energy_in_field)

    @classmethod
    def from_array(cls, data, arcmin_per_px: float, *, wavelength_nm: float = DEFAULT_WAVELENGTH_NM, pupil_diameter_mm: float = 0.0) -> PSF:
        """Wrap a user-supplied kernel (origin at ``[N//2, N//2]``), normalised to unit sum."""
        array = np.array(number_array(data, "a PSF's data", "relative energy"))
        if array.ndim != 2 or array.shape[0] != array.shape[1] or not np.all(np.isfinite(array)):
            raise VissimInputError(f"a PSF must be a finite square 2-D array, got shape {array.shape}")
        if np.any(array < 0) or array.sum() <= 0:
            raise VissimInputError("a PSF must be non-negative with a positive sum")
        step = check_arcmin_per_px(arcmin_per_px)
        array /= array.sum()
        array.setflags(write=False)
        return cls(array, step, (float(wavelength_nm),), (1.0,), float(pupil_diameter_mm), "user", 1.0,
                   Wavefront.zero(1.0), pixel="sample")

    @property
    def size_px(self) -> tuple[int, int]:
        return self.data.shape

    @property
    def field_arcmin(self) -> float:
        return self.data.shape[0] * self.arcmin_per_px

    @property
    def data_sum(self) -> float:
        """What ``data`` sums to: 1 (normalised over the field) or ``energy_in_field`` (over the total)."""
        return self.energy_in_field if self.normalisation == "total" else 1.0

    def as_json(self) -> dict:
        return {
            "arcmin_per_px": self.arcmin_per_px,
            "size_px": list(self.data.shape),
            "origin_px": [self.data.shape[0] // 2, self.data.shape[1] // 2],
            "orientation": "row 0 top (+y up), columns to the observer's right",
            "wavelengths_nm": list(self.wavelengths_nm),
            "weights": list(self.weights),
            "pupil_diameter_mm": self.pupil_diameter_mm,
            "mode": self.mode,
            "energy_in_field": self.energy_in_field,
            "lca_reference_nm": self.lca_reference_nm,
            "pixel": self.pixel,
            "normalisation": self.normalisation,
            "dtype": self.data.dtype.name,  # compute_psf: the precision of its arithmetic
            "wavefront": self.wavefront.as_json(),
            "sampling": [s.as_json() for s in self.sampling],
        }


def psf_sampling(pupil_diameter_mm: float, wavelength_nm: float, arcmin_per_px: float, size_px: int,
                 blur_radius_arcmin: float = 0.0, method: str | None = None) -> PsfSampling:
    """The internal sampling of a monochromatic wave PSF (refuses grids over the limit)."""
    return plan_wave_psf(pupil_diameter_mm, [wavelength_nm], arcmin_per_px, size_px, [blur_radius_arcmin], method)[0]


def _geometric_psf(wavefront, diameter_mm, arcmin_per_px, size_px, blur_arcmin, pixel):
    u, v = stratified_pupil_rays(ray_count(blur_arcmin / arcmin_per_px))
    col, row = landing_arcmin(wavefront, diameter_mm, u, v)
    col, row = col / arcmin_per_px, row / arcmin_per_px  # landing offsets in output pixels
    if pixel == "integrate":  # the histogram on output pixels is the exact pixel integral
        edges = np.arange(size_px + 1) - size_px // 2 - 0.5
        counts = histogram_on_edges(row, col, edges)
        return counts / len(u)
    q = SUBPIXELS_PER_PX  # band-limits the histogram (``pixel="sample"``)
    fine = q * size_px
    edges = (np.arange(fine + 1) - fine // 2 - 0.5) / q
    counts = histogram_on_edges(row, col, edges)
    return to_output_pixels(counts, size_px, q, pixel) / len(u)


def _clearly_holds(diameter_mm, wavelengths_nm, blurs_arcmin, arcmin_per_px, size_px, mode) -> bool:
    """True when no ray's Airy pattern can leave the plain estimate's margin outside the field."""
    half = (size_px - size_px // 2 - 0.5) * arcmin_per_px  # the nearer edge, for even sizes
    for w, blur in zip(wavelengths_nm, blurs_arcmin):
        margin = half - blur
        if margin <= 0:
            return False
        lambda_over_d = float(rad_to_arcmin(nm_to_mm(w) / diameter_mm))
        if mode == "wave" and airy_tail(margin / lambda_over_d) > PLAIN_ESTIMATE_MARGIN * MAX_ENERGY_OUTSIDE:
            return False
    return True


#: What `compute_psf` and `strehl_ratio` take as the aberration.
WAVEFRONT_ACCEPTED = ("a Wavefront or an OpdMap (or a SpectralWavefront), e.g. vissim.Wavefront.from_prescription("
                      "vissim.Prescription.parse('-2.00 DS'), pupil_diameter_mm=3.0)")


def _checked_front(wavefront, pupil_diameter_mm, what: str) -> float:
    """The pupil diameter (mm) a PSF or Strehl ratio of ``wavefront`` is computed over; wrong types refused."""
    instance_of(wavefront, (Wavefront, OpdMap, SpectralWavefront), f"{what}'s wavefront", WAVEFRONT_ACCEPTED)
    diameter = wavefront.pupil_diameter_mm if pupil_diameter_mm is None else check_pupil_mm(pupil_diameter_mm)
    if diameter > wavefront.pupil_diameter_mm * (1 + 1e-12):
        raise VissimInputError(
            f"pupil {diameter:g} mm is larger than the {wavefront.pupil_diameter_mm:g} mm pupil the "
            "wavefront was measured over"
        )
    return diameter


def _checked_weights(weights, wavelengths: tuple[float, ...]) -> tuple[float, ...]:
    """One non-negative relative weight per wavelength, normalised to unit sum."""
    try:
        weights_t = tuple(float(w) for w in (weights if weights is not None else [1.0] * len(wavelengths)))
    except (TypeError, ValueError):
        weights_t = ()
    if len(weights_t) != len(wavelengths) or any(not math.isfinite(w) or w < 0 for w in weights_t) or sum(weights_t) <= 0:
        raise VissimInputError(f"need one non-negative weight per wavelength, got {weights!r} for {wavelengths!r} nm")
    return tuple(w / sum(weights_t) for w in weights_t)


def _checked_size_px(size_px) -> int:
    if (isinstance(size_px, bool) or not isinstance(size_px, (int, float, np.integer, np.floating))
            or int(size_px) != size_px or not 1 <= size_px <= MAX_PSF_SIZE_PX):
        raise VissimInputError(f"PSF size must be an integer number of pixels in 1-{MAX_PSF_SIZE_PX} (or 'auto'), "
                               f"got {size_px!r}")
    return int(size_px)


def _check_options(mode, pixel, dtype, method, normalise) -> None:
    """`compute_psf`'s choices: optics, pixel, dtype, method and normalisation."""
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"PSF mode must be 'wave' or 'geometric', got {mode!r}")
    if pixel not in PIXEL_MODES:
        raise VissimInputError(f"PSF pixel must be one of {', '.join(PIXEL_MODES)}, got {pixel!r}")
    if dtype not in (np.float32, np.float64):
        raise VissimInputError(f"PSF dtype must be float32 or float64, got {dtype!r}")
    if method is not None and method not in ("mft", "fft"):
        raise VissimInputError(f"PSF method must be 'mft' or 'fft', got {method!r}")
    if normalise not in NORMALISATIONS:
        raise VissimInputError(f"PSF normalise must be one of {', '.join(NORMALISATIONS)}, got {normalise!r}")


def _accumulated_psf(fronts, wavelengths, weights, blurs, diameter: float, step: float, size_px: int, *, mode: str,
                     method, dtype, pixel: str, progress) -> tuple[np.ndarray, tuple]:
    """The weighted sum of each wavelength's PSF (not normalised), and the wave optics' samplings (() for rays)."""
    if mode != "wave":
        return sum(weight * _geometric_psf(front, diameter, step, size_px, blur, pixel)
                   for front, weight, blur in zip(fronts, weights, blurs)), ()
    try:
        samplings = plan_wave_psf(diameter, wavelengths, step, size_px, blurs, method)
    except VissimInputError as error:
        raise VissimInputError(f"{error}{_largest_term_words(fronts, wavelengths)}") from None
    log.debug("wave PSF by %s: %d^2 internal, %.0f pupil cells", samplings[0].method, samplings[0].internal_size,
              samplings[0].pupil_cells)
    return wave_psf(fronts, weights, diameter, samplings, size_px, dtype, pixel, progress), samplings


def _largest_term_words(fronts, wavelengths) -> str:
    """What in a Zernike front makes its PSF too wide to sample: its largest term, in µm and in waves."""
    terms = [(abs(v), key, v, w) for front, w in zip(fronts, wavelengths)
             for key, v in getattr(front, "coefficients_um", {}).items() if key[0] >= 2]
    if not terms:
        return ""
    _, (n, m), value, wavelength = max(terms)
    return (f" (the wavefront's largest term, Zernike {n},{m} = {value:g} µm, is {abs(value) / nm_to_um(wavelength):.3g} "
            f"waves at {wavelength:g} nm: check its coefficients and order)")


def compute_psf(
    wavefront: Wavefront,
    *,
    pupil_diameter_mm: float | None = None,
    wavelength_nm: float | Sequence[float] | None = None,
    weights: Sequence[float] | None = None,
    lca_reference_nm: float | None = None,
    arcmin_per_px: float = 0.25,
    size_px: int | str = 256,
    mode: str = "wave",
    pixel: str = "integrate",
    dtype=np.float32,
    method: str | None = None,
    normalise: str = "field",
    progress: Progress | None = None,
) -> PSF:
    """PSF of ``wavefront`` over a ``pupil_diameter_mm`` pupil (default: its measurement pupil).

    Parameters
    ----------
    wavefront : Wavefront, OpdMap or SpectralWavefront
        A Zernike `Wavefront`, a sampled
        `OpdMap` (a traced or measured OPD map), or a `SpectralWavefront` (one front per
        wavelength, e.g. a schematic eye traced at each: each wavelength's PSF is of its own front).
    pupil_diameter_mm : float, optional
        Pupil diameter in mm, at most the wavefront's measurement pupil.
    wavelength_nm : float or sequence of float, optional
        Wavelength(s) in nm: one wavelength, or several (default: a `SpectralWavefront`'s own
        wavelengths, else 550); with a `SpectralWavefront`, each must be one of its wavelengths.
    weights : sequence of float, optional
        Relative spectral weights of several wavelengths (default equal): each wavelength's PSF
        carries its weight of the total energy (inside and outside the field), and their sum is
        normalised as ``normalise`` says.
    lca_reference_nm : float, optional
        If given, add the eye's longitudinal chromatic aberration (Thibos 1992) relative to
        this wavelength: each wavelength gets its chromatic defocus.  Refused with a
        `SpectralWavefront` (its fronts have their own dispersion).
    arcmin_per_px : float
        Output sampling, arcmin per pixel (default 0.25).
    size_px : int or "auto"
        The side of the square field, pixels (default 256).  With ``normalise="field"``, a field
        that would leave more than 1 % of the energy outside raises `FieldTooSmallError` naming
        the size that holds it.  ``"auto"``: the smallest odd field that holds the wave PSF
        (`suggested_size_px`, whose estimate holds the geometric PSF of the same wavefront too).
    mode : {"wave", "geometric"}
        ``"wave"`` (diffraction) or ``"geometric"`` (ray optics of the same wavefront).
    pixel : {"integrate", "sample"}
        ``"integrate"`` (default): each value is the PSF integrated over its pixel, what a
        sensor records.  ``"sample"``: band-limited point samples, the exact kernel for
        blurring well-sampled images (see `vissim.optics.blur.convolve` for when it matters).
    dtype : numpy.float32 (default) or numpy.float64
        The arithmetic's and ``PSF.data``'s precision.  float32's round-off (1e-7 to 3e-6 of the
        peak, growing with the pupil cells) is far below the wave PSF's accuracy (2e-3 of the
        peak, ``docs/conventions.md``) and it is about twice as fast; float64 for work that differentiates PSFs numerically
        with small steps.
    method : str or None, optional
        Wave PSFs only: ``"mft"`` (matrix transform) or ``"fft"``; None (default): the cheaper,
        recorded in ``PSF.sampling``.  At suggested field sizes both give the same pixel energies to
        1e-3 of the peak.
    normalise : {"field", "total"}
        ``"field"`` (default): a blur kernel, unit sum over the field; a field leaving more than
        `MAX_ENERGY_OUTSIDE` outside is refused, because
        truncating a kernel changes the blur.  ``"total"``: a PSF image, normalised to the
        total energy through the pupil, so it sums to ``energy_in_field``; any field is
        computed, with a logged warning when more than that fraction falls outside.
    progress : callable, optional
        Wave PSFs: ``progress("wave PSF", done, total)`` after each stage (`vissim.progress`).

    Returns
    -------
    PSF
        ``data`` is a read-only ndarray of shape ``(size_px, size_px)``, summing to 1 (``"field"``)
        or to ``energy_in_field`` (``"total"``), sampled at ``arcmin_per_px`` (carried by the result).  Orientation
        (``docs/conventions.md``): ``data[row, col]`` is the observer's visual field, row 0 at
        the top (+y up is decreasing row), columns increasing to the observer's right, the
        chief ray at ``[size_px // 2, size_px // 2]``.  ``energy_in_field`` is the fraction of
        the total energy the field holds.

    Examples
    --------
    A -2.00 D myope (uncorrected) through a 3 mm pupil, at 550 nm:

    >>> import vissim
    >>> front = vissim.Wavefront.from_prescription(vissim.Prescription(-2.0), pupil_diameter_mm=3.0)
    >>> psf = vissim.compute_psf(front, arcmin_per_px=0.5, size_px=128)
    >>> psf.data.shape, round(float(psf.data.sum()), 6)
    ((128, 128), 1.0)
    """
    diameter = _checked_front(wavefront, pupil_diameter_mm, "compute_psf")
    step = check_arcmin_per_px(arcmin_per_px)
    wavelength_nm = wavelengths_for(wavefront, wavelength_nm, DEFAULT_WAVELENGTH_NM)
    if isinstance(size_px, str) and size_px == "auto":
        size_px = suggested_size_px(wavefront, step, pupil_diameter_mm=diameter, wavelength_nm=wavelength_nm,
                                    weights=weights, lca_reference_nm=lca_reference_nm)
        stretch = field_map_stretch(getattr(wavefront, "field_map", None))
        size_px = min(MAX_PSF_SIZE_PX, size_px if stretch <= 1.0 else 2 * math.ceil(stretch * size_px / 2) + 1)
    size_px = _checked_size_px(size_px)
    _check_options(mode, pixel, dtype, method, normalise)
    wavelengths = tuple(check_wavelength_nm(w) for w in np.atleast_1d(wavelength_nm))
    weights_t = _checked_weights(weights, wavelengths)
    if lca_reference_nm is not None:
        lca_reference_nm = check_wavelength_nm(lca_reference_nm, "LCA reference wavelength")
    kernel = normalise == "field"

    def too_small(outside: float) -> FieldTooSmallError:
        needed = size_holding_px(wavefront, diameter, wavelengths, weights_t, step, size_px, mode=mode,
                                 lca_reference_nm=lca_reference_nm)
        return FieldTooSmallError(
            f"a {size_px} px field at {step:g} arcmin/px ({size_px * step:g} arcmin) would leave "
            f"{100 * outside:.1f} % of the PSF's energy outside (at most {100 * MAX_ENERGY_OUTSIDE:g} %); "
            f"use a size of at least {needed} px or coarser sampling: a blur kernel is never cut "
            "(a PSF image, normalise='total', may be)"
        )

    fronts = [front_at_wavelength(wavefront, w, lca_reference_nm) for w in wavelengths]
    blurs = [geometric_blur_radius_arcmin(front, diameter) for front in fronts]
    # A kernel: refuse at once what is plainly too small (the plain estimate, with a margin); else measure.
    if kernel and not _clearly_holds(diameter, wavelengths, blurs, step, size_px, mode):
        outside = energy_outside_field(wavefront, diameter, wavelengths, weights_t, step, size_px, mode=mode,
                                       lca_reference_nm=lca_reference_nm, conservative=False)
        if outside > PLAIN_ESTIMATE_MARGIN * MAX_ENERGY_OUTSIDE:
            raise too_small(outside)
    accumulated, samplings = _accumulated_psf(fronts, wavelengths, weights_t, blurs, diameter, step, size_px,
                                              mode=mode, method=method, dtype=dtype, pixel=pixel, progress=progress)
    accumulated = field_mapped(accumulated, getattr(wavefront, "field_map", None))
    energy = float(accumulated.sum())
    if leaves_too_much_outside(energy):
        if kernel:
            raise too_small(1.0 - energy)
        log.warning("%.1f %% of the PSF's energy falls outside the %d px field (%g arcmin); the image sums to "
                    "the %.4f it holds", 100 * (1.0 - energy), size_px, size_px * step, energy)
    data = (accumulated / energy if kernel else accumulated).astype(dtype)
    data.setflags(write=False)
    return PSF(
        data=data,
        arcmin_per_px=step,
        wavelengths_nm=wavelengths,
        weights=weights_t,
        pupil_diameter_mm=diameter,
        mode=mode,
        energy_in_field=energy,
        wavefront=wavefront,
        lca_reference_nm=lca_reference_nm,
        sampling=samplings,
        pixel=pixel,
        normalisation=normalise,
    )


def strehl_ratio(wavefront: Wavefront, wavelength_nm: float | None = None, pupil_diameter_mm: float | None = None) -> float:
    """Strehl ratio |<exp(ikW)>|^2 over the pupil (cell-averaged quadrature, sampling from the slope).

    Parameters
    ----------
    wavefront : Wavefront
        The aberration (OPD in micrometres over its measurement pupil).
    wavelength_nm : float, optional
        Wavelength, nm (default: the wavefront's own, else 550).
    pupil_diameter_mm : float, optional
        Pupil diameter, mm, at most the wavefront's (default: the wavefront's pupil).

    Returns
    -------
    float
        The peak of the PSF relative to the diffraction-limited peak of the same pupil: 1 without
        aberration, ~exp(-(2 pi RMS / lambda)^2) for small ones.

    Examples
    --------
    >>> import vissim
    >>> round(vissim.strehl_ratio(vissim.Wavefront.zero(3.0)), 6)
    1.0
    >>> front = vissim.Wavefront.from_prescription(vissim.Prescription(-0.25), 3.0)
    >>> round(vissim.strehl_ratio(front), 2)
    0.39
    """
    diameter = _checked_front(wavefront, pupil_diameter_mm, "strehl_ratio")
    if isinstance(wavefront, SpectralWavefront) and wavelength_nm is None:
        raise VissimInputError("strehl_ratio of a spectral wavefront needs one of its wavelengths (wavelength_nm)")
    wavelength_nm = check_wavelength_nm(wavelengths_for(wavefront, wavelength_nm, DEFAULT_WAVELENGTH_NM))
    wavefront = front_at_wavelength(wavefront, wavelength_nm, None)  # a spectral front's own at that wavelength
    cells = max(256, psf_sampling(diameter, wavelength_nm, 1.0, 1, geometric_blur_radius_arcmin(wavefront, diameter),
                                  "mft").pupil_cells)
    grid = pupil_grid(diameter / cells, diameter)
    field_sum = generalised_pupil(grid, opd_on_points_um(grid, wavefront), wavelength_nm).sum()
    return float(abs(field_sum) ** 2 / grid.area_cells**2)
