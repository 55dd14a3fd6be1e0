"""Benchmark: DSLR-bench render time and noise against samples per pixel, per Mitsuba sampler.

    /tmp/venv/bin/python benchmarks/bench_render.py [--reference-spp 2048] [--spp 16,64,256]

Scene: the thesis tile (113 x 133 px at 1 arcmin/px), Sloan R at LogMAR 1.0, black on white,
a +2.00 D trial lens 10 mm in front of the 18 mm f/5 camera (24.7 arcmin blur disc).  The
reference is one multijitter render at ``--reference-spp`` with another seed; PSNR is over the
chart's white level (data range 0.9).  Each sampler's render time (best of ``--repeats``, after
one warm-up render that compiles the kernels) and PSNR are printed, with ratios to the
independent sampler measured in the same run.  No thresholds: the table is the result.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vissim.bench.dslr.bench import SAMPLERS, DslrBench, chart_mm_per_texel, dslr_scene
from vissim.charts import MM_PER_INCH, render_chart_print, single_letter_spec
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.run import render_scene

DATA_RANGE = 0.9  # white paper reflectance: the brightest value of the chart


def psnr_db(image: np.ndarray, reference: np.ndarray) -> float:
    mse = float(np.mean((image.astype(np.float64) - reference) ** 2))
    return float("inf") if mse == 0.0 else 10.0 * np.log10(DATA_RANGE**2 / mse)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference-spp", type=int, default=2048)
    parser.add_argument("--spp", default="16,64,256")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    spps = [int(v) for v in args.spp.split(",")]

    base = DslrBench(lenses=(TrialLens(2.0),))
    chart = render_chart_print(single_letter_spec("R", 1.0), MM_PER_INCH / chart_mm_per_texel(base))
    scene_of = {s: dslr_scene(DslrBench(lenses=base.lenses, sampler=s), chart.pixels, chart.mm_per_px)
                for s in SAMPLERS}
    start = time.perf_counter()
    reference_result = render_scene(scene_of["multijitter"], spp=args.reference_spp, seed=12345)
    reference = reference_result.pixels.astype(np.float64)
    print(f"variant {reference_result.variant}; reference: multijitter {args.reference_spp} spp in "
          f"{time.perf_counter() - start:.1f} s")

    rows = {}
    for sampler in SAMPLERS:
        render_scene(scene_of[sampler], spp=spps[0], seed=0)  # warm-up: compile
        for spp in spps:
            best = float("inf")
            for repeat in range(args.repeats):
                result = render_scene(scene_of[sampler], spp=spp, seed=repeat + 1)
                best = min(best, result.seconds)
            rows[sampler, spp] = (best, psnr_db(result.pixels, reference))

    print(f"{'sampler':>12} {'spp':>5} {'time (s)':>9} {'PSNR (dB)':>10} {'time/indep':>11} {'dPSNR vs indep':>15}")
    for sampler in SAMPLERS:
        for spp in spps:
            seconds, psnr = rows[sampler, spp]
            ref_seconds, ref_psnr = rows["independent", spp]
            print(f"{sampler:>12} {spp:>5} {seconds:>9.2f} {psnr:>10.2f} {seconds / ref_seconds:>11.2f} "
                  f"{psnr - ref_psnr:>+15.2f}")


if __name__ == "__main__":
    main()
