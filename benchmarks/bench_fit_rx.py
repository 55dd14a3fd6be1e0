"""Fit time of ``vissim fit-rx`` for one Sloan letter (LogMAR 1.0, 133 x 113 px at 1 arcmin/px, f/5 bench).

The capture is a synthetic +2.00 -1.00 x 30 trial lens (vissim's own forward chain, as in
``tests/fit/synthetic.py``, noise 0.002); the fit is geometric with the bench magnification tie,
as for a Mitsuba render.  Baseline, measured in the same run: one geometric PSF of the same
blur (``compute_psf``, ray histogram) followed by one ``blur_image`` of the tile -- what one
forward simulation of the campaign costs.  Prints the median of 3 runs and the ratio.

    .venv/bin/python benchmarks/bench_fit_rx.py
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from tests.fit import synthetic  # noqa: E402
from vissim.bench.dslr.bench import DslrBench  # noqa: E402
from vissim.fit.rx_fit import fit_rx  # noqa: E402
from vissim.optics.blur.convolve import blur_image  # noqa: E402
from vissim.optics.psf.compute import compute_psf, suggested_size_px  # noqa: E402
from vissim.optics.rx.trial_lens import TrialLens  # noqa: E402


def main() -> None:
    shape = (133, 113)
    bench = DslrBench(size_px=shape)
    synthetic.SHAPE = shape
    lens = TrialLens(2.0, -1.0, 30.0)
    image, reference, truth = synthetic.capture(lens, bench=bench)
    setup = DslrBench(lenses=(lens,), size_px=shape).viewing_setup()

    def baseline():
        front = setup.wavefront
        psf = compute_psf(front, arcmin_per_px=1.0, size_px=suggested_size_px(front, 1.0), mode="geometric")
        blur_image(reference, psf, arcmin_per_px=1.0, padding="edge")

    def fit():
        return fit_rx(image, reference, arcmin_per_px=1.0, pupil_diameter_mm=3.6, bench=bench)

    base = statistics.median(_time(baseline) for _ in range(3))
    times, result = [], None
    for _ in range(3):
        start = time.perf_counter()
        result = fit()
        times.append(time.perf_counter() - start)
    fit_s = statistics.median(times)
    error = np.max(np.abs(np.subtract(result.power_vector, truth)))
    print(f"cores: {os.cpu_count()}; tile {shape[0]} x {shape[1]} px; lens {lens.marked_power}")
    print(f"baseline (one geometric PSF + one blur): {1000 * base:.0f} ms")
    print(f"fit-rx (geometric, bench tie): {fit_s:.2f} s = {fit_s / base:.0f} x baseline; "
          f"{result.evaluations} model evaluations; status {result.status}; max power-vector error {error:.4f} D")


def _time(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


if __name__ == "__main__":
    main()
