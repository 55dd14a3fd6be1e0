"""Benchmark: render throughput of the schematic-eye sensor against Mitsuba's ``thinlens``, in one run.

    .venv/bin/python benchmarks/bench_eye_sensor.py [MODEL]

The scene is ``vissim render eye``'s (`vissim.render.eye_render.eye_scene_dict`, the eye bench's scene: a Sloan letter
at 6 m, no trial lens), 128 x 128 px at 1 arcmin/px, 64 spp, independent sampler, on the variant
vissim chooses.  Timed: ``mi.render`` of the scene with the ``vissim_schematic_eye`` sensor
(default Navarro 1985, 3 mm entrance pupil, 589.3 nm) and of the same scene with a ``thinlens``
camera of the same film, field of view and pupil, each after one warm-up render (the JIT
compiles its kernels once); the sensor's tables (made at scene load) are not in the time.
Printed: the median of a few renders, samples per second of each, and the ratio.
No thresholds: the ratio is the result.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vissim.render.backend import mitsuba  # noqa: E402
from vissim.render.eye_render import EyeRender, eye_scene_dict  # noqa: E402
from vissim.render.run import to_mitsuba_dict  # noqa: E402
from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor  # noqa: E402

SIZE, SPP, REPEATS = 128, 64, 5


def median_seconds(mi, scene) -> float:
    mi.render(scene, spp=SPP, seed=0)  # warm-up: kernels compiled
    times = []
    for seed in range(1, REPEATS + 1):
        start = time.perf_counter()
        image = mi.render(scene, spp=SPP, seed=seed)
        import drjit as dr

        dr.eval(image)
        dr.sync_thread()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    model = sys.argv[1] if len(sys.argv) > 1 else "navarro-1985"
    settings = EyeRender(model=model, size_px=(SIZE, SIZE), spp=SPP)
    mi = mitsuba("mono")
    register_schematic_eye_sensor(mi)
    eye_dict = eye_scene_dict(settings)
    lens_dict = dict(eye_dict)
    lens_dict["camera"] = {"type": "thinlens", "fov": SIZE * settings.arcmin_per_px / 60.0, "fov_axis": "x",
                           "aperture_radius": 0.5 * settings.pupil_mm,
                           "focus_distance": 1000.0 * settings.chart_distance_m,
                           "to_world": eye_dict["camera"]["to_world"], "film": eye_dict["camera"]["film"],
                           "sampler": eye_dict["camera"]["sampler"]}
    start = time.perf_counter()
    eye_scene = mi.load_dict(to_mitsuba_dict(eye_dict, mi))
    load_seconds = time.perf_counter() - start
    lens_scene = mi.load_dict(to_mitsuba_dict(lens_dict, mi))
    samples = SIZE * SIZE * SPP
    eye_s, lens_s = median_seconds(mi, eye_scene), median_seconds(mi, lens_scene)
    print(f"{mi.variant()}, {SIZE}x{SIZE} px, {SPP} spp ({samples} samples), {model}, median of {REPEATS}")
    print(f"  schematic eye: {eye_s:.3f} s = {samples / eye_s:,.0f} samples/s "
          f"(scene load with its tables {load_seconds:.2f} s)")
    print(f"  thinlens:      {lens_s:.3f} s = {samples / lens_s:,.0f} samples/s")
    print(f"  throughput ratio thinlens / schematic eye: {eye_s / lens_s:.2f}")


if __name__ == "__main__":
    main()
