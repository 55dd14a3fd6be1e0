"""Benchmark: depth-dependent blur of a 1080p RGB-D image against one blur_image and the naive layer floor.

    .venv/bin/python benchmarks/bench_depth.py [--cli | --cli-only] [--repeats N] [--baseline CHECKOUT]

Scene (synthetic, linear RGB noise textures, the hardest case for every FFT shortcut): a wall at
8 m over the top half, a floor sloping from 8 m (horizon) to 0.33 m (bottom row), and panels at
3, 1.5, 0.8 and 0.33 m.  Eye: uncorrected -1.50 DS, 4 mm pupil, relaxed, 1 arcmin/px, 550 nm
wave optics, the default layering (spacing fraction 0.5: 82 layers).  Issue 15's case.

Measured in the same run, best of ``--repeats`` each, interleaved:

* ``blur_depth`` with its PSFs computed (cold: the PSF cache cleared) and cached (warm);
* ``blur_image`` of the same image with one PSF (the widest layer's, edge padding);
* the window floor: the FFT convolutions of the layers' windows alone (the planes and PSFs
  ``blur_depth`` hands `vissim.optics.blur.device.convolve_window`, recorded in one call), spread
  over as many threads as ``blur_depth`` uses: what is left when extension, PSFs and compositing
  cost nothing;
* the naive per-layer floor: per non-empty layer, the kernel's transform and one batched
  real FFT pair of 3 colour planes + coverage on the full padded frame (what the layered blur
  cost before it cropped each layer to its support), times the number of layers;
* with ``--cli`` (``--cli-only``: this alone): ``vissim blur-depth`` and ``vissim blur`` of the
  same files, each a fresh process (imports, EXR reading and writing, PSFs: everything a user
  waits for), so every run is cold (nothing is cached across processes).  Printed per run: the
  wall and CPU seconds of each and their ratio; then the best-of ratio and the runs' spread;
* with ``--baseline CHECKOUT`` too: ``vissim blur-depth`` and ``vissim blur`` from another checkout
  of vissim (a git worktree of an older commit, run by this interpreter), interleaved with the
  others: each command's median here over there (a change's effect measured in one run), and the
  ratio blur-depth / blur in each checkout.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import scipy.fft

from vissim.optics.blur.convolve import BlurKernel, blur_image, padded_shape, padding_width_px
from vissim.optics.blur.device import convolve_window
from vissim.optics.depth import composite, windows
from vissim.optics.depth.depth_map import blur_depth
from vissim.optics.depth.psfs import cached_psf, worker_threads
from vissim.optics.runtime.array_backend import CPU
from vissim.optics.rx.prescription import Prescription
from vissim.optics.pupil.wavefront import Wavefront

ROWS, COLS = 1080, 1920
PUPIL_MM, STEP, EYE = 4.0, 1.0, Prescription(-1.5)


def scene() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    image = rng.random((ROWS, COLS, 3), dtype=np.float32)
    depth = np.full((ROWS, COLS), 8.0)
    horizon = ROWS // 2
    depth[horizon:] = (1.0 / np.linspace(1 / 8.0, 1 / 0.33, ROWS - horizon))[:, None]
    for (top, left, height, width), metres in zip(
        [(150, 150, 400, 300), (300, 600, 450, 350), (200, 1100, 500, 300), (600, 1450, 450, 400)], [3.0, 1.5, 0.8, 0.33]
    ):
        depth[top : top + height, left : left + width] = metres
        image[top : top + height, left : left + width] *= np.array([0.9, 0.6, 0.3], np.float32)
    return image, depth


def naive_layer(planes: np.ndarray, psf, shape: tuple[int, int]) -> None:
    """One layer the naive way: its kernel's transform, 4 planes padded to the frame, rfft2 / irfft2."""
    offset = psf.data.shape[0] // 2 + 1
    padded = np.pad(planes, ((0, 0), (offset, shape[0] - planes.shape[1] - offset),
                             (offset, shape[1] - planes.shape[2] - offset)), mode="edge")
    transfer = BlurKernel.prepare(psf, shape).transfer
    spectrum = scipy.fft.rfft2(padded, axes=(-2, -1), workers=-1)
    spectrum *= transfer
    scipy.fft.irfft2(spectrum, s=shape, axes=(-2, -1), workers=-1, overwrite_x=True)


