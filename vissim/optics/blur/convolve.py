"""Blurring images with PSFs, in linear light, by FFT convolution.

* The image must be linear light (`vissim.imageio` decodes files) and its angular
  sampling must equal the PSF's: a PSF travels with its sampling and a mismatch is an error.
* The PSF's origin ``[N//2, N//2]`` is moved to the FFT origin, so even-sized kernels do
  not shift the image.
* The image is padded before the FFT so that the convolution is linear, not circular:
  ``"constant"`` (a background value; default the mean of the image's border), ``"edge"``,
  ``"reflect"`` or ``"wrap"`` (circular; preserves the mean exactly).
* A PSF that sums to 1 preserves the mean wherever the padding continues the image.
* Pixels of an image are integrals over the pixel.  For a *well-sampled* image the exact
  kernel is the PSF's band-limited point samples (``compute_psf(..., pixel="sample")``, whose
  DFT is the OTF); a pixel-integrated PSF adds the pixel's box once more.  Images of sharp
  letters at 1 arcmin/px are under-sampled, and there the band-limited kernel rings while the
  extra box costs little: measured against the Mitsuba bench the two differ by < 1 dB, so
  vissim's default is the non-negative integrated PSF.  Simulate sharp inputs on a finer grid
  and integrate (as the validation harness does) when the last dB matters.
* One greyscale image with one PSF costs one forward and one inverse real FFT of the padded
  size plus the kernel's transform, pruned to the kernel's support (`kernel_transfer`),
  which `BlurKernel` keeps for the next image blurred by the same PSF on the same grid.
  Large images with small kernels are convolved by overlap-save instead, in squares of a few
  hundred pixels (`_tile_px` picks the size from an operation count): the same numbers
  to round-off, a kernel transform the size of one square, and FFTs that stay in cache, one
  square per core at a time.
"""

from __future__ import annotations

import functools
import logging
import math
import os
import threading
import weakref
from collections import OrderedDict
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import describe, size_text
from vissim.errors import FieldTooSmallError, VissimInputError, VissimTypeError
from vissim.lazy_import import lazy_module
from vissim.optics.blur.padding import PADDING_MODES
from vissim.optics.psf.compute import PSF, compute_psf, suggested_size_px

scipy_fft = lazy_module("scipy.fft")

__all__ = ["blur_image", "image_kernel_psf", "BlurKernel", "PADDING_MODES", "border_mean", "psf_padding_width_px",
           "pad_window"]

log = logging.getLogger(__name__)

#: ``numpy.pad``'s (and CuPy's) name for each padding mode: "reflect" repeats the border pixel.
NUMPY_PAD_MODES = {"constant": "constant", "edge": "edge", "reflect": "symmetric", "wrap": "wrap"}


@dataclass(frozen=True, eq=False)
class BlurKernel:
    """The transfer function of a PSF on a padded FFT grid (reusable across images)."""

    psf: PSF
    padded_shape: tuple[int, int]
    transfer: np.ndarray

    @classmethod
    def prepare(cls, psf: PSF, padded_shape: tuple[int, int], dtype=np.float32, workers: int = -1) -> BlurKernel:
        """The PSF's transfer function on this grid, reused while the PSF lives (``workers``: FFT threads)."""
        key = (id(psf), tuple(padded_shape), np.dtype(dtype).name)
        with _TRANSFERS_LOCK:  # threads blurring layers at once share the cache
            cached = _TRANSFERS.get(key)
            if cached is not None and cached[0]() is psf:
                _TRANSFERS.move_to_end(key)
                return cls(psf, padded_shape, cached[1])
        transfer = kernel_transfer(psf.data, padded_shape, dtype, workers)
        transfer.setflags(write=False)
        with _TRANSFERS_LOCK:
            _TRANSFERS[key] = (weakref.ref(psf), transfer)
            while sum(t.nbytes for _, t in _TRANSFERS.values()) > TRANSFER_CACHE_BYTES and len(_TRANSFERS) > 1:
                _TRANSFERS.popitem(last=False)
        return cls(psf, padded_shape, transfer)


#: Transfer functions kept for reuse (least recently used dropped beyond this many bytes).
TRANSFER_CACHE_BYTES = 256 * 2**20
_TRANSFERS: OrderedDict = OrderedDict()
_TRANSFERS_LOCK = threading.Lock()


