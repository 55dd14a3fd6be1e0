"""Benchmark: what hero-wavelength termination costs in variance, spectral bench renders at equal spp.

    .venv/bin/python benchmarks/bench_dispersion.py [--spp 16] [--seeds 8] [--sampler multijitter] [--lens-d 2]

Scene: the DSLR bench (``vissim render bench --spectral``), 64 x 64 px at 1 arcmin/px, a trial lens of
``--lens-d`` dioptres, two charts: Sloan K at LogMAR 1.0 and a uniform white.  Each is rendered
``--seeds`` times with the dispersive lens (one wavelength per path after the lens, weighted by 4)
and with the same lens made non-dispersive (all four of a path's wavelengths carried); printed:
the per-pixel variance over the seeds (mean over pixels) of each, their ratio, the means (they
agree: termination is unbiased) and seconds per render.  No thresholds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vissim.bench.dslr.bench import SAMPLERS, DslrBench, chart_mm_per_texel, dslr_scene
from vissim.charts import MM_PER_INCH, render_chart_print, single_letter_spec
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.run import render_scene


def seeds_variance(scene: dict, spp: int, seeds: int) -> tuple[float, float, float]:
    """(per-pixel variance over the seeds, mean over pixels; image mean; seconds per render)."""
    start = time.perf_counter()
    stack = np.stack([render_scene(scene, kind="spectral", spp=spp, seed=seed).pixels.astype(np.float64)
                      for seed in range(seeds)])
    return float(stack.var(axis=0, ddof=1).mean()), float(stack.mean()), (time.perf_counter() - start) / seeds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--sampler", choices=SAMPLERS, default="multijitter")
    parser.add_argument("--lens-d", type=float, default=2.0)
    args = parser.parse_args()
    bench = DslrBench(lenses=(TrialLens(args.lens_d),), size_px=(64, 64), spp=args.spp, sampler=args.sampler)
    letter = render_chart_print(single_letter_spec("K", 1.0), MM_PER_INCH / chart_mm_per_texel(bench))
    charts = {"Sloan K, LogMAR 1.0": (letter.pixels, letter.mm_per_px),
              "uniform white": (np.ones((400, 400), np.float32), 0.5)}
    print(f"{args.lens_d:+.2f} D lens, 64 x 64 px, {args.spp} spp, {args.sampler}, {args.seeds} seeds")
    for name, (pixels, mm) in charts.items():
        hero_scene = dslr_scene(bench, pixels, mm, kind="spectral")
        carried_scene = dslr_scene(bench, pixels, mm, kind="spectral")
        del carried_scene["lens_0"]["bsdf"]["dispersion"]
        hero, carried = seeds_variance(hero_scene, args.spp, args.seeds), seeds_variance(carried_scene, args.spp, args.seeds)
        print(f"{name}: per-pixel variance, hero only {hero[0]:.3e}, four wavelengths {carried[0]:.3e}: "
              f"ratio {hero[0] / carried[0]:.2f}; means {hero[1]:.5f} and {carried[1]:.5f}; "
              f"{hero[2]:.2f} s and {carried[2]:.2f} s per render")


if __name__ == "__main__":
    main()