def window_inputs(image: np.ndarray, depth: np.ndarray, kwargs: dict) -> list[tuple]:
    """The arguments of every layer's FFT convolution in one ``blur_depth``, on the image's grid (`composite`) or the
    coarse one (`windows.blur_coarse`): (planes, psf, padding, touches)."""
    calls = []

    def recording(planes, psf, padding, touches, backend, threads=None):
        calls.append((planes.copy(), psf, padding, touches))
        return convolve_window(planes, psf, padding, touches, backend, threads=threads)

    for module in (composite, windows):
        module.convolve_window = recording
    try:
        blur_depth(image, depth, **kwargs)
    finally:
        for module in (composite, windows):
            module.convolve_window = convolve_window
    return calls


def window_floor(calls: list[tuple]) -> float:
    """Seconds to convolve the layers' windows alone, spread over one thread per core as blur_depth spreads them."""
    threads = worker_threads(CPU)
    start = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        list(pool.map(lambda call: convolve_window(*call, CPU, threads=1), calls))
    return time.perf_counter() - start


def best(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def cli_times(image: np.ndarray, depth: np.ndarray, repeats: int, coarse_blur_px=None,
              baseline: Path | None = None) -> dict[str, list]:
    """Wall and CPU seconds (user + system) of each command, per repeat: {name: [(wall_s, cpu_s), ...]};
    with ``baseline`` (another checkout of vissim), its two commands too ("baseline blur-depth", "baseline blur")."""
    from vissim.imageio import write_data_map, write_image

    with tempfile.TemporaryDirectory() as folder:
        rgb, depth_file, out = Path(folder, "rgb.exr"), Path(folder, "depth.exr"), Path(folder, "out.exr")
        write_image(rgb, image, arcmin_per_px=STEP)
        write_data_map(depth_file, depth.astype(np.float32), arcmin_per_px=STEP)
        eye = ["--rx", EYE.format(), "--pupil-mm", f"{PUPIL_MM:g}", "--overwrite"]
        commands = {"blur": ["blur", str(rgb), "-o", str(out), *eye],
                    "blur-depth": ["blur-depth", str(rgb), str(depth_file), "-o", str(out), *eye]
                    + ([] if coarse_blur_px is None else ["--coarse-blur-px", f"{coarse_blur_px:g}"])}
        roots = dict.fromkeys(commands, Path(__file__).resolve().parents[1])
        if baseline is not None:
            for name in ("blur-depth", "blur"):
                commands[f"baseline {name}"], roots[f"baseline {name}"] = commands[name], baseline.resolve()
        times = {name: [] for name in commands}
        for _ in range(repeats):  # interleaved, so a busy machine slows all alike
            for name, argv in commands.items():
                env = dict(os.environ, PYTHONPATH=str(roots[name]))
                before, start = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
                subprocess.run([sys.executable, "-m", "vissim", *argv], check=True, capture_output=True, env=env,
                               cwd=roots[name])  # python -m looks in the working folder first
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                times[name].append((time.perf_counter() - start, cpu))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="best of N (default 3)")
    parser.add_argument("--cli", action="store_true", help="also time the two commands (fresh processes)")
    parser.add_argument("--cli-only", action="store_true", help="time only the two commands")
    parser.add_argument("--coarse-blur-px", type=float, help="blur_depth's coarse_blur_px (default: off)")
    parser.add_argument("--baseline", type=Path, metavar="CHECKOUT",
                        help="with --cli/--cli-only: also time both commands from another checkout of vissim (e.g. a "
                             "git worktree of an older commit), interleaved, and print new / baseline")
    args = parser.parse_args()
    if args.baseline is not None and not (args.cli or args.cli_only):
        parser.error("--baseline times the commands: give it with --cli or --cli-only")
    image, depth = scene()
    if args.cli_only:
        return print_cli_times(image, depth, args)
    kwargs = dict(rx=EYE, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
                  coarse_blur_px=args.coarse_blur_px)

    def cold():
        cached_psf.cache_clear()
        return blur_depth(image, depth, **kwargs)

    result = cold()
    widest = max(result.layers, key=lambda layer: layer.psf_size_px)
    front = Wavefront.from_prescription(EYE, PUPIL_MM).with_defocus_diopters(widest.proximity_diopters)
    single_psf = cached_psf(tuple(front.coefficients_um.items()), PUPIL_MM, 550.0, STEP, "wave")
    offset = padding_width_px(widest.psf_size_px)
    frame = padded_shape((ROWS, COLS), widest.psf_size_px)
    planes = np.ascontiguousarray(np.moveaxis(np.concatenate([image, image[..., :1]], axis=-1), -1, 0))

    window_calls = window_inputs(image, depth, kwargs)
    timings = {"cold": [], "warm": [], "single": [], "floor": [], "windows": []}
    for _ in range(args.repeats):
        timings["cold"].append(best(cold, 1))
        timings["warm"].append(best(lambda: blur_depth(image, depth, **kwargs), 1))
        timings["single"].append(best(lambda: blur_image(image, single_psf, arcmin_per_px=STEP, padding="edge"), 1))
        timings["floor"].append(best(lambda: naive_layer(planes, single_psf, frame), 1))
        timings["windows"].append(window_floor(window_calls))
    cold_s, warm_s, single_s, floor_s, windows_s = (min(timings[k]) for k in ("cold", "warm", "single", "floor",
                                                                               "windows"))
    n = len(result.layers)
    print(f"image {COLS}x{ROWS} RGB float32, depth 0.33-8 m, eye {EYE.format()}, {PUPIL_MM:g} mm pupil, "
          f"{STEP:g} arcmin/px, 550 nm wave optics, coarse grid from {args.coarse_blur_px} px of blur")
    print(f"layers: {result.n_layers} planned (<= {result.max_layer_spacing_diopters:.4f} D apart), {n} non-empty; "
          f"PSFs {min(la.psf_size_px for la in result.layers)}-{widest.psf_size_px} px")
    print(f"blur_depth, PSFs computed (cold):  {cold_s:6.2f} s  ({1e3 * cold_s / n:5.1f} ms/layer)")
    print(f"blur_depth, PSFs cached (warm):    {warm_s:6.2f} s  ({1e3 * warm_s / n:5.1f} ms/layer)")
    print(f"blur_image, one {single_psf.data.shape[0]} px PSF:        {single_s:6.3f} s")
    print(f"naive floor: {n} x (kernel + 4-plane rfft2/irfft2 on {frame}) = {n} x {1e3 * floor_s:.1f} ms = "
          f"{n * floor_s:5.2f} s")
    print(f"window floor: the {len(window_calls)} layer windows' FFT convolutions alone, on {worker_threads(CPU)} "
          f"thread(s): {windows_s:5.2f} s")
    print(f"ratios: blur_depth / blur_image {cold_s / single_s:5.1f} (cold), {warm_s / single_s:5.1f} (warm); "
          f"blur_depth (warm) / naive floor {warm_s / (n * floor_s):5.2f}; blur_depth (cold) / window floor "
          f"{cold_s / windows_s:4.2f}")
    if args.cli:
        print_cli_times(image, depth, args)


