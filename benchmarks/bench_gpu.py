"""The GPU check: the CuPy blur, Mitsuba's ``cuda_*`` eye render and the population, each against the CPU, in one run.

    .venv/bin/python -m pip install -c constraints.txt -e ".[gpu]"   # CuPy for CUDA 12, on the GPU machine
    .venv/bin/python benchmarks/bench_gpu.py

Three parts, each timed on the CPU and on the GPU in the same run (best of a few, after a warm-up that compiles
kernels and plans FFTs), each printing ``ratio GPU/CPU`` and how far the two results are apart:

* **blur**: a 1920 x 1080 chart blurred by a -2.00 -1.00 x 30 eye's PSF (3 mm, 550 nm, 1 arcmin/px):
  `vissim.optics.blur.convolve.blur_image` against `vissim.optics.blur.device.blur_image_on` with
  ``device="cuda"``; the difference as PSNR (dB) of the GPU's image against the CPU's.
* **eye render**: ``vissim render eye``'s scene (Navarro 1985, 3 mm, a Sloan letter at 6 m, 256 x 256 px,
  256 spp) on the CPU variant vissim chooses and on ``cuda_ad_mono``; the difference as the two renders' PSNR
  (their noise differs: equal seeds on different devices draw different samples, so this is near the noise
  floor, not 100 dB).
* **population**: 40 measured eyes (Jaeken & Artal 2012, 4 mm, uncorrected) in one process against as many
  processes as the machine has cores; the population is NumPy code, so this is the CPU's own scaling on the
  GPU machine, printed for the README beside the others.

A part whose device is missing prints why and is skipped; the script then exits 0.  No thresholds: the ratios are
the result.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

REPEATS = 3


def best_seconds(run, repeats: int = REPEATS) -> tuple[float, object]:
    """(the fastest of ``repeats`` runs after a warm-up, the last result)."""
    result = run()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def psnr_db(reference: np.ndarray, other: np.ndarray) -> float:
    """PSNR (dB) of ``other`` against ``reference``, peak the reference's largest value."""
    from vissim.imaging.metrics import psnr_db as psnr

    reference, other = np.asarray(reference, dtype=np.float64), np.asarray(other, dtype=np.float64)
    return psnr(float(np.mean((other - reference) ** 2)), float(np.max(reference)) or 1.0)


def blur_part() -> None:
    from vissim.charts import etdrs_chart_spec, render_chart_angular
    from vissim.checks import DEFAULT_WAVELENGTH_NM
    from vissim.optics.blur.convolve import blur_image, image_kernel_psf
    from vissim.optics.blur.device import blur_image_on
    from vissim.optics.pupil.wavefront import Wavefront
    from vissim.optics.rx.prescription import Prescription
    from vissim.optics.runtime.array_backend import cuda_available

    chart = render_chart_angular(etdrs_chart_spec(), 1.0).pixels.astype(np.float32)
    image = np.zeros((1080, 1920), np.float32) + chart.mean()
    rows, cols = min(chart.shape[0], 1080), min(chart.shape[1], 1920)
    image[:rows, :cols] = chart[:rows, :cols]
    front = Wavefront.from_prescription(Prescription.parse("-2.00 -1.00 x 30"), 3.0)
    psf = image_kernel_psf(front, image.shape, arcmin_per_px=1.0, wavelength_nm=DEFAULT_WAVELENGTH_NM)
    cpu_seconds, cpu = best_seconds(lambda: blur_image(image, psf, arcmin_per_px=1.0))
    print(f"blur 1920x1080, PSF {psf.size_px} px: CPU {cpu_seconds:.3f} s")
    if not cuda_available():
        print("blur on the GPU: skipped (no CuPy with a CUDA device)")
        return
    gpu_seconds, gpu = best_seconds(lambda: blur_image_on(image, psf, arcmin_per_px=1.0, device="cuda"))
    print(f"blur on the GPU: {gpu_seconds:.3f} s; ratio GPU/CPU {gpu_seconds / cpu_seconds:.3f}; "
          f"PSNR of the GPU's image against the CPU's {psnr_db(cpu, gpu):.1f} dB")


def render_part() -> None:
    from vissim.render.backend import choose_variant
    from vissim.render.eye_render import EyeRender, render_eye

    settings = EyeRender(size_px=(256, 256), spp=256)
    cpu_variant = choose_variant("mono").variant
    cpu_seconds, cpu = best_seconds(lambda: render_eye(settings, cpu_variant), repeats=2)
    print(f"eye render 256x256 at 256 spp: {cpu_variant} {cpu_seconds:.2f} s")
    try:
        gpu_seconds, gpu = best_seconds(lambda: render_eye(settings, "cuda_ad_mono"), repeats=2)
    except Exception as error:  # noqa: BLE001  (no CUDA: Mitsuba says why in its own words)
        print(f"eye render on cuda_ad_mono: skipped ({str(error).splitlines()[0]})")
        return
    print(f"eye render on cuda_ad_mono: {gpu_seconds:.2f} s; ratio GPU/CPU {gpu_seconds / cpu_seconds:.3f}; "
          f"PSNR between the two renders {psnr_db(cpu.pixels, gpu.pixels):.1f} dB")


def population_part() -> None:
    from vissim.optics.eyes.defaults import POPULATION_MTF_CYC_PER_DEG
    from vissim.optics.eyes.measured.population import PopulationCondition, evaluate_population, select_eyes

    eyes = select_eyes("jaeken-artal-2012")[:40]
    condition = [PopulationCondition(pupil_mm=4.0, correction="uncorrected")]
    frequencies = POPULATION_MTF_CYC_PER_DEG
    one_seconds, _ = best_seconds(lambda: evaluate_population(eyes, condition, frequencies), repeats=1)
    cores = os.cpu_count() or 1
    many_seconds, _ = best_seconds(lambda: evaluate_population(eyes, condition, frequencies, workers=cores),
                                   repeats=1)
    print(f"population of {len(eyes)} eyes: 1 process {one_seconds:.2f} s ({1000 * one_seconds / len(eyes):.0f} ms "
          f"an eye), {cores} processes {many_seconds:.2f} s; ratio {many_seconds / one_seconds:.3f}")


def main() -> None:
    for part in (blur_part, render_part, population_part):
        part()


if __name__ == "__main__":
    main()
