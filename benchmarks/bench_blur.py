"""Benchmark: blur of a 4K greyscale image against one rfft2 + irfft2 pair of the padded size.

    .venv/bin/python benchmarks/bench_blur.py

A 3840 x 2160 float32 image, a -2.00 DS PSF at 1 arcmin/px (3 mm pupil), constant padding.
Prints the time of one rfft2 + irfft2 pair of the padded shape and precision, the blur time
with the kernel's transform computed in the call (a new PSF object each time), the blur time
when the same PSF blurs another image (its transform reused), and the ratios to the pair:
of the best times, and the median of each round's ratio (a blur timed right after a pair, so
that the machine's speed, which drifts between runs on a shared VM, cancels).
The blur takes the overlap-save path in squares when its operation count says so (printed).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import scipy.fft

from vissim.optics.blur.convolve import _tile_px, blur_image, padded_shape
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


ROUNDS = 15


def main() -> None:
    rows, cols = 2160, 3840
    image = np.random.default_rng(0).random((rows, cols), dtype=np.float32)
    front = Wavefront.from_prescription(Prescription(-2.0), 3.0)
    psf = compute_psf(front, arcmin_per_px=1.0, size_px=suggested_size_px(front, 1.0))
    shape = padded_shape((rows, cols), psf.data.shape[0])
    padded = np.zeros(shape, np.float32)

    def fft_pair():
        scipy.fft.irfft2(scipy.fft.rfft2(padded, workers=-1), s=shape, workers=-1)

    blur_image(image, psf, arcmin_per_px=1.0)
    rounds = np.array([
        (timed(fft_pair), timed(lambda: blur_image(image, dataclasses.replace(psf), arcmin_per_px=1.0)),
         timed(fft_pair), timed(lambda: blur_image(image, psf, arcmin_per_px=1.0)))
        for _ in range(ROUNDS)
    ])
    pair = rounds[:, [0, 2]].min()
    cold, warm = rounds[:, 1].min(), rounds[:, 3].min()
    cold_median, warm_median = np.median(rounds[:, 1] / rounds[:, 0]), np.median(rounds[:, 3] / rounds[:, 2])
    tile = _tile_px((rows, cols), psf.data.shape[0])
    path = f"overlap-save in {tile} px squares" if tile else "one FFT of the padded size"
    print(f"image {cols}x{rows} float32, PSF {psf.data.shape[0]} px, padded {shape[1]}x{shape[0]}; blur by {path}")
    print(f"{ROUNDS} rounds; ratios to the pair: of the best times, and the median of the rounds' ratios")
    print(f"rfft2+irfft2 pair:          {1e3 * pair:8.1f} ms")
    print(f"blur_image, new PSF:        {1e3 * cold:8.1f} ms   ratio {cold / pair:5.2f}  median {cold_median:5.2f}"
          "  (its transform computed)")
    print(f"blur_image, same PSF again: {1e3 * warm:8.1f} ms   ratio {warm / pair:5.2f}  median {warm_median:5.2f}"
          "  (its transform reused)")


if __name__ == "__main__":
    main()
