"""Render a plain scene dict with Mitsuba: conversion, sample passes, progress, provenance.

:func:`render_scene` is the one place that hands a scene to Mitsuba.  Scene dicts from
:mod:`vissim.bench` hold plain values only; :func:`to_mitsuba_dict` turns ``to_world`` 4 x 4
nested lists into transforms and bitmap ``data`` arrays into ``mi.Bitmap``.

Rendering happens in passes of at most ``pass_spp`` samples per pixel (all of them in one pass
by default when the image is small), each pass seeded from ``(seed, pass index)``; passes are
averaged in float64.  The same scene, spp, seed and variant give bit-identical pixels.  A
``progress`` callback (and a log line per pass) reports long renders; nothing is written to
disk here, so an interrupted render leaves no file behind.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vissim.errors import VissimInputError
from vissim.provenance import json_safe, make_provenance
from vissim.render.backend import mitsuba
from vissim.render.plugins import register_plugins

__all__ = ["RenderResult", "to_mitsuba_dict", "render_scene", "render_bench", "pass_seeds", "DEFAULT_PASS_SAMPLES"]

log = logging.getLogger(__name__)

#: Samples (pixels x spp) per pass above which a render is split into passes.
DEFAULT_PASS_SAMPLES = 1 << 22


@dataclass(frozen=True, eq=False)
class RenderResult:
    """Linear float32 ``pixels`` (H, W) or (H, W, 3), and how they were made.

    ``spp`` is the number of samples per pixel actually taken: stratified samplers round a
    request up to their grid (multijitter 512 -> 528, stratified to a square, ldsampler to 4^k).
    """

    pixels: np.ndarray
    variant: str
    spp: int
    seed: int
    seconds: float
    passes: int = 1
    provenance: dict | None = None


def to_mitsuba_dict(value: Any, mi) -> Any:
    """Copy of a plain scene dict with transforms and bitmaps made Mitsuba objects (module doc)."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key == "to_world" and isinstance(item, (list, tuple)):
                matrix = np.asarray(item, dtype=float)
                if matrix.shape != (4, 4):
                    raise VissimInputError(f"to_world must be a 4 x 4 matrix, got shape {matrix.shape}")
                out[key] = mi.ScalarTransform4f(matrix.tolist())
            elif key == "data" and value.get("type") == "bitmap" and isinstance(item, np.ndarray):
                out["bitmap"] = mi.Bitmap(np.ascontiguousarray(item, dtype=np.float32))
            else:
                out[key] = to_mitsuba_dict(item, mi)
        return out
    return value


def pass_seeds(seed: int, passes: int) -> list[int]:
    """Sampler seeds of the passes: one pass keeps ``seed``; more draw from SeedSequence([seed, i])."""
    if passes == 1:
        return [int(seed)]
    return [int(np.random.SeedSequence([int(seed), i]).generate_state(1)[0]) for i in range(passes)]


