"""Benchmark: depth-dependent blur of a 1080p RGB-D image, 32 depth layers, against one blur_image.

    .venv/bin/python benchmarks/bench_depth.py

Scene (synthetic, linear RGB noise textures): a wall at 6 m, a floor sloping from 6 m (horizon)
to 0.4 m (bottom row) so that every layer has pixels, and panels at 3, 1.5, 0.8 and 0.4 m.
Eye: uncorrected -1.00 DS, 3 mm pupil, no accommodation, 1 arcmin/px, 550 nm wave optics.  The
layer-spacing fraction is chosen so that the plan has exactly 32 layers.

Prints the total time with the PSF cache cold (PSFs computed) and warm, the time per layer, and
the time of ``blur_image`` of the same image with one PSF (the widest layer's, so the padded
FFT shape is the same), all measured in the same run, the ratio, and the FFT floor of a layer
(its kernel's transform plus one batched real FFT pair of 3 colour planes + coverage).
"""

from __future__ import annotations

import time

import numpy as np

from vissim.optics.blur import BlurKernel, blur_image
from vissim.optics.depth import (
    _blur_planes,
    _cached_psf,
    blur_depth,
    layer_spacing_diopters,
    plan_layers,
)
from vissim.optics.prescription import Prescription
from vissim.optics.wavefront import Wavefront

ROWS, COLS = 1080, 1920
PUPIL_MM, STEP, EYE = 3.0, 1.0, Prescription(-1.0)
TARGET_LAYERS = 32


def scene() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    image = rng.random((ROWS, COLS, 3), dtype=np.float32)
    depth = np.full((ROWS, COLS), 6.0)
    horizon = ROWS // 2
    floor_proximity = np.linspace(1 / 6.0, 1 / 0.4, ROWS - horizon)
    depth[horizon:] = (1.0 / floor_proximity)[:, None]
    for (top, left, height, width), metres in zip(
        [(150, 150, 400, 300), (300, 600, 450, 350), (200, 1100, 500, 300), (600, 1450, 450, 400)], [3.0, 1.5, 0.8, 0.4]
    ):
        depth[top : top + height, left : left + width] = metres
        image[top : top + height, left : left + width] *= np.array([0.9, 0.6, 0.3], np.float32)
    return image, depth


def spacing_fraction_for(depth: np.ndarray, n_layers: int) -> float:
    proximity = 1.0 / depth
    low, high, anchor = float(proximity.min()), float(proximity.max()), -EYE.spherical_equivalent_diopters
    for fraction in np.arange(2.0, 0.01, -0.001):
        spacing = layer_spacing_diopters(STEP, PUPIL_MM, fraction)
        if plan_layers(low, high, spacing, anchor_diopters=anchor).n_layers == n_layers:
            return float(fraction)
    raise RuntimeError("no spacing fraction gives the requested layer count")


def main() -> None:
    image, depth = scene()
    fraction = spacing_fraction_for(depth, TARGET_LAYERS)
    kwargs = dict(eye_prescription=EYE, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, layer_spacing_fraction=fraction)

    _cached_psf.cache_clear()
    start = time.perf_counter()
    result = blur_depth(image, depth, **kwargs)
    cold = time.perf_counter() - start
    warm = float("inf")
    for _ in range(2):
        start = time.perf_counter()
        blur_depth(image, depth, **kwargs)
        warm = min(warm, time.perf_counter() - start)

    widest = max(result.layers, key=lambda layer: layer.psf_size_px)
    front = Wavefront.from_prescription(EYE, PUPIL_MM).with_defocus_diopters(widest.proximity_diopters)
    single_psf = _cached_psf(tuple(front.coefficients_um.items()), PUPIL_MM, 550.0, STEP, "wave")
    single = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        blur_image(image, single_psf, arcmin_per_px=STEP, padding="edge")
        single = min(single, time.perf_counter() - start)

    # The FFT floor of one layer: its kernel's transform and one batched rfft2/irfft2 of 4 planes.
    planes = np.ascontiguousarray(np.moveaxis(np.concatenate([image, image[..., :1]], axis=-1), -1, 0))
    offset = max(la.psf_size_px for la in result.layers) // 2 + 1
    floor = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        _blur_planes(planes, BlurKernel.prepare(single_psf, result.padded_shape), offset, "edge")
        floor = min(floor, time.perf_counter() - start)

    n = len(result.layers)
    print(f"image {COLS}x{ROWS} RGB float32, depth 0.4-6 m, eye {EYE.format()}, {PUPIL_MM:g} mm pupil, {STEP:g} arcmin/px")
    print(f"layers: {result.n_layers} planned (spacing fraction {fraction:.3f}, <= {result.max_layer_spacing_diopters:.4f} D), "
          f"{n} non-empty; PSFs {min(la.psf_size_px for la in result.layers)}-{widest.psf_size_px} px; padded {result.padded_shape}")
    print(f"blur_depth, PSFs computed (cold cache): {cold:7.2f} s  ({1e3 * cold / n:6.1f} ms/layer)")
    print(f"blur_depth, PSFs cached (warm, best of 2): {warm:7.2f} s  ({1e3 * warm / n:6.1f} ms/layer)")
    print(f"blur_image, one {single_psf.data.shape[0]} px PSF, same image (best of 3): {single:7.3f} s")
    print(f"ratio blur_depth / blur_image: {cold / single:6.1f} (cold)  {warm / single:6.1f} (warm)")
    print(f"FFT floor per layer (kernel + 4-plane rfft2/irfft2): {1e3 * floor:6.1f} ms; x {n} layers = {n * floor:5.2f} s "
          f"({100 * n * floor / warm:4.1f} % of the warm total)")


if __name__ == "__main__":
    main()
