"""``blur_image`` on a device (`vissim.optics.runtime.array_backend`): the CPU, or a CUDA GPU through CuPy.

Same contract as `vissim.optics.blur.convolve.blur_image` (linear light, one PSF or one per channel,
the same padding modes and default background, float32), computed as one full-frame real FFT
pair per PSF with every channel that shares it batched: on a GPU a 1080p frame fits in one
transform, so the CPU's overlap-save squares would only add launches.  On the CPU backend it
equals ``blur_image`` to float32 round-off (``tests/test_array_backend.py``), and it is the same
code that runs on the GPU.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.runtime.array_backend import CPU, ArrayBackend, array_backend
from vissim.optics.blur.convolve import (BlurKernel, border_mean, checked_blur_inputs, pad_array, pad_window,
                                padded_shape, padding_width_px, psf_padding_width_px)
from vissim.optics.psf.compute import PSF

__all__ = ["blur_image_on", "convolve_padded", "convolve_window", "WINDOW_PADDING_MODES"]

#: How `convolve_window` continues a window beyond the image's border (inside the image: zeros).
WINDOW_PADDING_MODES = ("edge", "reflect")


def blur_image_on(
    image: np.ndarray,
    psf: PSF | Sequence[PSF],
    *,
    arcmin_per_px: float,
    padding: str = "constant",
    background: float | Sequence[float] | None = None,
    device: str = "cpu",
) -> np.ndarray:
    """`vissim.optics.blur.convolve.blur_image` on ``device`` (``"cpu"``, ``"cuda"`` or ``"auto"``); float32, on the host."""
    backend = array_backend(device)
    xp = backend.xp
    array, psfs, backgrounds = checked_blur_inputs(image, psf, arcmin_per_px, padding, background)
    array = array.astype(np.float32, copy=False)
    channels = array[np.newaxis] if array.ndim == 2 else np.moveaxis(array, -1, 0)
    rows, cols = array.shape[:2]
    out = np.empty(channels.shape, np.float32)
    for group in {id(p): p for p in psfs}.values():
        members = [c for c, p in enumerate(psfs) if p is group]
        if padding == "wrap":  # sizes checked in checked_blur_inputs
            offset, shape = 0, (rows, cols)
            padded = backend.asarray(channels[members])
        else:
            offset = psf_padding_width_px(group)
            shape = padded_shape((rows, cols), group.data.shape[0])
            widths = ((offset, shape[0] - rows - offset), (offset, shape[1] - cols - offset))
            padded = xp.stack([_pad(backend.asarray(channels[c]), widths, padding, backgrounds[c], channels[c], xp)
                               for c in members])
        blurred = convolve_padded(padded, group, backend)
        out[members] = backend.to_numpy(blurred[:, offset : offset + rows, offset : offset + cols])
    return out[0] if array.ndim == 2 else np.moveaxis(out, 0, -1)


def convolve_padded(padded, psf: PSF, backend: ArrayBackend = CPU, *, threads: int | None = None):
    """Planes (C, H, W) on ``backend`` convolved circularly with ``psf``: one batched real FFT pair, float32.

    Callers pad the planes first.  ``threads``: the CPU FFT's threads (default all; 1 for a caller
    that runs several convolutions at once).
    """
    shape = tuple(padded.shape[-2:])
    if backend is CPU:
        transfer = BlurKernel.prepare(psf, shape, dtype=np.float32, workers=-1 if threads is None else threads).transfer
    else:  # each (PSF, grid) is convolved once per call: its spectrum is sent, not kept
        transfer = backend.asarray(BlurKernel.prepare(psf, shape, dtype=np.float32).transfer)
    kwargs = backend.fft_kwargs() if threads is None or backend is not CPU else {"workers": threads}
    spectrum = backend.fft.rfft2(padded, axes=(-2, -1), **kwargs)
    spectrum *= transfer
    return backend.fft.irfft2(spectrum, s=shape, axes=(-2, -1), overwrite_x=True, **kwargs)


def convolve_window(planes, psf: PSF, padding: str, touches, backend: ArrayBackend = CPU, *,
                    threads: int | None = None) -> tuple:
    """Planes (C, h, w) of a window of an image, padded (`vissim.optics.blur.convolve.pad_window`) and convolved
    with ``psf`` (`convolve_padded`): (the blurred planes, the padded grid's shape).

    ``touches``: whether the window's (top, bottom, left, right) side is the image's border.  On the
    CPU the rows' transforms skip the padding rows (`_convolve_window_pruned`), to the same bits.  ``padding``: one
    of `WINDOW_PADDING_MODES`, whose padding rows are copies of the window's (the pruning's premise).
    """
    if padding not in WINDOW_PADDING_MODES:
        raise VissimInputError(f"a window's padding must be one of {', '.join(WINDOW_PADDING_MODES)}; got {padding!r}")
    _, h, w = planes.shape
    offset = padding_width_px(psf.data.shape[0])
    shape = padded_shape((h, w), psf.data.shape[0])
    widths = ((offset, shape[0] - h - offset), (offset, shape[1] - w - offset))
    if backend is CPU:
        return _convolve_window_pruned(planes, psf, padding, touches, widths, shape, threads), shape
    blurred = convolve_padded(pad_window(planes, widths, padding, touches, backend.xp), psf, backend, threads=threads)
    return blurred[:, offset : offset + h, offset : offset + w], shape


def _convolve_window_pruned(planes, psf: PSF, padding: str, touches, widths, shape: tuple[int, int],
                            threads: int | None):
    """`convolve_window` on the CPU, bit for bit, for about three quarters of the work: the real transforms along
    the rows run only on the planes' own rows.

    A 2-D real FFT transforms each row, then each column.  A padding row is zero or a copy of a
    plane's row (edge, reflect), so its row transform is zero or a copy: the rows' spectra are
    padded instead of the rows.  Backwards, only the planes' rows are transformed back, and the
    inverse's 1 / (rows x cols) is applied last, as SciPy's pocketfft applies it (the pinned SciPy;
    ``tests/test_depth_windows.py`` holds the two paths to the same bits).
    """
    _, h, w = planes.shape
    (top, bottom), (left, right) = widths
    workers = -1 if threads is None else threads
    fft = CPU.fft
    rows = fft.rfft(pad_window(planes, ((0, 0), (left, right)), padding, (False, False, *touches[2:])), axis=-1,
                    workers=workers)
    spectrum = fft.fft(pad_window(rows, ((top, bottom), (0, 0)), padding, (*touches[:2], False, False)), axis=-2,
                       workers=workers, overwrite_x=True)
    spectrum *= BlurKernel.prepare(psf, shape, dtype=np.float32, workers=workers).transfer
    spectrum = fft.ifft(spectrum, axis=-2, workers=workers, overwrite_x=True, norm="forward")
    blurred = fft.irfft(spectrum[:, top : top + h], n=shape[1], axis=-1, workers=workers, norm="forward")
    blurred *= blurred.dtype.type(1.0 / (shape[0] * shape[1]))
    return blurred[:, :, left : left + w]


def _pad(channel, widths, mode: str, background, host_channel: np.ndarray, xp):
    if mode == "constant":
        background = border_mean(host_channel) if background is None else float(background)
    return pad_array(channel, widths, mode, background, xp)