def _split(spp: int, pixels: int, pass_spp: int | None) -> list[int]:
    if pass_spp is None:
        pass_spp = max(1, DEFAULT_PASS_SAMPLES // max(pixels, 1))
    if pass_spp >= spp:
        return [spp]
    passes = math.ceil(spp / pass_spp)
    base, extra = divmod(spp, passes)
    return [base + (1 if i < extra else 0) for i in range(passes)]


_ROUNDING_REPORTED: set[tuple[int, int]] = set()


def render_scene(
    scene_dict: dict,
    *,
    kind: str = "mono",
    spp: int,
    seed: int = 0,
    variant: str | None = None,
    pass_spp: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Render ``scene_dict`` (plain, see module doc) with ``spp`` samples per pixel.

    ``progress(done_spp, total_spp)`` is called after each pass.  Returns float32 pixels:
    (H, W) for ``kind="mono"`` (the one channel; on a scalar_rgb fallback, Rec. 709 luminance),
    (H, W, 3) for ``"rgb"``.
    """
    if int(spp) != spp or spp < 1:
        raise VissimInputError(f"spp must be a whole number of samples per pixel >= 1, got {spp!r}")
    mi = mitsuba(kind, variant)
    register_plugins(mi)
    start = time.perf_counter()
    scene = mi.load_dict(to_mitsuba_dict(scene_dict, mi))
    film = scene.sensors()[0].film()
    width, height = (int(v) for v in film.crop_size())
    counts = _split(int(spp), width * height, pass_spp)
    seeds = pass_seeds(seed, len(counts))
    sampler = scene.sensors()[0].sampler()
    total = np.zeros((height, width, 3 if kind == "rgb" else 1), dtype=np.float64)
    done = 0
    for i, (count, pass_seed) in enumerate(zip(counts, seeds)):
        image = np.asarray(mi.render(scene, spp=count, seed=pass_seed), dtype=np.float64)
        count = int(sampler.sample_count())  # stratified samplers round up to their grids
        if image.ndim == 2:
            image = image[:, :, None]
        if kind == "mono" and image.shape[2] >= 3:  # scalar_rgb fallback
            image = image[:, :, :3] @ np.array([0.2126, 0.7152, 0.0722])[:, None]
        total += image[:, :, : total.shape[2]] * count
        done += count
        log.info("render pass %d/%d: %d/%d spp, %.1f s", i + 1, len(counts), done, spp, time.perf_counter() - start)
        if progress is not None:
            progress(min(done, int(spp)), int(spp))
    if done != spp and (spp, done) not in _ROUNDING_REPORTED:
        _ROUNDING_REPORTED.add((spp, done))  # once per process: a campaign renders many times
        log.warning("the sampler rounded %d spp up to %d (its grid); provenance records %d", spp, done, done)
    pixels = (total / done).astype(np.float32)
    if kind != "rgb":
        pixels = pixels[:, :, 0]
    seconds = time.perf_counter() - start
    log.info("rendered %d x %d px, %d spp on %s in %.1f s", width, height, spp, mi.variant(), seconds)
    return RenderResult(pixels, mi.variant(), done, int(seed), seconds, len(counts))


def render_bench(
    bench,
    chart,
    *,
    kind: str = "mono",
    variant: str | None = None,
    pass_spp: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Render a :class:`~vissim.bench.dslr.DslrBench` looking at ``chart``.

    ``chart`` is a :class:`vissim.charts.ChartSpec` (rendered for print at the bench's texel
    size, :func:`vissim.bench.dslr.chart_mm_per_texel`) or a :class:`vissim.charts.Chart`
    already rendered for print.  The result carries a provenance record: bench parameters,
    theory (added power, blur, magnification), chart, variant, spp, seed, vissim, Mitsuba and
    Dr.Jit versions.
    """
    from vissim.bench.dslr import bench_theory, chart_mm_per_texel, dslr_scene
    from vissim.charts import MM_PER_INCH, Chart, ChartSpec, chart_sidecar, render_chart_print

    if isinstance(chart, ChartSpec):
        chart = render_chart_print(chart, MM_PER_INCH / chart_mm_per_texel(bench))
    if not isinstance(chart, Chart):
        raise VissimInputError(f"chart must be a vissim ChartSpec or Chart, got {type(chart).__name__}")
    scene = dslr_scene(bench, chart.pixels, chart.mm_per_px, kind=kind)
    result = render_scene(scene, kind=kind, spp=bench.spp, seed=bench.seed, variant=variant,
                          pass_spp=pass_spp, progress=progress)
    import drjit as _dr_module  # versions only, imported after the backend set Dr.Jit up
    import mitsuba as _mi_module

    theory = bench_theory(bench)
    provenance = make_provenance(
        bench=bench,
        physical_lenses=bench.physical_lenses,
        clear_aperture_mm=bench.clear_aperture(),
        lens_back_vertex_z_mm=bench.lens_back_vertex_z_mm(),
        theory={
            "added_power": None if theory.effect is None else theory.effect.added_power.format(4),
            "defocus_matrix_diopters": theory.defocus_matrix_diopters,
            "blur_diameter_arcmin": theory.blur_diameter_arcmin,
            "magnification_principal": theory.magnification_principal,
        },
        chart=chart_sidecar(chart.spec, chart.layout),
        chart_mm_per_px=chart.mm_per_px,
        kind=kind,
        variant=result.variant,
        spp=result.spp,
        seed=result.seed,
        passes=result.passes,
        render_seconds=round(result.seconds, 3),
        mitsuba_version=_mi_module.__version__,
        drjit_version=_dr_module.__version__,
    )
    return RenderResult(result.pixels, result.variant, result.spp, result.seed, result.seconds, result.passes,
                        json_safe(provenance))
