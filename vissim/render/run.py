"""Render a plain scene dict with Mitsuba: conversion, sample passes, progress, provenance.

`render_scene` is the one place that hands a scene to Mitsuba.  Scene dicts from
`vissim.bench` hold plain values only; `to_mitsuba_dict` turns ``to_world`` 4 x 4
nested lists into transforms and bitmap ``data`` arrays into ``mi.Bitmap``.

Rendering happens in passes of at most ``pass_spp`` samples per pixel (all of them in one pass
by default when the image is small), each pass seeded from ``(seed, pass index)``; passes are
averaged in float64.  Each pass goes through `vissim.render.fixed_order.render_image`, which
sums a pixel's samples in a fixed order, so the same scene, spp, seed and variant give
bit-identical pixels on the llvm and scalar variants (``RenderResult.deterministic``; CUDA is
untested and not promised).

``statistic="nearest_surface"`` makes a pixel from its samples otherwise: R holds a value (the
depth pass's proximity, dioptres) and G a label of the surface the sample met (0: none), and the
pixel is the mean R over the samples on the surface of its largest-R sample -- the nearest
surface's mean proximity over the part of the pixel it covers (`nearest_surface`).  The
samples of all passes are kept (`vissim.render.fixed_order.render_samples`) and reduced
once; the pixels are (H, W).  A ``progress`` callback (and a log line per pass) reports long
renders; nothing is written to disk here, so an interrupted render leaves no file behind.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vissim.checks import check_allocation, instance_of, sampler_seed, samples_per_pixel, size_text
from vissim.errors import VissimInputError
from vissim.provenance import json_safe, make_provenance
from vissim.render.backend import mitsuba
from vissim.render.fixed_order import pass_seeds, render_image, render_samples
from vissim.render.plugins import attach_scene, register_plugins
from vissim.units import REC709_LUMINANCE

__all__ = ["RenderResult", "PIXEL_STATISTICS", "nearest_surface", "to_mitsuba_dict", "render_scene", "render_bench",
           "pass_seeds", "mitsuba_versions", "render_memory_bytes", "DEFAULT_PASS_SAMPLES"]

log = logging.getLogger(__name__)

#: Samples (pixels x spp) per pass above which a render is split into passes.
DEFAULT_PASS_SAMPLES = 1 << 22
#: How a pixel's value comes from its samples: the film's mean, or `nearest_surface`.
PIXEL_STATISTICS = ("mean", "nearest_surface")
#: Relative tolerance within which two samples' surface labels (G) are the same surface: labels are
#: small integers, carried with weight 1 (to float32 round-off through refracting lenses).
LABEL_RTOL = 1e-3
#: Peak bytes per sample kept for `nearest_surface`: R, G, B float32 per pass and their
#: concatenation (24), R and G in float64 (16), the masked values and mask (9).
NEAREST_SURFACE_BYTES_PER_SAMPLE = 50
#: Peak bytes per sample of a pass: the sampler's and the integrator's wavefront state, and the
#: sample's channels kept for the fixed-order sum (`vissim.render.fixed_order`).
BYTES_PER_SAMPLE = 64


@dataclass(frozen=True, eq=False)
class RenderResult:
    """Linear float32 ``pixels`` (H, W) or (H, W, 3), and how they were made.

    ``spp`` is the number of samples per pixel actually taken: stratified samplers round a
    request up to their grid (multijitter 512 -> 528, stratified to a square, ldsampler to 4^k);
    ``spp_requested`` is what was asked.  ``pass_seeds`` and ``pass_spp`` (taken) are per pass;
    ``deterministic``: the same inputs give bit-identical pixels on this variant.
    """

    pixels: np.ndarray
    variant: str
    spp: int
    seed: int
    seconds: float
    passes: int = 1
    provenance: dict | None = None
    spp_requested: int | None = None
    pass_seeds: tuple[int, ...] = ()
    pass_spp: tuple[int, ...] = ()
    deterministic: bool | None = None
    accumulation: str = ""
    statistic: str = "mean"  # PIXEL_STATISTICS

    def render_record(self) -> dict:
        """How the pixels were made: variant, spp asked and taken, seeds, passes, determinism."""
        return {
            "variant": self.variant,
            "spp_requested": self.spp if self.spp_requested is None else self.spp_requested,
            "spp_used": self.spp,
            "seed": self.seed,
            "passes": self.passes,
            "pass_seeds": list(self.pass_seeds),
            "pass_spp_used": list(self.pass_spp),
            "deterministic": self.deterministic,
            "accumulation": self.accumulation,
            "pixel_statistic": self.statistic,
            "seconds": round(self.seconds, 3),
        }


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


def _split(spp: int, pixels: int, pass_spp: int | None) -> list[int]:
    if pass_spp is None:
        pass_spp = max(1, DEFAULT_PASS_SAMPLES // max(pixels, 1))
    if pass_spp >= spp:
        return [spp]
    passes = math.ceil(spp / pass_spp)
    base, extra = divmod(spp, passes)
    return [base + (1 if i < extra else 0) for i in range(passes)]


def nearest_surface(samples: np.ndarray) -> np.ndarray:
    """Per pixel, the mean R of the samples on the surface (label G) of its largest-R sample.

    ``samples``: (pixels, spp, >= 2) float32, R a value that is larger on nearer surfaces (a
    proximity, 0 for sky) and G the surface's label (0 for sky).  Returns (pixels,) float32.  A
    pixel wholly on one surface gets its plain mean; one straddling an edge gets the near surface's
    mean over the part it covers, never a blend with what lies behind.
    """
    value, label = samples[:, :, 0].astype(np.float64), samples[:, :, 1].astype(np.float64)
    nearest = np.take_along_axis(label, np.argmax(value, axis=1)[:, None], axis=1)
    on = np.abs(label - nearest) <= LABEL_RTOL * np.abs(nearest)
    return ((value * on).sum(axis=1) / on.sum(axis=1)).astype(np.float32)


def render_memory_bytes(n_pixels: float, spp: int, *, channels: int = 1, pass_spp: int | None = None) -> float:
    """Peak bytes of one render: the samples of its largest pass in flight, and the float64 sums."""
    largest_pass = max(_split(int(spp), max(int(n_pixels), 1), pass_spp))
    return float(n_pixels) * (2 * 8 * channels + largest_pass * BYTES_PER_SAMPLE)


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
    statistic: str = "mean",
) -> RenderResult:
    """Render ``scene_dict`` (plain, see module doc) with ``spp`` samples per pixel.

    ``statistic`` (`PIXEL_STATISTICS`): the film's ``"mean"``, or ``"nearest_surface"`` (module
    doc; (H, W) pixels from a scene whose R is a proximity and G a surface label).

    ``progress(done_spp, total_spp)`` is called after each pass.  Returns float32 pixels:
    (H, W) for ``kind="mono"`` (the one channel; on a scalar_rgb fallback, Rec. 709 luminance)
    and ``"spectral"`` (a luminance film: CIE Y of the spectrum), (H, W, 3) for ``"rgb"``.
    """
    spp = samples_per_pixel(spp)
    seed = sampler_seed(seed)
    if statistic not in PIXEL_STATISTICS:
        raise VissimInputError(f"pixel statistic must be one of {', '.join(PIXEL_STATISTICS)}, got {statistic!r}")
    if statistic != "mean" and kind != "rgb":
        raise VissimInputError(f"the {statistic} statistic reads a value and a label: render kind 'rgb'")
    mi = mitsuba(kind, variant)
    register_plugins(mi)
    start = time.perf_counter()
    scene = mi.load_dict(to_mitsuba_dict(scene_dict, mi))
    attach_scene(mi, scene)
    try:
        return _render_loaded(mi, scene, kind=kind, spp=spp, seed=seed, pass_spp=pass_spp, progress=progress,
                              statistic=statistic, start=start)
    finally:
        attach_scene(mi, scene, detach=True)  # no scene <-> BSDF cycle left behind


def _render_loaded(mi, scene, *, kind, spp, seed, pass_spp, progress, statistic, start) -> RenderResult:
    film = scene.sensors()[0].film()
    width, height = (int(v) for v in film.crop_size())
    counts = _split(int(spp), width * height, pass_spp)
    kept = 0 if statistic == "mean" else width * height * spp * NEAREST_SURFACE_BYTES_PER_SAMPLE
    check_allocation(render_memory_bytes(width * height, spp, channels=3 if kind == "rgb" else 1, pass_spp=pass_spp)
                     + kept, f"a {size_text((height, width))} render at {max(counts)} spp per pass")
    seeds = pass_seeds(seed, len(counts))
    total = np.zeros((height, width, 3 if kind == "rgb" else 1), dtype=np.float64)
    done, used, deterministic, methods = 0, [], True, set()
    samples = []
    for i, (count, pass_seed) in enumerate(zip(counts, seeds)):
        rendered = (render_image if statistic == "mean" else render_samples)(mi, scene, count, pass_seed)
        count = rendered.spp  # stratified samplers round up to their grids
        used.append(count)
        deterministic = deterministic and rendered.deterministic
        methods.add(rendered.accumulation)
        if statistic == "mean":
            image = rendered.image.astype(np.float64)
            if image.ndim == 2:
                image = image[:, :, None]
            if kind != "rgb" and image.shape[2] >= 3:  # scalar_rgb fallback
                image = image[:, :, :3] @ np.array(REC709_LUMINANCE)[:, None]
            total += image[:, :, : total.shape[2]] * count
        else:  # reduced from the samples after the passes
            samples.append(rendered.values)
        done += count
        log.info("render pass %d/%d: %d/%d spp, %.1f s", i + 1, len(counts), done, spp, time.perf_counter() - start)
        if progress is not None:
            progress(min(done, int(spp)), int(spp))
    if done != spp and (spp, done) not in _ROUNDING_REPORTED:
        _ROUNDING_REPORTED.add((spp, done))  # once per process: a campaign renders many times
        log.warning("the sampler rounded %d spp up to %d (its grid); provenance records %d", spp, done, done)
    if statistic == "nearest_surface":
        pixels = nearest_surface(np.concatenate(samples, axis=1)).reshape(height, width)
    else:
        pixels = (total / done).astype(np.float32)
        pixels = pixels if kind == "rgb" else pixels[:, :, 0]
    seconds = time.perf_counter() - start
    log.info("rendered %d x %d px, %d spp on %s in %.1f s", width, height, done, mi.variant(), seconds)
    result = RenderResult(pixels, mi.variant(), done, int(seed), seconds, len(counts), spp_requested=int(spp),
                          pass_seeds=tuple(seeds), pass_spp=tuple(used), deterministic=deterministic,
                          accumulation="+".join(sorted(methods)), statistic=statistic)
    return dataclasses.replace(result, provenance=json_safe(make_provenance(mitsuba_render=result.render_record(),
                                                                            **mitsuba_versions())))


def mitsuba_versions() -> dict:
    import drjit as _dr_module  # versions only, imported after the backend set Dr.Jit up
    import mitsuba as _mi_module

    return {"mitsuba_version": _mi_module.__version__, "drjit_version": _dr_module.__version__}


@functools.lru_cache(maxsize=4)  # a campaign renders a chart for its configuration's renders in a row
def _print_chart(spec, dpi: float):
    """``spec`` rendered for print at ``dpi``, kept read-only: a campaign renders each chart with several seeds
    and lenses (0.1-0.2 s a chart)."""
    from vissim.charts import render_chart_print

    chart = render_chart_print(spec, dpi)
    chart.pixels.setflags(write=False)
    return chart


def render_bench(
    bench,
    chart,
    *,
    kind: str = "mono",
    variant: str | None = None,
    pass_spp: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Render a `DslrBench` looking at ``chart``.

    ``chart`` is a `vissim.charts.ChartSpec` (rendered for print at the bench's texel
    size, `vissim.bench.dslr.bench.chart_mm_per_texel`) or a `vissim.charts.Chart`
    already rendered for print.  The result carries a provenance record: bench parameters,
    theory (added power, blur, magnification), chart, variant, spp taken, seed, ``mitsuba_render``
    (`RenderResult.render_record`: spp asked and taken, pass seeds, determinism), vissim,
    Mitsuba and Dr.Jit versions.

    Parameters
    ----------
    bench : DslrBench
        Camera (focal length mm, f-number), trial lenses, distances (mm), sampling
        (arcmin per pixel, ``size_px`` = (rows, cols)), spp and seed.
    chart : ChartSpec or Chart
        What the camera looks at, at ``bench.chart_distance_mm``.
    kind : {"mono", "rgb", "spectral"}
        One channel, three, or the luminance of a spectral render through dispersive lenses
        (`vissim.bench.dslr.bench.SPECTRAL_MODE`).
    variant : str, optional
        Mitsuba variant (default: the fastest that works here, `vissim.render.backend`).
    pass_spp : int, optional
        Samples per pixel per pass (default: split large renders).
    progress : callable, optional
        ``progress(done_spp, total_spp)`` after each pass.

    Returns
    -------
    RenderResult
        ``pixels``: float32 linear radiance, (H, W) for ``"mono"`` and ``"spectral"`` or (H, W, 3) for ``"rgb"``,
        row 0 at the top and columns to the observer's right (as the camera sees the chart,
        not mirrored); ``provenance``, ``spp``, ``seed``, ``variant``, ``seconds``.

    Examples
    --------
    Needs Mitsuba 3 (seconds on a CPU at this size):

    >>> import vissim
    >>> bench = vissim.DslrBench(size_px=(64, 64), spp=16)
    >>> result = vissim.render_bench(bench, vissim.single_letter_spec("K", 1.0))  # doctest: +SKIP
    >>> result.pixels.shape  # doctest: +SKIP
    (64, 64)
    """
    from vissim.bench.dslr.bench import SPECTRAL_MODE, DslrBench, chart_mm_per_texel, dslr_scene
    from vissim.optics.rx.trial_lens import trial_lens_effect
    from vissim.charts import MM_PER_INCH, Chart, ChartSpec, chart_sidecar

    instance_of(bench, DslrBench, "render_bench's bench", "a DslrBench (vissim.DslrBench(...))")
    instance_of(chart, (ChartSpec, Chart), "render_bench's chart",
                "a ChartSpec (vissim.single_letter_spec('K', 1.0)) or a Chart (vissim.render_chart_print(spec))")
    if isinstance(chart, ChartSpec):
        chart = _print_chart(chart, MM_PER_INCH / chart_mm_per_texel(bench))
    scene = dslr_scene(bench, chart.pixels, chart.mm_per_px, kind=kind)
    result = render_scene(scene, kind=kind, spp=bench.spp, seed=bench.seed, variant=variant,
                          pass_spp=pass_spp, progress=progress)
    theory = bench.viewing_setup()
    provenance = make_provenance(
        bench=bench,
        physical_lenses=bench.physical_lenses,
        clear_aperture_mm=bench.clear_aperture(),
        lens_back_vertex_z_mm=bench.lens_back_vertex_z_mm(),
        theory={
            # what the lenses add, without the camera's own focus error (that is in the defocus)
            "added_power": trial_lens_effect(bench.trial_lens_setup()).added_power.format(4) if bench.lenses else None,
            "defocus_matrix_diopters": theory.defocus_matrix_diopters,
            "blur_diameter_arcmin": theory.blur_diameter_arcmin,
            "magnification_principal": theory.magnification_principal,
        },
        chart=chart_sidecar(chart.spec, chart.layout),
        chart_mm_per_px=chart.mm_per_px,
        kind=kind,
        **({"spectral": SPECTRAL_MODE} if kind == "spectral" else {}),
        variant=result.variant,
        spp=result.spp,  # taken; mitsuba_render.spp_requested is bench.spp
        seed=result.seed,
        passes=result.passes,
        render_seconds=round(result.seconds, 3),
        mitsuba_render=result.render_record(),
        **mitsuba_versions(),
    )
    return dataclasses.replace(result, provenance=json_safe(provenance))
