"""Benchmark: fixed-order sample sums (vissim) against Mitsuba's atomic film, time and repeatability.

    .venv/bin/python benchmarks/bench_accumulation.py [--spp 64,128,256,1024] [--repeats 7] [--lens-d 0]

Scene: the ``vissim render bench`` default (133 x 113 px, Sloan R at LogMAR 1.0, f/5, no lens;
``--lens-d`` adds a trial lens).  For each spp, both ways render the loaded scene alternately
``--repeats`` times after a warm-up that compiles the kernels; the best and median seconds are
printed, with the pixels that differ between two renders of one seed.  No thresholds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vissim.bench.dslr.bench import DslrBench, chart_mm_per_texel, dslr_scene
from vissim.charts import MM_PER_INCH, render_chart_print, single_letter_spec
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.backend import mitsuba
from vissim.render.fixed_order import render_image
from vissim.render.plugins import register_plugins
from vissim.render.run import to_mitsuba_dict


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", default="64,128,256,1024")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--lens-d", type=float, default=0.0)
    args = parser.parse_args()
    bench = DslrBench(lenses=(TrialLens(args.lens_d),) if args.lens_d else ())
    chart = render_chart_print(single_letter_spec("R", 1.0), MM_PER_INCH / chart_mm_per_texel(bench))
    mi = mitsuba("mono")
    register_plugins(mi)
    scene = mi.load_dict(to_mitsuba_dict(dslr_scene(bench, chart.pixels, chart.mm_per_px), mi))
    ways = {"mitsuba atomic": lambda spp, seed: np.asarray(mi.render(scene, spp=spp, seed=seed)),
            "fixed-order": lambda spp, seed: render_image(mi, scene, spp, seed).image}
    print(f"{mi.variant()}, {bench.size_px[1]} x {bench.size_px[0]} px, lens {args.lens_d:+.2f} D")
    print(f"{'spp':>5} {'way':>15} {'best s':>8} {'median s':>9} {'px differing':>13}")
    for spp in (int(v) for v in args.spp.split(",")):
        times: dict[str, list[float]] = {way: [] for way in ways}
        images: dict[str, list[np.ndarray]] = {way: [] for way in ways}
        for way, render in ways.items():
            render(spp, 0)  # warm-up: compile
        for _ in range(args.repeats):
            for way, render in ways.items():
                start = time.perf_counter()
                images[way].append(render(spp, 0))
                times[way].append(time.perf_counter() - start)
        for way in ways:
            differing = max(int(np.count_nonzero(images[way][0] != im)) for im in images[way][1:])
            print(f"{spp:5d} {way:>15} {min(times[way]):8.3f} {np.median(times[way]):9.3f} {differing:13d}")


if __name__ == "__main__":
    main()
