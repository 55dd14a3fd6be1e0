"""Point-spread functions from wavefronts, alias-safe at any angular sampling.

Wave optics: the generalised pupil ``P exp(i k W)`` is Fourier transformed and
``PSF = |FFT|^2`` (Goodman 2005, Ch. 6).  The PSF is computed on an internal grid finer than
the Nyquist interval lambda/(2D) of the intensity PSF, over a field that holds the geometric
blur plus the diffraction skirt, and then *integrated* over the requested output pixels
(ERRATA item 6); the integration is exact, done as the pixel's sinc in the
Fourier domain.  ``pixel="sample"`` gives instead the band-limited point samples, whose DFT
is the OTF: the exact kernel for blurring a *well-sampled* image (see :mod:`vissim.optics.blur`).
A requested field too small for the blur raises
:class:`~vissim.errors.FieldTooSmallError`; nothing wraps around silently.

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

import functools
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.fft

from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import FieldTooSmallError, VissimInputError
from vissim.optics.chromatic import chromatic_difference_of_refraction_diopters
from vissim.optics.wavefront import Wavefront
from vissim.optics.zernike import zernike_nm
from vissim.units import arcmin_to_rad, nm_to_mm, nm_to_um, rad_to_arcmin

__all__ = [
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

#: Fewest pupil samples across the diameter (edge anti-aliased); sets a floor on the FFT field.
MIN_PUPIL_SAMPLES = 128
#: Diffraction margin (in lambda/D) kept beyond the geometric blur on each side.
SKIRT_MARGIN_LAMBDA_OVER_D = 8.0
#: How output pixels relate to the continuous PSF (see :func:`_to_output_pixels`).
PIXEL_MODES = ("integrate", "sample")
#: Largest internal FFT (complex128: 1 GiB at 8192^2).
MAX_FFT_SIZE = 8192
#: Largest PSF field, pixels.
MAX_PSF_SIZE_PX = 16384


@dataclass(frozen=True, eq=False)
class PSF:
    """A PSF with its sampling: ``data`` sums to 1 over the field, origin at ``[N//2, N//2]``."""

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

    @classmethod
    def from_array(cls, data, arcmin_per_px: float, *, wavelength_nm: float = 550.0, pupil_diameter_mm: float = 0.0) -> PSF:
        """Wrap a user-supplied kernel (origin at ``[N//2, N//2]``), normalised to unit sum."""
        array = np.array(data, dtype=float)
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
            "wavefront": self.wavefront.as_json(),
            "sampling": [s.as_json() for s in self.sampling],
        }


@dataclass(frozen=True)
class PsfSampling:
    """How one monochromatic wave PSF is sampled internally."""

    oversample: int  # q: internal samples per output pixel along each axis
    fft_size: int  # M
    pupil_step_mm: float  # dx
    internal_arcmin_per_px: float

    def as_json(self) -> dict:
        return {
            "oversample": self.oversample,
            "fft_size": self.fft_size,
            "pupil_step_mm": self.pupil_step_mm,
            "internal_arcmin_per_px": self.internal_arcmin_per_px,
        }


