"""Benchmark: blur of a 4K greyscale image against one rfft2 + irfft2 pair of the padded size.

    .venv/bin/python benchmarks/bench_blur.py

A 3840 x 2160 float32 image, a -2.00 DS PSF at 1 arcmin/px (3 mm pupil), constant padding.
Prints the blur time (kernel transform included, and with the kernel prepared once), the time
of one rfft2 + irfft2 pair of the same padded shape and precision, and the ratios.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.fft

from vissim.optics.blur import _padding_width, blur_image
from vissim.optics.prescription import Prescription
from vissim.optics.psf import compute_psf, suggested_size_px
from vissim.optics.wavefront import Wavefront


def best_of(fn, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    rows, cols = 2160, 3840
    image = np.random.default_rng(0).random((rows, cols), dtype=np.float32)
    front = Wavefront.from_prescription(Prescription(-2.0), 3.0)
    psf = compute_psf(front, arcmin_per_px=1.0, size_px=suggested_size_px(front, 1.0))
    width = _padding_width(psf)
    shape = (scipy.fft.next_fast_len(rows + 2 * width, real=True), scipy.fft.next_fast_len(cols + 2 * width, real=True))
    padded = np.zeros(shape, np.float32)

    def fft_pair():
        scipy.fft.irfft2(scipy.fft.rfft2(padded, workers=-1), s=shape, workers=-1)

    pair = best_of(fft_pair)
    blur = best_of(lambda: blur_image(image, psf, arcmin_per_px=1.0))
    print(f"image {cols}x{rows} float32, PSF {psf.data.shape[0]} px, padded {shape[1]}x{shape[0]}")
    print(f"rfft2+irfft2 pair: {1e3 * pair:8.1f} ms")
    print(f"blur_image:        {1e3 * blur:8.1f} ms   ratio {blur / pair:5.2f}  (includes the kernel's own rfft2)")


if __name__ == "__main__":
    main()
