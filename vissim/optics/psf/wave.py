"""Wave-optical PSFs: the pupil's Fourier transform by matrix products or by one FFT.

The generalised pupil is sampled as cell averages (`vissim.optics.pupil.grid`), on as
many cells as the wavefront needs (``docs/conventions.md``, "Pupil sampling"), independently
of the output grid.  Its Fraunhofer transform is evaluated on an internal grid finer than the
intensity's Nyquist interval lambda/(2D), over a field that holds the output pixels and the
PSF, and then integrated over the output pixels (or band-limited, ``pixel="sample"``).

Two ways to evaluate the transform, the same numbers to round-off:

* ``"mft"``, a matrix Fourier transform ``A G A^T`` (Soummer et al. 2007, Opt. Express 15,
  15935): any pupil step, exactly the internal samples asked for;
* ``"fft"``, one zero-padded FFT: the pupil step is then lambda / (FFT field), so the FFT
  grows until the pupil is sampled finely enough.

The cheaper of the two (an operation count) is chosen per call and recorded in the
provenance (``PSF.sampling``).  Several wavelengths share the internal grid, the pixel pass
and, for the matrix transform, the pupil grid; each is transformed in turn.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.progress import Progress, counter
from vissim.optics.psf.field_size import airy_tail_radius_lambda_over_d, rim_widening
from vissim.optics.pupil.grid import generalised_pupil, generalised_pupil_parts, opd_on_points_um, pupil_grid
from vissim.optics.runtime.threads import map_shares
from vissim.optics.runtime.workspace import scratch
from vissim.units import arcmin_to_rad, nm_to_mm, rad_to_arcmin

scipy_fft = lazy_module("scipy.fft")

__all__ = ["PHASE_STEP_WAVES", "MIN_PUPIL_CELLS", "PsfSampling", "plan_wave_psf", "wave_psf", "to_output_pixels"]

#: Largest change of the wavefront across one pupil cell at its steepest slope, in waves.
PHASE_STEP_WAVES = 0.125
#: Fewest cells across the pupil diameter (the rim's quadrature needs no more).
MIN_PUPIL_CELLS = 64
#: Diffraction margin (in lambda/D) kept beyond the geometric blur on each side.
SKIRT_MARGIN_LAMBDA_OVER_D = 8.0
#: Largest internal grid or FFT, per side (complex128: 1 GiB at 8192^2).
MAX_INTERNAL_SIZE = 8192
#: Bytes per internal grid point (complex field, intensity, the pixel filter's spectrum).
BYTES_PER_INTERNAL_PX = 48
#: Largest fraction of the energy that the pupil sampling may fold back into the field (aliasing).
ALIAS_MAX_ENERGY = 2e-3
#: Measured rates on this project's 2-core machine: real matrix products and complex FFTs (flop/s).
GEMM_FLOPS_PER_S, FFT_FLOPS_PER_S = 40e9, 6e9


@dataclass(frozen=True)
class PsfSampling:
    """How one monochromatic wave PSF is sampled internally."""

    method: str  # "mft" or "fft"
    wavelength_nm: float
    oversample: int  # q: internal samples per output pixel along each axis
    internal_size: int  # M: internal grid (or FFT) points per side
    pupil_step_mm: float
    pupil_cells: float  # cells across the pupil diameter
    internal_arcmin_per_px: float

    def as_json(self) -> dict:
        return {
            "method": self.method,
            "wavelength_nm": self.wavelength_nm,
            "oversample": self.oversample,
            "internal_size": self.internal_size,
            "pupil_step_mm": self.pupil_step_mm,
            "pupil_cells": self.pupil_cells,
            "internal_arcmin_per_px": self.internal_arcmin_per_px,
        }


def required_pupil_cells(blur_radius_arcmin: float, pupil_diameter_mm: float, wavelength_nm: float) -> float:
    """Cells across the pupil so the phase changes by <= PHASE_STEP_WAVES per cell at the steepest slope."""
    slope_rad = float(arcmin_to_rad(blur_radius_arcmin))
    return max(MIN_PUPIL_CELLS, pupil_diameter_mm * slope_rad / (PHASE_STEP_WAVES * nm_to_mm(wavelength_nm)))


def _fft_seconds(size: int) -> float:
    return 5.0 * size**2 * math.log2(max(size, 2) ** 2) / FFT_FLOPS_PER_S


#: The cell average's correction (1 / sinc, up to sinc(1/2)) lifts a folded skirt by at most pi / 2.
FOLD_LIFT = math.pi / 2
#: A diagonal replica's tail over the field, relative to a side replica's (a quadrant beyond
#: (d, d) holds (2 - sqrt 2) / 2 of the half-plane beyond d, for a 1 / r^3 tail).
DIAGONAL_SHARE = (2.0 - math.sqrt(2.0)) / 2.0


def folded_energy(distance_arcmin: float, half_field_arcmin: float, blur_arcmin: float,
                  lambda_over_d_arcmin: float) -> float:
    """Energy the eight nearest replicas fold into a square field of half-width ``half_field_arcmin``
    when the period exceeds it by ``distance_arcmin``.

    Each replica's light beyond radius r is the Airy tail 2 / (pi^2 r) (r in lambda/D beyond the
    geometric blur, widened for a defocused rim as in `vissim.optics.psf.field_size`).  With a
    1 / r^3 density, 1 / pi of it lies beyond a line at distance d, and of that the fraction
    (sqrt(d^2 + h^2) - d) / h within the field's strip |y| <= h; the four diagonal replicas add
    at most DIAGONAL_SHARE each; the cell average's correction lifts it by up to FOLD_LIFT.
    """
    beyond = distance_arcmin - blur_arcmin
    if beyond <= 0:
        return math.inf
    widening = rim_widening(blur_arcmin, lambda_over_d_arcmin)
    tail = min(1.0, widening * 2.0 / (math.pi**2 * beyond / lambda_over_d_arcmin))
    h, d = half_field_arcmin, distance_arcmin
    strip = (math.hypot(d, h) - d) / h
    return FOLD_LIFT * (4.0 / math.pi) * tail * strip * (1.0 + DIAGONAL_SHARE)


def fold_distance_arcmin(half_field_arcmin: float, blur_arcmin: float, lambda_over_d_arcmin: float) -> float:
    """The margin beyond the field's half-width for the period: the radius beyond which at most
    ALIAS_MAX_ENERGY of one replica's light lies (what bounds the error pixel by pixel in a small
    field), or, over a field far wider than the PSF, the distance at which the eight nearest
    replicas fold at most ALIAS_MAX_ENERGY into it (`folded_energy`, by bisection)."""
    widening = rim_widening(blur_arcmin, lambda_over_d_arcmin)
    one = blur_arcmin + widening * lambda_over_d_arcmin * airy_tail_radius_lambda_over_d(ALIAS_MAX_ENERGY)
    args = (half_field_arcmin, blur_arcmin, lambda_over_d_arcmin)
    low, high = blur_arcmin, blur_arcmin + 4.0 * (one - blur_arcmin)  # the folded share is at most ~3.3 x one's
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if folded_energy(middle, *args) > ALIAS_MAX_ENERGY else (low, middle)
    return max(one, high)


def plan_wave_psf(
    pupil_diameter_mm: float,
    wavelengths_nm: Sequence[float],
    arcmin_per_px: float,
    size_px: int,
    blur_radii_arcmin: Sequence[float],
    method: str | None = None,
) -> tuple[PsfSampling, ...]:
    """Internal sampling shared by the wavelengths, by the cheaper method unless ``method`` is given.

    The pupil cells repeat the PSF every lambda/step in angle (for the FFT, lambda/step is its
    field).  That period must exceed the internal field by a margin over which at most
    ALIAS_MAX_ENERGY of the light of the eight nearest replicas folds back into it
    (`folded_energy`); the light itself then lies where the cell average's sinc is
    divided out in full.
    """
    d = pupil_diameter_mm
    lambda_over_d = [float(rad_to_arcmin(nm_to_mm(w) / d)) for w in wavelengths_nm]
    oversample = max(1, math.ceil(arcmin_per_px / (0.5 * min(lambda_over_d)) - 1e-9))
    internal = arcmin_per_px / oversample
    reach = [b + SKIRT_MARGIN_LAMBDA_OVER_D * ld for b, ld in zip(blur_radii_arcmin, lambda_over_d)]
    field = max(size_px * arcmin_per_px, 2.0 * max(reach))
    size = max(int(math.ceil(field / internal - 1e-9)), oversample * size_px)
    size += size % 2
    half_field = size * internal / 2
    period = [max(required_pupil_cells(b, d, w) * ld, half_field + fold_distance_arcmin(half_field, b, ld))
              for b, w, ld in zip(blur_radii_arcmin, wavelengths_nm, lambda_over_d)]  # arcmin
    # Matrix transform: one pupil grid for every wavelength.
    mft_step = d / max(p / ld for p, ld in zip(period, lambda_over_d))
    grid = 2 * int(math.ceil(d / 2 / mft_step + 0.5)) + 1
    n = len(wavelengths_nm)
    mft_seconds = n * 2.0 * (grid**2 * size + grid * size**2) / GEMM_FLOPS_PER_S + _fft_seconds(size)
    # FFT: its field is the period; one FFT per wavelength and one for the pixels.
    fft = scipy_fft.next_fast_len(max(size, int(math.ceil(max(period) / internal - 1e-9))))
    fft += fft % 2
    fft_seconds = (n + 1) * _fft_seconds(fft)
    if method is None:
        method = "fft" if fft_seconds < mft_seconds and fft <= MAX_INTERNAL_SIZE else "mft"
    used = fft if method == "fft" else size
    if used > MAX_INTERNAL_SIZE:
        raise VissimInputError(
            f"{arcmin_per_px:g} arcmin/px over {size_px} px with a {d:g} mm pupil needs a {used}^2 internal grid "
            f"(over the {MAX_INTERNAL_SIZE}^2 limit, ~{used**2 * BYTES_PER_INTERNAL_PX / 2**30:.0f} GiB); "
            "use coarser sampling or a smaller field"
        )
    plans = []
    for w in wavelengths_nm:
        step = mft_step if method == "mft" else nm_to_mm(w) / (fft * float(arcmin_to_rad(internal)))
        plans.append(PsfSampling(method, float(w), oversample, used, step, d / step, internal))
    return tuple(plans)


@functools.lru_cache(maxsize=16)
def _folded_matrices(size: int, internal_arcmin: float, pupil_step_mm: float, half: int, wavelength_nm: float, dtype):
    """Real cos and sin of ``k theta_r u_j`` for theta_r >= 0 (rows 0..size/2) and u_j >= 0, over the
    cell average's sinc (divided out up to sinc(1/2): beyond, only folded skirt, not to amplify)."""
    wavelength_mm = nm_to_mm(wavelength_nm)
    theta = np.arange(size // 2 + 1) * float(arcmin_to_rad(internal_arcmin))
    u = np.arange(half + 1) * pupil_step_mm
    phase = (2 * math.pi / wavelength_mm) * np.outer(theta, u)
    correction = 1.0 / np.sinc(np.minimum(theta * pupil_step_mm / wavelength_mm, 0.5))[:, None]
    cos, sin = (np.cos(phase) * correction).astype(dtype), (np.sin(phase) * correction).astype(dtype)
    for array in (cos, sin):
        array.setflags(write=False)
    return cos, sin


def _fold_rows(source: np.ndarray, even: np.ndarray, odd: np.ndarray) -> None:
    """Even and odd parts of ``source`` about its centre row, on the centre row and below."""
    h = source.shape[0] // 2
    ahead, behind = source[h:], source[h::-1]
    np.add(ahead, behind, out=even)
    np.subtract(ahead, behind, out=odd)
    even[0] *= 0.5


def _quadrant_intensities(pupil: tuple[np.ndarray, np.ndarray], cos: np.ndarray, sin: np.ndarray,
                          total: np.ndarray, accumulate: bool) -> None:
    """|A G A^T|^2 for ``A = cos - i sin``, ``G`` as (real, imag), written (or, with ``accumulate``,
    added) into the M x M intensity ``total`` centred on [M/2, M/2].

    The cell grid is symmetric about its centre, so each axis splits into even and odd parts
    that transform by real cosines and sines over half the cells, and the output's four
    quadrants follow from the non-negative one: a quarter of the multiply-adds of ``A G A^T``.
    """
    n, h, m = pupil[0].shape[0], pupil[0].shape[0] // 2, cos.shape[0]
    work = functools.partial(scratch, dtype=cos.dtype)
    # Columns: fold along them; rows of the products are (real | imag) x pupil rows.
    even, odd = work("even_columns", (2 * n, h + 1)), work("odd_columns", (2 * n, h + 1))
    for i, part in enumerate(pupil):  # real, imaginary
        _fold_rows(part.T, even[i * n : (i + 1) * n].T, odd[i * n : (i + 1) * n].T)
    te = np.matmul(even, cos.T, out=work("te", (2 * n, m)))  # [(real | imag) x row, theta_c]
    to = np.matmul(odd, sin.T, out=work("to", (2 * n, m)))
    # Rows: fold each part about the centre row; even parts go to cos, odd parts to sin.
    even_rows, odd_rows = work("even_rows", (h + 1, 4, m)), work("odd_rows", (h + 1, 4, m))
    for i, (source, part) in enumerate(((te, 0), (te, 1), (to, 0), (to, 1))):
        _fold_rows(source[part * n : (part + 1) * n], even_rows[:, i], odd_rows[:, i])
    # [theta_r, (p1r, p1i, p3r, p3i), theta_c] and [theta_r, (p2r, p2i, p4r, p4i), theta_c]
    pc = np.matmul(cos, even_rows.reshape(h + 1, 4 * m), out=work("pc", (m, 4 * m))).reshape(m, 4, m)
    ps = np.matmul(sin, odd_rows.reshape(h + 1, 4 * m), out=work("ps", (m, 4 * m))).reshape(m, 4, m)
    # E(+,+) = A - iB, E(-,-) = A + iB with A = p1 - p4, B = p2 + p3;
    # E(+,-) = C - iD, E(-,+) = C + iD with C = p1 + p4, D = p2 - p3.
    ac, bd = work("ac", (2, m, 2, m)), work("bd", (2, m, 2, m))  # [A | C], [B | D]: [theta_r, real | imag, theta_c]
    np.subtract(pc[:, :2], ps[:, 2:], out=ac[0])
    np.add(pc[:, :2], ps[:, 2:], out=ac[1])
    np.add(ps[:, :2], pc[:, 2:], out=bd[0])
    np.subtract(ps[:, :2], pc[:, 2:], out=bd[1])
    # |E(+-,+-)|^2 = |A|^2 + |B|^2 +- 2 (Ar Bi - Ai Br), likewise with C and D.
    both, cross, spare = work("sum", (2, m, m)), work("cross", (2, m, m)), work("spare", (2, m, m))
    np.multiply(ac[:, :, 0], ac[:, :, 0], out=both)
    for source, part in ((ac, 1), (bd, 0), (bd, 1)):
        both += np.multiply(source[:, :, part], source[:, :, part], out=spare)
    np.multiply(ac[:, :, 0], bd[:, :, 1], out=cross)
    cross -= np.multiply(ac[:, :, 1], bd[:, :, 0], out=spare)
    cross *= 2
    # Quadrant (signs of theta_row, theta_col) -> its place in ``total``: |k| = 0..M/2 - 1 up, 1..M/2 down.
    half = total.shape[0] // 2
    place = {1: (slice(half, None), slice(0, half)), -1: (slice(half - 1, None, -1), slice(1, half + 1))}
    for pair, ((row_sign, col_sign), combine) in enumerate((((1, 1), np.add), ((1, -1), np.add))):
        for rs, cs, op in ((row_sign, col_sign, combine), (-row_sign, -col_sign, np.subtract)):
            (rows_out, rows_in), (cols_out, cols_in) = place[rs], place[cs]
            target = total[rows_out, cols_out]
            if accumulate:
                target += op(both[pair, rows_in, cols_in], cross[pair, rows_in, cols_in],
                             out=spare[pair, rows_in, cols_in])
            else:
                op(both[pair, rows_in, cols_in], cross[pair, rows_in, cols_in], out=target)


def _mft_intensity(fronts, weights, diameter_mm, plans, dtype, advance=lambda: None) -> np.ndarray:
    """Sum over wavelengths of weight x unit-energy intensity on the internal grid (origin at [M/2, M/2]).

    ``advance()`` after the pupil grid, and after each wavelength's pupil and transform. Several wavelengths are
    shared out over `spare_threads` (each its own pupil and partial sum, OpenBLAS on one thread meanwhile), and
    the partial sums added in a fixed order; how many there are follows the cores, so results on machines with
    other core counts differ by round-off (1e-9 of the peak in float32, 1e-13 of it in float64).
    """
    grid = pupil_grid(plans[0].pupil_step_mm, diameter_mm)
    advance()
    jobs = list(zip(fronts, weights, plans))
    partials = map_shares(lambda share: _mft_partial(grid, share, dtype, advance), jobs)  # advance: a thread-safe counter
    total = partials[0]
    for partial in partials[1:]:
        total += partial
    return total


def _mft_partial(grid, jobs, dtype, advance) -> np.ndarray:
    """`_mft_intensity`'s sum over ``jobs`` ((front, weight, plan) each), on this thread."""
    plan = jobs[0][2]
    m = plan.internal_size
    total = np.empty((m, m), dtype=dtype)
    opd = scratch("opd", (grid.centre_x_mm.size + grid.rim_x_mm.size,), dtype)
    parts = scratch("real", (grid.size, grid.size), dtype), scratch("imag", (grid.size, grid.size), dtype)
    for index, (front, weight, each) in enumerate(jobs):
        real, imag = generalised_pupil_parts(grid, opd_on_points_um(grid, front, dtype, out=opd), each.wavelength_nm,
                                             dtype, out=parts)
        advance()
        cos, sin = _folded_matrices(m, plan.internal_arcmin_per_px, plan.pupil_step_mm, grid.half,
                                    each.wavelength_nm, dtype)
        scale = (plan.pupil_step_mm * float(arcmin_to_rad(plan.internal_arcmin_per_px))
                 / nm_to_mm(each.wavelength_nm)) ** 2 / grid.area_cells
        amplitude = math.sqrt(weight * scale)  # the intensity's weight, applied to the (smaller) pupil
        real *= amplitude
        imag *= amplitude
        _quadrant_intensities((real, imag), cos, sin, total, accumulate=index > 0)
        advance()
    return total


@functools.lru_cache(maxsize=8)
def _cell_transfer(size: int) -> np.ndarray:
    """1 / sinc of the FFT's angles in units of lambda / step: the cell average divided out."""
    return 1.0 / np.sinc(scipy_fft.fftfreq(size))


def _fft_intensity(fronts, weights, diameter_mm, plans, dtype, advance=lambda: None) -> np.ndarray:
    """As `_mft_intensity`, by one FFT per wavelength: ``advance()`` after its pupil and after its transform."""
    complex_dtype = np.complex64 if dtype == np.float32 else np.complex128
    m = plans[0].internal_size
    total = np.zeros((m, m), dtype=dtype)
    correction = scipy_fft.fftshift(_cell_transfer(m)).astype(dtype)
    for front, weight, plan in zip(fronts, weights, plans):
        grid = pupil_grid(plan.pupil_step_mm, diameter_mm)
        offsets = np.arange(-grid.half, grid.half + 1)
        window = offsets % m  # pupil centre at index [0, 0]
        checker = np.where(offsets % 2, -1, 1).astype(dtype)  # (-1)^(i + j): the output centred on [M/2, M/2]
        pupil = np.zeros((m, m), dtype=complex_dtype)
        pupil[np.ix_(window, window)] = (generalised_pupil(grid, opd_on_points_um(grid, front), plan.wavelength_nm,
                                                           complex_dtype) * checker[:, None] * checker[None, :])
        advance()
        spectrum = scipy_fft.fft2(pupil, workers=-1, overwrite_x=True)
        spectrum *= correction[:, None]
        spectrum *= correction[None, :]
        total += (weight / (m * m * grid.area_cells)) * (np.square(spectrum.real) + np.square(spectrum.imag))
        advance()
    return total


def _profile(cycles_per_pixel: np.ndarray, pixel: str) -> np.ndarray:
    if pixel == "integrate":  # the output pixel's box
        return np.sinc(cycles_per_pixel)
    # ideal low-pass at the output Nyquist (half weight on the Nyquist bin itself)
    magnitude = np.abs(cycles_per_pixel)
    return np.where(magnitude < 0.5 - 1e-12, 1.0, np.where(magnitude <= 0.5 + 1e-12, 0.5, 0.0))


@functools.lru_cache(maxsize=16)
def _pixel_transfer(m: int, oversample: int, dtype, pixel: str) -> np.ndarray:
    """Transfer function applied before decimation onto output pixels, rfft2 grid (cached)."""
    y = _profile(scipy_fft.fftfreq(m) * oversample, pixel)
    x = _profile(scipy_fft.rfftfreq(m) * oversample, pixel)
    transfer = (y[:, None] * x[None, :]).astype(dtype)
    transfer.setflags(write=False)
    return transfer


def to_output_pixels(intensity: np.ndarray, size_px: int, oversample: int, pixel: str) -> np.ndarray:
    """Decimate the (Nyquist-sampled, periodic) internal PSF onto ``size_px`` output pixels.

    ``intensity`` (M x M) has its origin at ``[M//2, M//2]``; the output has it at ``[N//2, N//2]``.

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
    spectrum = scipy_fft.rfft2(intensity, workers=-1)
    spectrum *= _pixel_transfer(m, oversample, intensity.dtype.type, pixel)
    averaged = scipy_fft.irfft2(spectrum, s=intensity.shape, workers=-1, overwrite_x=True)
    first = m // 2 - (size_px // 2) * oversample
    averaged = averaged[first : first + size_px * oversample : oversample, first : first + size_px * oversample : oversample]
    return averaged * oversample**2 if oversample != 1 else averaged


def wave_psf(fronts, weights, diameter_mm, plans, size_px, dtype, pixel, progress: Progress | None = None) -> np.ndarray:
    """Weighted wave PSF on the output pixels; each wavelength carries its weight of the total energy.

    ``progress("wave PSF", done, total)`` after each stage: the pupil grid, each wavelength's
    pupil and transform, the output pixels (`vissim.progress`).
    """
    mft = plans[0].method == "mft"
    advance = counter(progress, "wave PSF", 2 * len(plans) + (2 if mft else 1))
    intensity = (_mft_intensity if mft else _fft_intensity)(fronts, weights, diameter_mm, plans, dtype, advance)
    out = to_output_pixels(intensity, size_px, plans[0].oversample, pixel)
    advance()
    if pixel == "integrate":
        np.maximum(out, 0.0, out=out)  # round-off only: integrals of an intensity are >= 0
    return out