def print_cli_times(image: np.ndarray, depth: np.ndarray, args) -> None:
    times = cli_times(image, depth, args.repeats, args.coarse_blur_px, args.baseline)
    for i, ((depth_wall, depth_cpu), (blur_wall, blur_cpu)) in enumerate(zip(times["blur-depth"], times["blur"])):
        print(f"command line, cold run {i + 1}: vissim blur-depth {depth_wall:5.2f} s (cpu {depth_cpu:5.2f} s), "
              f"vissim blur {blur_wall:5.2f} s (cpu {blur_cpu:5.2f} s), ratio {depth_wall / blur_wall:4.2f}")
    ratios = sorted(d[0] / b[0] for d, b in zip(times["blur-depth"], times["blur"]))
    best = min(t[0] for t in times["blur-depth"]) / min(t[0] for t in times["blur"])
    print(f"command line, cold: ratio blur-depth / blur {best:4.2f} (best of {args.repeats} each); per run "
          f"{ratios[0]:4.2f}-{ratios[-1]:4.2f} (median {ratios[len(ratios) // 2]:4.2f})")
    if "baseline blur-depth" in times:
        median = {name: float(np.median([wall for wall, _ in runs])) for name, runs in times.items()}
        for name in ("blur-depth", "blur"):
            print(f"command line, cold: {name} here / from {args.baseline}: median {median[name]:5.2f} s / "
                  f"{median['baseline ' + name]:5.2f} s = {median[name] / median['baseline ' + name]:4.2f} "
                  f"({args.repeats} interleaved runs each)")
        print(f"command line, cold: median ratio blur-depth / blur {median['blur-depth'] / median['blur']:4.2f} here, "
              f"{median['baseline blur-depth'] / median['baseline blur']:4.2f} from {args.baseline}; blur-depth here "
              f"/ blur from there {median['blur-depth'] / median['baseline blur']:4.2f}")


if __name__ == "__main__":
    main()