def kernel_transfer(kernel: np.ndarray, padded_shape: tuple[int, int], dtype=np.float32,
                    workers: int = -1) -> np.ndarray:
    """``rfft2`` of ``kernel`` placed with its origin ``[N//2, M//2]`` at ``[0, 0]`` of a zero grid.

    Pruned to the kernel's support: only its rows are real-FFT'd along the columns, then the
    columns are FFT'd with those rows scattered onto the grid.  Equal to the full ``rfft2`` to
    round-off, for about half its cost.  (A matrix product over the kernel's rows does fewer
    operations but was slower in a blur: BLAS and FFT thread pools contend on few cores.)
    """
    rows, cols = padded_shape
    n_rows, n_cols = kernel.shape
    if n_rows > rows or n_cols > cols:
        raise AssertionError("kernel larger than the padded image")  # pragma: no cover
    complex_dtype = np.complex64 if dtype == np.float32 else np.complex128
    placed = np.zeros((n_rows, cols), dtype=dtype)
    placed[:, (np.arange(n_cols) - n_cols // 2) % cols] = kernel
    along_cols = scipy_fft.rfft(placed, axis=1, workers=workers)
    scattered = np.zeros((rows, along_cols.shape[1]), dtype=complex_dtype)
    scattered[(np.arange(n_rows) - n_rows // 2) % rows] = along_cols
    return scipy_fft.fft(scattered, axis=0, workers=workers, overwrite_x=True)


def padding_width_px(kernel_px: int) -> int:
    """Pixels of padding on each side for linear (not circular) convolution by a ``kernel_px`` kernel."""
    return kernel_px // 2 + 1


def padded_shape(shape: tuple[int, int], kernel_px: int) -> tuple[int, int]:
    """The full-frame FFT's grid: the image plus the kernel's reach on each side, at a fast size."""
    width = padding_width_px(kernel_px)
    return tuple(scipy_fft.next_fast_len(n + 2 * width, real=True) for n in shape)


def psf_padding_width_px(psf: PSF) -> int:
    """The padding (px) each side of an image blurred by ``psf``: its half-width."""
    return padding_width_px(psf.data.shape[0])


def _pad(channel: np.ndarray, width: int, shape: tuple[int, int], mode: str, background: float | None) -> np.ndarray:
    rows, cols = channel.shape
    extra_r, extra_c = shape[0] - rows - 2 * width, shape[1] - cols - 2 * width
    if mode == "constant" and background is None:
        background = border_mean(channel)
    return pad_array(channel, ((width, width + extra_r), (width, width + extra_c)), mode, background)


def pad_array(array, widths, mode: str, background: float | None = None, xp=np):
    """``array`` padded by ``widths`` (``numpy.pad``'s) as padding ``mode`` says; ``xp``: NumPy or CuPy.

    ``background`` is the value outside for ``"constant"`` (required there).
    """
    if mode == "constant":
        if background is None:
            raise AssertionError("constant padding needs a background value")  # pragma: no cover
        return xp.pad(array, widths, mode="constant", constant_values=background)
    return xp.pad(array, widths, mode=NUMPY_PAD_MODES[mode])


def pad_window(array, widths, mode: str, touches, xp=np):
    """A window of an image, (..., h, w), padded by ``widths`` ((top, bottom), (left, right)): as padding ``mode``
    says on a side that ``touches`` (top, bottom, left, right) the image's border, with zeros on a side inside the
    image (beyond it the window already holds everything that reaches it)."""
    padded = pad_array(array, ((0, 0),) * (array.ndim - 2) + tuple(widths), mode, xp=xp)
    (top, bottom), (left, right) = widths
    rows, cols = padded.shape[-2:]
    for touching, side in zip(touches, (np.s_[..., :top, :], np.s_[..., rows - bottom :, :], np.s_[..., :left],
                                        np.s_[..., cols - right :])):
        if not touching:
            padded[side] = 0.0
    return padded


def border_mean(channel: np.ndarray) -> float:
    """The mean of a channel's outermost pixels: the background ``"constant"`` padding fills in."""
    border = np.concatenate([channel[0], channel[-1], channel[1:-1, 0], channel[1:-1, -1]])
    return float(np.mean(border))


def _check_sampling(psf: PSF, arcmin_per_px: float) -> None:
    if not math.isclose(psf.arcmin_per_px, arcmin_per_px, rel_tol=1e-9):
        raise VissimInputError(
            f"the PSF is sampled at {psf.arcmin_per_px:g} arcmin/px but the image at {arcmin_per_px:g} "
            "arcmin/px; compute the PSF at the image's sampling"
        )
    if psf.data.shape[0] != psf.data.shape[1]:
        raise VissimInputError(f"PSF must be square, got {psf.data.shape}")


#: The smallest and largest tile (px) tried for overlap-save convolution of large images (larger squares measured
#: slower than one full-frame FFT: cache); `tile_sizes_px` keeps the sizes between whose FFT is fast.
SMALLEST_TILE_PX, LARGEST_TILE_PX = 256, 512


@functools.cache
def tile_sizes_px() -> tuple[int, ...]:
    """The tile sizes tried: the even sizes from `SMALLEST_TILE_PX` to `LARGEST_TILE_PX` that ``scipy.fft.next_fast_len`` keeps (5-smooth),
    found when a blur first needs them (not when the module is imported)."""
    return tuple(n for n in range(SMALLEST_TILE_PX, LARGEST_TILE_PX + 1, 2) if scipy_fft.next_fast_len(n, real=True) == n)


#: A tiled blur is chosen when its estimated cost is below this fraction of the full FFT's.
#: The estimate counts FFT operations (n log n); measured on 2 cores, the small tiles' FFTs run
#: at about 1.6x the full-frame FFT's rate per operation (cache), so their count is scaled by this.
#: (Measured for whole rows of squares; with one thread per square, at 0.5-1.9k px per side the
#: chosen squares were at or below the full frame's time, 2026-12-02.)
TILE_COST_FACTOR = 0.6


def _fft_cost(shape) -> float:
    n = float(np.prod(shape))
    return n * math.log2(n)


def _tile_px(shape: tuple[int, int], kernel_px: int) -> int | None:
    """The overlap-save tile size for an image of ``shape`` that beats one full-frame FFT, or None."""
    best, best_cost = None, _fft_cost(padded_shape(shape, kernel_px))
    for tile in tile_sizes_px():
        valid = tile - kernel_px + 1
        if valid < 3 * kernel_px or tile >= min(shape):
            continue
        count = math.ceil(shape[0] / valid) * math.ceil(shape[1] / valid)
        cost = TILE_COST_FACTOR * count * _fft_cost((tile, tile))
        if cost < best_cost:
            best, best_cost = tile, cost
    return best


def _blur_tiled(channel, psf, padding, background, dtype, tile):
    """Overlap-save: the image cut into ``tile``-px squares, each convolved circularly.

    A square's circular convolution is exact on its ``tile - N + 1`` valid pixels per axis (those
    the kernel reaches without wrapping); squares step by that much, so their valid parts tile
    the image.  Squares are read from the image in place and padded only where they cross its
    edge.  They are independent: one thread per core takes them in turn, each square's transforms
    single-threaded in that core's cache, and only its valid rows inverted along the rows.
    Equal to the full-frame convolution to round-off.
    """
    rows, cols = channel.shape
    n = psf.data.shape[0]
    valid, first_valid = tile - n + 1, n - 1 - n // 2
    if padding == "constant" and background is None:
        background = border_mean(channel)
    transfer = BlurKernel.prepare(psf, (tile, tile), dtype=dtype).transfer
    out = np.empty((rows, cols), dtype)

    def blur_square(top: int, left: int) -> None:  # the output from [top, left], valid x valid at most
        r0, c0 = top - first_valid, left - first_valid  # the square's corner in the image
        square = channel[max(r0, 0) : r0 + tile, max(c0, 0) : c0 + tile]
        widths = ((max(-r0, 0), max(r0 + tile - rows, 0)), (max(-c0, 0), max(c0 + tile - cols, 0)))
        if any(map(any, widths)):
            square = pad_array(square, widths, padding, background)
        spectrum = scipy_fft.rfft2(square, workers=1)
        spectrum *= transfer
        spectrum = scipy_fft.ifft(spectrum, axis=0, workers=1, overwrite_x=True)
        height, width = min(valid, rows - top), min(valid, cols - left)
        blurred = scipy_fft.irfft(spectrum[first_valid : first_valid + height], n=tile, axis=1, workers=1,
                                  overwrite_x=True)
        out[top : top + height, left : left + width] = blurred[:, first_valid : first_valid + width]

    corners = [(top, left) for top in range(0, rows, valid) for left in range(0, cols, valid)]
    with ThreadPoolExecutor(len(os.sched_getaffinity(0))) as pool:  # the cores this process may use
        list(pool.map(lambda corner: blur_square(*corner), corners))  # re-raises a square's error
    return out


def _blur_channel(channel, psf, padding, background, dtype):
    rows, cols = channel.shape
    if padding == "wrap":  # the PSF's size against the image's is checked in checked_blur_inputs
        shape = (rows, cols)
        padded, offset = channel, 0
    else:
        offset = psf_padding_width_px(psf)
        shape = padded_shape((rows, cols), psf.data.shape[0])
        tile = _tile_px((rows, cols), psf.data.shape[0])
        if tile is not None:
            log.debug("blur by overlap-save in %d px tiles", tile)
            return _blur_tiled(channel, psf, padding, background, dtype, tile)
        padded = _pad(channel, offset, shape, padding, background)
    kernel = BlurKernel.prepare(psf, shape, dtype=dtype)
    spectrum = scipy_fft.rfft2(padded.astype(dtype, copy=False), workers=-1)
    spectrum *= kernel.transfer
    out = scipy_fft.irfft2(spectrum, s=shape, workers=-1, overwrite_x=True)
    return out[offset : offset + rows, offset : offset + cols]


def pixel_array(image) -> np.ndarray:
    """``image`` as a numeric array; a path or an object that is no pixel array refused with what is accepted."""
    array = np.asarray(image) if not isinstance(image, (str, bytes, os.PathLike)) else np.asarray(None)
    if array.dtype.kind not in "biuf":
        raise VissimTypeError(f"image must be an ndarray of linear light, shape (H, W) or (H, W, C) (read a file with "
                              f"vissim.imageio.read_image(path).pixels), got {describe(image)}")
    return array


def _psf_list(psf) -> list[PSF]:
    """A list or tuple of PSFs (one per channel); anything else refused with what is accepted."""
    psfs = list(psf) if isinstance(psf, (list, tuple)) else [None]
    if not psfs or not all(isinstance(p, PSF) for p in psfs):
        raise VissimTypeError("psf must be a PSF (from vissim.compute_psf) or a list of PSFs, one per channel, "
                              f"got {describe(psf)}")
    return psfs


def checked_blur_inputs(image, psf, arcmin_per_px: float, padding: str, background):
    """The image as an array, one PSF and one background per channel; every refusal of a blur's inputs."""
    if padding not in PADDING_MODES:
        raise VissimInputError(f"padding must be one of {', '.join(PADDING_MODES)}; got {padding!r}")
    array = pixel_array(image)
    if array.ndim not in (2, 3) or min(array.shape[:2]) < 1:
        raise VissimInputError(f"image must have shape (H, W) or (H, W, C), got {array.shape}")
    if not (np.isfinite(array.min()) and np.isfinite(array.max())):  # NaN propagates; no mask allocated
        raise VissimInputError("image has NaN or infinite pixels; blur needs finite linear-light values")
    n_channels = 1 if array.ndim == 2 else array.shape[2]
    psfs = [psf] * n_channels if isinstance(psf, PSF) else _psf_list(psf)
    arcmin_per_px = check_arcmin_per_px(arcmin_per_px, "the image's arcmin_per_px")
    if len(psfs) != n_channels:
        raise VissimInputError(f"got {len(psfs)} PSFs for an image with {n_channels} channels")
    if background is None or np.ndim(background) == 0:
        backgrounds = [background] * n_channels
    else:
        backgrounds = [float(b) for b in background]
        if len(backgrounds) != n_channels:
            raise VissimInputError(f"got {len(backgrounds)} background values for {n_channels} channels")
    for p in psfs:
        _check_sampling(p, arcmin_per_px)
        if p.normalisation != "field":
            raise VissimInputError("a PSF image (normalised to its total energy) is no blur kernel; compute the "
                                   "kernel with compute_psf(..., normalise='field'), which sums to 1 over its field")
        if padding == "wrap" and p.data.shape[0] > min(array.shape[:2]):
            raise VissimInputError(f"a {size_text(p.data.shape)} PSF is larger than the {size_text(array.shape)} "
                                   "image; 'wrap' padding needs a smaller PSF")
    return array, psfs, backgrounds


def blur_image(
    image: np.ndarray,
    psf: PSF | Sequence[PSF],
    *,
    arcmin_per_px: float,
    padding: str = "constant",
    background: float | Sequence[float] | None = None,
    dtype=np.float32,
) -> np.ndarray:
    """Convolve a linear-light image with a PSF (or one PSF per channel).

    Parameters
    ----------
    image : ndarray of shape (H, W) or (H, W, C)
        Linear light, indexed ``[row, col]``.
    psf : PSF or sequence of PSF
        One PSF for every channel, or one per channel (e.g. a wavelength per channel).
    arcmin_per_px : float
        The image's angular sampling; must equal the PSFs'.
    padding : {"constant", "edge", "reflect", "wrap"}
    background : float or per-channel floats, optional
        Value outside the image for ``"constant"`` (default: the mean of the border pixels).
    dtype : float32 (default) or float64

    Returns
    -------
    ndarray of shape (H, W) or (H, W, C), ``dtype``
        The blurred image, the same shape and sampling as ``image``: row 0 at the top, columns
        increasing to the observer's right (the PSF is applied in the same orientation).

    Examples
    --------
    A Sloan K at 20/200 (logMAR 1.0), 1 arcmin per pixel, seen by a -1.00 D myope through a
    3 mm pupil:

    >>> import vissim
    >>> chart = vissim.render_chart_angular(vissim.single_letter_spec("K", 1.0), arcmin_per_px=1.0)
    >>> front = vissim.Wavefront.from_prescription(vissim.Prescription(-1.0), pupil_diameter_mm=3.0)
    >>> psf = vissim.compute_psf(front, arcmin_per_px=1.0, size_px=64)
    >>> blurred = vissim.blur_image(chart.pixels, psf, arcmin_per_px=1.0)
    >>> blurred.shape, blurred.dtype.name
    ((150, 150), 'float32')
    >>> bool(blurred.min() > chart.pixels.min())  # the black strokes are washed out
    True
    """
    if dtype not in (np.float32, np.float64):
        raise VissimInputError(f"dtype must be float32 or float64, got {dtype!r}")
    array, psfs, backgrounds = checked_blur_inputs(image, psf, arcmin_per_px, padding, background)
    channels = [array] if array.ndim == 2 else [array[..., c] for c in range(array.shape[2])]
    blurred = [
        _blur_channel(np.asarray(c, dtype=dtype), p, padding, b, dtype)
        for c, p, b in zip(channels, psfs, backgrounds)
    ]
    log.debug("blurred a %s image with %d PSF(s), padding %s", array.shape, len(set(map(id, psfs))), padding)
    out = blurred[0] if array.ndim == 2 else np.stack(blurred, axis=-1)
    return out.astype(dtype, copy=False)


def image_kernel_psf(front, shape: tuple[int, ...], *, arcmin_per_px: float, wavelength_nm, weights=None,
                     lca_reference_nm=None, mode: str = "wave", progress=None) -> PSF:
    """The blur kernel of ``front`` (a `Wavefront`, `OpdMap` or `SpectralWavefront`, over its pupil) for an
    image of ``shape``: its field the one that holds it (`suggested_size_px`), cut to twice the image's
    longer side plus one (no pixel sees farther). An image whose cut field would lose more than 1 % of the
    energy is too small: `FieldTooSmallError` naming the image side that holds the blur."""
    pupil = front.pupil_diameter_mm
    size = suggested_size_px(front, arcmin_per_px, pupil_diameter_mm=pupil, wavelength_nm=wavelength_nm,
                             weights=weights, lca_reference_nm=lca_reference_nm)
    field_px = min(size, 2 * max(shape[:2]) + 1)
    try:
        return compute_psf(front, pupil_diameter_mm=pupil, wavelength_nm=wavelength_nm, weights=weights,
                           lca_reference_nm=lca_reference_nm, arcmin_per_px=arcmin_per_px, size_px=field_px,
                           mode=mode, progress=progress)
    except FieldTooSmallError:
        if field_px == size:
            raise
        raise FieldTooSmallError(
            f"the image is {size_text(shape[:2])}, too small for this blur: its PSF needs a {size} px field at "
            f"{arcmin_per_px:g} arcmin/px, so the image needs at least {math.ceil((size - 1) / 2)} px on its longer "
            "side (or a coarser sampling)") from None
