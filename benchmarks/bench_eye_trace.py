"""Benchmark: the traced wavefront of a schematic eye against one wave PSF of it, measured in one run.

    .venv/bin/python benchmarks/bench_eye_trace.py

The case (issue 26): the wide-angle Navarro eye (``escudero-sanz-1999``) at 10° horizontal field,
555 nm, a 4 mm entrance pupil. Timed: ``trace_eye_wavefront`` at its defaults (65 samples across
the iris, aimed through the cornea, traced to the retina, the reference-sphere OPD, the real-ray
entrance-pupil coordinates and the OSA Zernike fit to order 8), and, as the baseline, one wave
PSF of that wavefront (``compute_psf``, float32, 0.25 arcmin/px, the field sized by itself).
Printed: the median of a few runs of each and the ratio trace / PSF. No thresholds: the ratio is
the result.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vissim.optics.eyes.models import escudero_sanz_1999  # noqa: E402
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront  # noqa: E402
from vissim.optics.psf.compute import compute_psf  # noqa: E402
from vissim.optics.pupil.wavefront import Wavefront  # noqa: E402

FIELD_DEG, WAVELENGTH_NM, PUPIL_MM, ARCMIN_PER_PX, REPEATS = (10.0, 0.0), 555.0, 4.0, 0.25, 5


def median_time(fn, repeats: int = REPEATS) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    eye = escudero_sanz_1999()

    def trace():
        return trace_eye_wavefront(eye, WAVELENGTH_NM, FIELD_DEG, pupil_mm=PUPIL_MM)

    traced = trace()
    wavefront = Wavefront({k: v for k, v in traced.zernike_um.items() if k[0] >= 2}, PUPIL_MM)

    def psf():
        return compute_psf(wavefront, wavelength_nm=WAVELENGTH_NM, arcmin_per_px=ARCMIN_PER_PX, size_px="auto")

    size = psf().data.shape
    t_trace, t_psf = median_time(trace), median_time(psf)
    print(f"{eye.name}, field {FIELD_DEG} deg, {WAVELENGTH_NM:g} nm, entrance pupil {PUPIL_MM:g} mm "
          f"(iris {traced.iris_mm:.3f} mm), {traced.x_mm.size} rays, RMS {traced.rms_um:.4f} µm")
    print(f"trace + Zernike fit : {1e3 * t_trace:8.1f} ms (median of {REPEATS})")
    print(f"one wave PSF        : {1e3 * t_psf:8.1f} ms ({size[0]} x {size[1]} px at {ARCMIN_PER_PX:g} arcmin/px)")
    print(f"ratio trace / PSF   : {t_trace / t_psf:8.2f}")


if __name__ == "__main__":
    main()
