"""Benchmark: PSF computation against a bare FFT of the same size, measured in one run.

    .venv/bin/python benchmarks/bench_psf.py

Prints, for 512^2 and 1024^2 output fields, the time of a PSF (defocus + astigmatism, 3 mm
pupil, 550 nm, sampling chosen so the internal FFT equals the output size) with the pupil
grid cached, the time of one complex FFT of that size (scipy.fft.fft2, same workers), and
their ratio.  No thresholds: the ratio is the result.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import scipy.fft

from vissim.optics.prescription import Prescription
from vissim.optics.psf import compute_psf
from vissim.optics.wavefront import Wavefront


def best_of(fn, repeats: int = 7) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times), statistics.median(times)


def main() -> None:
    print(f"{'size':>6} {'dtype':>8} {'fft_size':>8} {'q':>3} {'PSF best (ms)':>14} {'FFT best (ms)':>14} {'ratio':>6}")
    for size, dtype in ((512, np.float64), (512, np.float32), (1024, np.float64), (1024, np.float32)):
        front = Wavefront.from_prescription(Prescription.parse("-0.50 -0.25 x 30"), 3.0)
        kwargs = dict(arcmin_per_px=0.25, size_px=size, dtype=dtype)
        psf = compute_psf(front, **kwargs)  # warms the pupil-grid cache
        sampling = psf.sampling[0]
        field = (np.random.default_rng(0).random((sampling.fft_size,) * 2) + 0j).astype(
            np.complex64 if dtype == np.float32 else np.complex128
        )
        psf_best, _ = best_of(lambda: compute_psf(front, **kwargs))
        fft_best, _ = best_of(lambda: scipy.fft.fft2(field, workers=-1))
        print(
            f"{size:>6} {np.dtype(dtype).name:>8} {sampling.fft_size:>8} {sampling.oversample:>3} {1e3 * psf_best:>14.2f} "
            f"{1e3 * fft_best:>14.2f} {psf_best / fft_best:>6.2f}"
        )


if __name__ == "__main__":
    main()