def _pupil_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A polar sample of the unit disc for slope maxima (deterministic)."""
    rho = np.sqrt(np.linspace(0.0, 1.0, n))
    theta = np.linspace(0.0, 2 * np.pi, 4 * n, endpoint=False)
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    return rr * np.cos(tt), rr * np.sin(tt)


def geometric_blur_radius_arcmin(wavefront: Wavefront, pupil_diameter_mm: float) -> float:
    """Largest ray deviation |grad W| over the pupil, in arcmin (tilt included)."""
    if not wavefront.coefficients_um:
        return 0.0
    return _blur_radius_cached(tuple(wavefront.coefficients_um.items()), wavefront.pupil_diameter_mm, float(pupil_diameter_mm))


@functools.lru_cache(maxsize=256)
def _blur_radius_cached(items: tuple, measured_mm: float, diameter_mm: float) -> float:
    ux, uy = _pupil_points(48)
    radius = diameter_mm / 2.0
    sx, sy = Wavefront(dict(items), measured_mm).slopes_mrad(radius * ux, radius * uy)
    return float(rad_to_arcmin(1e-3 * np.max(np.hypot(sx, sy))))


def suggested_size_px(
    wavefront: Wavefront,
    arcmin_per_px: float,
    *,
    pupil_diameter_mm: float | None = None,
    wavelength_nm: float | Sequence[float] = 550.0,
    lca_reference_nm: float | None = None,
    skirt_lambda_over_d: float = 20.0,
    minimum_px: int = 33,
) -> int:
    """An odd field size (px) holding the geometric blur plus ``skirt_lambda_over_d`` of skirt."""
    diameter = wavefront.pupil_diameter_mm if pupil_diameter_mm is None else check_pupil_mm(pupil_diameter_mm)
    step = check_arcmin_per_px(arcmin_per_px)
    radius = 0.0
    for w in np.atleast_1d(wavelength_nm):
        front = wavefront
        if lca_reference_nm is not None:
            front = wavefront.with_defocus_diopters(chromatic_difference_of_refraction_diopters(w, lca_reference_nm))
        skirt = skirt_lambda_over_d * float(rad_to_arcmin(nm_to_mm(w) / diameter))
        radius = max(radius, geometric_blur_radius_arcmin(front, diameter) + skirt)
    half = int(math.ceil(radius / step))
    return max(minimum_px, 2 * half + 1)


def psf_sampling(
    pupil_diameter_mm: float,
    wavelength_nm: float,
    arcmin_per_px: float,
    size_px: int,
    blur_radius_arcmin: float = 0.0,
) -> PsfSampling:
    """Choose the internal grid: finer than lambda/(2D), a field that holds blur and skirt."""
    wavelength_mm = nm_to_mm(wavelength_nm)
    lambda_over_d_rad = wavelength_mm / pupil_diameter_mm
    step_rad = float(arcmin_to_rad(arcmin_per_px))
    oversample = max(1, math.ceil(step_rad / (0.5 * lambda_over_d_rad) - 1e-9))
    internal_rad = step_rad / oversample
    field_rad = max(
        size_px * step_rad,
        2.0 * (float(arcmin_to_rad(blur_radius_arcmin)) + SKIRT_MARGIN_LAMBDA_OVER_D * lambda_over_d_rad),
        MIN_PUPIL_SAMPLES * lambda_over_d_rad,
    )
    fft_size = scipy.fft.next_fast_len(max(int(math.ceil(field_rad / internal_rad - 1e-9)), oversample * size_px))
    fft_size += fft_size % 2
    if fft_size > MAX_FFT_SIZE:
        raise VissimInputError(
            f"{arcmin_per_px:g} arcmin/px over {size_px} px with a {pupil_diameter_mm:g} mm pupil at "
            f"{wavelength_nm:g} nm needs a {fft_size}^2 FFT (over the {MAX_FFT_SIZE}^2 limit, "
            f"~{fft_size**2 * 24 / 2**30:.0f} GiB); use coarser sampling or a smaller field"
        )
    return PsfSampling(
        oversample=oversample,
        fft_size=fft_size,
        pupil_step_mm=wavelength_mm / (fft_size * internal_rad),
        internal_arcmin_per_px=arcmin_per_px / oversample,
    )


@functools.lru_cache(maxsize=16)
def _pupil_geometry(fft_size: int, step_mm: float, diameter_mm: float):
    """Sub-grid holding the pupil, its OSA coordinates and amplitude (cached)."""
    radius = diameter_mm / 2.0
    half = int(math.ceil(radius / step_mm)) + 1
    if half > fft_size // 2:
        raise AssertionError("pupil does not fit the FFT grid")  # pragma: no cover
    offsets = np.arange(-half, half + 1) * step_mm
    # Image-oriented pupil array (col -> observer's right, row -> down) maps to OSA (-u, -v).
    x_osa = -offsets[np.newaxis, :]
    y_osa = -offsets[:, np.newaxis]
    r = np.hypot(x_osa, y_osa)
    # Point samples of the hard-edged pupil: their DFT is the aliased Fourier transform of the
    # pupil with no attenuation.  (An anti-aliased edge would low-pass the pupil and apodise
    # the PSF: +0.5 % encircled energy at the Airy zero with 128 samples across.)
    inside = r <= radius
    amplitude = inside.astype(float)
    for array in (amplitude, inside):
        array.setflags(write=False)
    # Pupil centre at FFT index [0, 0] (negative offsets wrap): no shifts needed.
    window = np.arange(-half, half + 1) % fft_size
    window.setflags(write=False)
    return window, np.broadcast_to(x_osa, r.shape), np.broadcast_to(y_osa, r.shape), amplitude, inside


@functools.lru_cache(maxsize=256)
def _zernike_on_grid(fft_size: int, step_mm: float, diameter_mm: float, measured_mm: float, n: int, m: int):
    _, x, y, _, inside = _pupil_geometry(fft_size, step_mm, diameter_mm)
    radius = measured_mm / 2.0
    values = np.zeros(inside.shape)
    values[inside] = zernike_nm(n, m, np.hypot(x[inside], y[inside]) / radius, np.arctan2(y[inside], x[inside]))
    values.setflags(write=False)
    return values


def _opd_on_grid(wavefront: Wavefront, sampling: PsfSampling, diameter_mm: float) -> np.ndarray:
    key = (sampling.fft_size, sampling.pupil_step_mm, diameter_mm, wavefront.pupil_diameter_mm)
    _, _, _, amplitude, _ = _pupil_geometry(*key[:3])
    opd = np.zeros(amplitude.shape)
    for (n, m), value in wavefront.coefficients_um.items():
        if n > 0:  # piston changes nothing
            opd += value * _zernike_on_grid(*key, n, m)
    return opd


def _profile(cycles_per_pixel: np.ndarray, pixel: str) -> np.ndarray:
    if pixel == "integrate":  # the output pixel's box
        return np.sinc(cycles_per_pixel)
    # ideal low-pass at the output Nyquist (half weight on the Nyquist bin itself)
    magnitude = np.abs(cycles_per_pixel)
    return np.where(magnitude < 0.5 - 1e-12, 1.0, np.where(magnitude <= 0.5 + 1e-12, 0.5, 0.0))


@functools.lru_cache(maxsize=16)
def _pixel_transfer(m: int, oversample: int, dtype, pixel: str) -> np.ndarray:
    """Transfer function applied before decimation onto output pixels, rfft2 grid (cached)."""
    y = _profile(scipy.fft.fftfreq(m) * oversample, pixel)
    x = _profile(scipy.fft.rfftfreq(m) * oversample, pixel)
    transfer = (y[:, None] * x[None, :]).astype(dtype)
    transfer.setflags(write=False)
    return transfer


def _to_output_pixels(intensity: np.ndarray, size_px: int, oversample: int, pixel: str) -> np.ndarray:
    """Decimate the (Nyquist-sampled, periodic) internal PSF onto ``size_px`` output pixels.

    ``intensity`` has its origin at ``[0, 0]``; the output has it at ``[N//2, N//2]``.

    * ``pixel="integrate"``: exact integrals over the output pixels (the box applied as its sinc
      in the Fourier domain, then sampled).  What a sensor records; non-negative; unit sum.
    * ``pixel="sample"``: band-limited point samples (ideal low-pass at the output Nyquist),
      times the pixel area.  Its DFT is the OTF itself: the exact kernel for convolving a
      well-sampled, pixel-integrated image (an integrated PSF adds the pixel's box once more).
      May ring slightly negative near sharp features.
    """
    m = intensity.shape[0]
    if oversample * size_px > m:
        raise AssertionError("output field larger than the internal field")  # pragma: no cover
    spectrum = scipy.fft.rfft2(intensity, workers=-1)
    spectrum *= _pixel_transfer(m, oversample, intensity.dtype.type, pixel)
    averaged = scipy.fft.irfft2(spectrum, s=intensity.shape, workers=-1, overwrite_x=True)
    picks = ((np.arange(size_px) - size_px // 2) * oversample) % m
    return averaged[np.ix_(picks, picks)] * oversample**2


def _wave_psf(wavefront, diameter_mm, wavelength_nm, arcmin_per_px, size_px, blur_arcmin, dtype, pixel):
    sampling = psf_sampling(diameter_mm, wavelength_nm, arcmin_per_px, size_px, blur_arcmin)
    window, _, _, amplitude, _ = _pupil_geometry(sampling.fft_size, sampling.pupil_step_mm, diameter_mm)
    complex_dtype = np.complex64 if dtype == np.float32 else np.complex128
    k_per_um = 2.0 * math.pi / nm_to_um(wavelength_nm)
    pupil = np.zeros((sampling.fft_size, sampling.fft_size), dtype=complex_dtype)
    opd = _opd_on_grid(wavefront, sampling, diameter_mm)
    pupil[np.ix_(window, window)] = amplitude * np.exp(1j * k_per_um * opd)
    spectrum = scipy.fft.fft2(pupil, workers=-1, overwrite_x=True)
    intensity = np.square(spectrum.real)  # origin at [0, 0]
    intensity += np.square(spectrum.imag)
    total = sampling.fft_size**2 * float(np.sum(amplitude**2))  # Parseval
    binned = _to_output_pixels(intensity, size_px, sampling.oversample, pixel)
    if pixel == "integrate":
        binned = np.maximum(binned, 0.0)  # round-off only: integrals of an intensity are >= 0
    return binned / total, sampling


#: Sub-pixels per output pixel for band-limiting a geometric PSF (``pixel="sample"``).
GEOMETRIC_SAMPLE_OVERSAMPLE = 5


def _geometric_psf(wavefront, diameter_mm, arcmin_per_px, size_px, blur_arcmin, pixel):
    blur_px = blur_arcmin / arcmin_per_px
    covered_px = math.pi * (blur_px + 1.0) ** 2
    n_rays = int(min(4_000_000, max(250_000, 400 * covered_px)))
    n_side = int(math.ceil(math.sqrt(n_rays * 4.0 / math.pi)))
    rng = np.random.default_rng(20151218)  # fixed: the same wavefront gives the same PSF
    cells = (np.arange(n_side) + 0.5) / n_side * 2.0 - 1.0
    u, v = np.meshgrid(cells, cells)
    u = u + (rng.random(u.shape) - 0.5) * (2.0 / n_side)
    v = v + (rng.random(v.shape) - 0.5) * (2.0 / n_side)
    keep = u * u + v * v <= 1.0
    radius = diameter_mm / 2.0
    x_osa, y_osa = -u[keep] * radius, -v[keep] * radius  # image-oriented pupil -> OSA
    sx, sy = wavefront.slopes_mrad(x_osa, y_osa)
    col = rad_to_arcmin(-sx * 1e-3) / arcmin_per_px  # landing offsets in output pixels
    row = rad_to_arcmin(-sy * 1e-3) / arcmin_per_px  # dW/dy > 0 lands up (+y), i.e. at -row
    if pixel == "integrate":  # the histogram on output pixels is the exact pixel integral
        edges = np.arange(size_px + 1) - size_px // 2 - 0.5
        counts, _, _ = np.histogram2d(row, col, bins=(edges, edges))
        return counts / keep.sum(), None
    q = GEOMETRIC_SAMPLE_OVERSAMPLE
    fine = q * size_px
    edges = (np.arange(fine + 1) - fine // 2 - 0.5) / q
    counts, _, _ = np.histogram2d(row, col, bins=(edges, edges))
    return _to_output_pixels(scipy.fft.ifftshift(counts), size_px, q, pixel) / keep.sum(), None


def compute_psf(
    wavefront: Wavefront,
    *,
    pupil_diameter_mm: float | None = None,
    wavelength_nm: float | Sequence[float] = 550.0,
    weights: Sequence[float] | None = None,
    lca_reference_nm: float | None = None,
    arcmin_per_px: float = 0.25,
    size_px: int = 256,
    mode: str = "wave",
    pixel: str = "integrate",
    dtype=np.float64,
) -> PSF:
    """PSF of ``wavefront`` over a ``pupil_diameter_mm`` pupil (default: its measurement pupil).

    Parameters
    ----------
    wavelength_nm, weights
        One wavelength, or several with relative weights (polychromatic PSF = weighted sum of
        unit-sum monochromatic PSFs).
    lca_reference_nm
        If given, add the eye's longitudinal chromatic aberration (Thibos 1992) relative to
        this wavelength: each wavelength gets its chromatic defocus.
    arcmin_per_px, size_px
        Output sampling and square field (pixels).  The result is pixel-integrated.
    mode
        ``"wave"`` (diffraction) or ``"geometric"`` (ray optics of the same wavefront).
    pixel
        ``"integrate"`` (default): each value is the PSF integrated over its pixel, what a
        sensor records.  ``"sample"``: band-limited point samples, the exact kernel for
        blurring well-sampled images (see :mod:`vissim.optics.blur` for when it matters).
    """
    diameter = wavefront.pupil_diameter_mm if pupil_diameter_mm is None else check_pupil_mm(pupil_diameter_mm)
    if diameter > wavefront.pupil_diameter_mm * (1 + 1e-12):
        raise VissimInputError(
            f"pupil {diameter:g} mm is larger than the {wavefront.pupil_diameter_mm:g} mm pupil the "
            "Zernike coefficients were measured over"
        )
    step = check_arcmin_per_px(arcmin_per_px)
    if int(size_px) != size_px or not 1 <= size_px <= MAX_PSF_SIZE_PX:
        raise VissimInputError(f"PSF size must be an integer number of pixels in 1-{MAX_PSF_SIZE_PX}, got {size_px!r}")
    size_px = int(size_px)
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"PSF mode must be 'wave' or 'geometric', got {mode!r}")
    if pixel not in PIXEL_MODES:
        raise VissimInputError(f"PSF pixel must be one of {', '.join(PIXEL_MODES)}, got {pixel!r}")
    if dtype not in (np.float32, np.float64):
        raise VissimInputError(f"PSF dtype must be float32 or float64, got {dtype!r}")
    wavelengths = tuple(float(w) for w in np.atleast_1d(wavelength_nm))
    for w in wavelengths:
        if not math.isfinite(w) or not 200.0 <= w <= 2000.0:
            raise VissimInputError(f"wavelength must be within 200-2000 nm, got {w!r} nm")
    weights_t = tuple(float(w) for w in (weights if weights is not None else [1.0] * len(wavelengths)))
    if len(weights_t) != len(wavelengths) or any(not math.isfinite(w) or w < 0 for w in weights_t) or sum(weights_t) <= 0:
        raise VissimInputError(f"need one non-negative weight per wavelength, got {weights_t!r} for {wavelengths!r} nm")
    total_weight = sum(weights_t)
    weights_t = tuple(w / total_weight for w in weights_t)

    accumulated = np.zeros((size_px, size_px))
    energy = 0.0
    samplings = []
    for w, weight in zip(wavelengths, weights_t):
        front = wavefront
        if lca_reference_nm is not None:
            front = wavefront.with_defocus_diopters(chromatic_difference_of_refraction_diopters(w, lca_reference_nm))
        blur = geometric_blur_radius_arcmin(front, diameter)
        lambda_over_d_arcmin = float(rad_to_arcmin(nm_to_mm(w) / diameter))
        needed = 2.0 * (blur + (2.44 * lambda_over_d_arcmin if mode == "wave" else 0.0))
        if needed > size_px * step:
            raise FieldTooSmallError(
                f"a {size_px} px field at {step:g} arcmin/px ({size_px * step:g} arcmin) cannot hold the "
                f"{needed:.3g} arcmin blur at {w:g} nm; use a size of at least "
                f"{int(math.ceil(needed / step)) + 2} px or coarser sampling"
            )
        if mode == "wave":
            mono, sampling = _wave_psf(front, diameter, w, step, size_px, blur, dtype, pixel)
            samplings.append(sampling)
        else:
            mono, _ = _geometric_psf(front, diameter, step, size_px, blur, pixel)
        in_field = float(mono.sum())
        energy += weight * in_field
        accumulated += weight * (mono / in_field)
    if energy < 0.98:
        log.warning(
            "only %.1f %% of the PSF's energy falls inside the %d px field; the PSF is renormalised",
            100 * energy,
            size_px,
        )
    data = (accumulated / accumulated.sum()).astype(dtype)
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
        sampling=tuple(samplings),
        pixel=pixel,
    )


def strehl_ratio(wavefront: Wavefront, wavelength_nm: float = 550.0, pupil_diameter_mm: float | None = None) -> float:
    """Strehl ratio |<A exp(ikW)>|^2 / <A>^2 over the pupil (sampling-independent)."""
    diameter = wavefront.pupil_diameter_mm if pupil_diameter_mm is None else float(pupil_diameter_mm)
    step = diameter / 512.0
    fft_size = 2 * (int(math.ceil(diameter / (2 * step))) + 2)
    sampling = PsfSampling(1, fft_size, step, 0.0)
    _, _, _, amplitude, _ = _pupil_geometry(fft_size, step, diameter)
    opd = _opd_on_grid(wavefront, sampling, diameter)
    field_sum = np.sum(amplitude * np.exp(2j * math.pi / nm_to_um(wavelength_nm) * opd))
    return float(abs(field_sum) ** 2 / np.sum(amplitude) ** 2)
