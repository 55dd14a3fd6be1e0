"""Benchmark: vissim's wave PSF against prysm's ``focus_fixed_sampling``, measured in one run.

    .venv/bin/python -m pip install -c constraints.txt -e ".[bench]"   # prysm, benchmark-only
    .venv/bin/python benchmarks/bench_psf.py

The case (issue 12): -1.00 -0.50 x 30 at 550 nm, a 3.6 mm pupil, 0.25 arcmin/px, 512^2 and
1024^2 output.  prysm samples the pupil on 256 points (its matrix DFT, float64), and its
per-call work is timed: the phase from cached Zernike maps, the propagation and |E|^2.
vissim's is a whole ``compute_psf`` call (field check, sampling plan, pixel integration
included), in float32 (its default) and float64, with its path (matrix transform or FFT) chosen by itself;
both paths are also timed forced.  Printed: best-of times, the ratio vissim / prysm, and each
result's largest error against the independent quadrature oracle of the test suite
(``tests/fraunhofer_reference.py``) on a few dozen pixels, as a fraction of the peak: vissim's
pixel integrals against the oracle's, prysm's point samples against the oracle's point values.
prysm is also timed at finer pupils (512, 1024, 2048 samples): what approaching vissim's accuracy costs it.
The ratios stay against the 256-sample baseline; a second ratio puts vissim against prysm's finest pupil, which is
still less accurate than vissim (its error is printed): an upper bound on the ratio at equal accuracy.
No thresholds: the ratios are the result.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import fraunhofer_reference as oracle  # noqa: E402

PUPIL_MM, WAVELENGTH_NM, ARCMIN_PER_PX, RX = 3.6, 550.0, 0.25, "-1.00 -0.50 x 30"
PRYSM_SAMPLES = 256  # the baseline
#: prysm also at finer pupils, for the time it takes to approach vissim's accuracy (not a baseline).
PRYSM_FINER_SAMPLES = (512, 1024, 2048)
EFL_MM = 100.0  # any focal length: prysm samples its focal plane in microns


def best_of(fn, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def probe_offsets(size: int, peak: tuple[int, int], rng) -> np.ndarray:
    """Offsets (d_row, d_col) from the centre: the peak, a cross through it, random and corner pixels."""
    c = size // 2
    pr, pc = peak[0] - c, peak[1] - c
    cross = [(pr, pc + d) for d in range(-6, 7, 2)] + [(pr + d, pc) for d in range(-6, 7, 3)]
    rand = [tuple(x) for x in rng.integers(-size // 8, size // 8, size=(12, 2))]
    corners = [(-c, -c), (-c, size - 1 - c), (size - 1 - c, -c), (0, 0)]
    return np.array(cross + rand + corners, dtype=float)


def prysm_psf(size: int, samples: int = PRYSM_SAMPLES):
    """prysm's PSF as its users write it: returns the per-call function and its setup."""
    from prysm.coordinates import cart_to_polar, make_xy_grid
    from prysm.geometry import circle
    from prysm.polynomials import zernike_nm
    from prysm.propagation import focus_fixed_sampling

    front = Wavefront.from_prescription(Prescription.parse(RX), PUPIL_MM)
    x, y = make_xy_grid(samples, diameter=PUPIL_MM)
    r, t = cart_to_polar(x, y)
    mask = circle(PUPIL_MM / 2, r)
    # OSA terms as vissim's (prysm's zernike_nm with norm=True is the OSA/ANSI normalisation).
    rho, theta = r / (PUPIL_MM / 2), t
    basis = [(c, zernike_nm(n, m, rho, theta, norm=True)) for (n, m), c in front.coefficients_um.items()]
    dx = x[0, 1] - x[0, 0]
    output_dx_um = math.radians(ARCMIN_PER_PX / 60) * EFL_MM * 1e3
    k = 2 * math.pi / (WAVELENGTH_NM * 1e-3)

    def run():
        opd = sum(c * z for c, z in basis)
        wave = mask * np.exp(1j * k * opd)
        field = focus_fixed_sampling(wave, dx, EFL_MM, WAVELENGTH_NM * 1e-3, output_dx_um, size)
        return np.abs(field) ** 2

    # prysm's matrix DFT has its own normalisation: calibrate it on the unaberrated pupil's DC term.
    dc = focus_fixed_sampling(mask.astype(complex), dx, EFL_MM, WAVELENGTH_NM * 1e-3, output_dx_um, size)
    unit = (mask.sum() / abs(dc[size // 2, size // 2])) ** 2
    return run, mask.sum() / unit


def oracle_error(values: np.ndarray, offsets: np.ndarray, front: Wavefront, integrate: bool, scale: float) -> float:
    c = values.shape[0] // 2
    reference = oracle.pixel_values(front.coefficients_um, front.pupil_diameter_mm, PUPIL_MM, WAVELENGTH_NM,
                                    ARCMIN_PER_PX, offsets, integrate=integrate)
    mine = np.array([values[int(c + r), int(c + q)] for r, q in offsets]) * scale
    return float(np.max(np.abs(mine - reference)) / np.max(reference))


def main() -> None:
    front = Wavefront.from_prescription(Prescription.parse(RX), PUPIL_MM)
    rng = np.random.default_rng(12)
    print(f"{RX} at {WAVELENGTH_NM:g} nm, {PUPIL_MM:g} mm pupil, {ARCMIN_PER_PX:g} arcmin/px; "
          f"prysm {PRYSM_SAMPLES} pupil samples (matrix DFT, float64)")
    finest = PRYSM_FINER_SAMPLES[-1]
    print(f"{'size':>5} {'who':>22} {'internal':>9} {'cells':>6} {'best (ms)':>10} {'/ prysm':>8} {'error/peak':>11} "
          f"{'/ prysm ' + str(finest):>13}")
    for size in (512, 1024):
        reference_psf = compute_psf(front, arcmin_per_px=ARCMIN_PER_PX, size_px=size, dtype=np.float64)
        peak = np.unravel_index(np.argmax(reference_psf.data), reference_psf.data.shape)
        offsets = probe_offsets(size, peak, rng)
        prysm_time = None
        for samples in (PRYSM_SAMPLES, *PRYSM_FINER_SAMPLES):
            run, area = prysm_psf(size, samples)
            elapsed = best_of(run, repeats=5 if samples < finest else 2)
            prysm_time = prysm_time or elapsed
            # prysm's frame: a slope +x lands at +col, +y at +row; vissim's is rotated by 180 degrees.
            # Turned after the timing (|E|^2 of the reversed view alone took 10-57 ms, 4x prysm's DFT).
            intensity = np.roll(run()[::-1, ::-1], (1, 1), axis=(0, 1))
            dx_mm = PUPIL_MM / samples
            pixel_rad = math.radians(ARCMIN_PER_PX / 60)
            scale = (dx_mm * pixel_rad / (WAVELENGTH_NM * 1e-6)) ** 2 / area  # |E|^2 -> energy per pixel
            error = oracle_error(intensity, offsets, front, integrate=False, scale=scale)
            print(f"{size:>5} {'prysm':>22} {'':>9} {samples:>6} {1e3 * elapsed:>10.1f} {elapsed / prysm_time:>8.2f} "
                  f"{error:>11.1e}")
            finest_time, finest_error = elapsed, error
        vissim_errors = []
        for dtype in (np.float32, np.float64):
            for method in (None, "mft", "fft"):
                kwargs = dict(arcmin_per_px=ARCMIN_PER_PX, size_px=size, dtype=dtype, method=method)
                psf = compute_psf(front, **kwargs)  # warms the caches
                elapsed = best_of(lambda: compute_psf(front, **kwargs))
                plan = psf.sampling[0]
                error = oracle_error(psf.data, offsets, front, integrate=True, scale=psf.energy_in_field)
                who = f"vissim {np.dtype(dtype).name} {method or 'auto=' + plan.method}"
                print(f"{size:>5} {who:>22} {plan.internal_size:>9} {plan.pupil_cells:>6.0f} {1e3 * elapsed:>10.1f} "
                      f"{elapsed / prysm_time:>8.2f} {error:>11.1e} {elapsed / finest_time:>13.2f}")
                vissim_errors.append(error)
        print(f"{size:>5} prysm at {finest} samples is still {finest_error / max(vissim_errors):.0f}x less accurate than "
              "vissim's least accurate row: at equal accuracy the ratio is below the last column")


if __name__ == "__main__":
    main()
