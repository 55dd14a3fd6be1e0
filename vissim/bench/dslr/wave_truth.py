"""The bench's wave-optical ground truth: the chart imaged through the traced trial lenses.

Mitsuba renders ray optics.  The wave truth images the same chart with the wavefront the
bench's own lenses add, traced exactly (`vissim.bench.dslr.traced_wavefront`), by wave optics:

1. the chart on a grid ``oversample`` times finer than the camera's pixels, in visual angle
   (`render_chart_angular`, the chart's real distance);
2. magnified by the lenses' spectacle magnification (the bench's `ViewingSetup`; the
   trace's tilt at the frame's corners agrees with it to 2e-5);
3. convolved with the wave PSF of the traced OPD map (`OpdMap`)
   over the camera's entrance pupil, pixel-integrated at the fine sampling;
4. integrated onto the camera's pixels (block means).

Deterministic and noise-free; monochromatic at ``wavelength_nm`` (the d line by default, where
the glass has the index Mitsuba renders) or polychromatic over several wavelengths with
weights, each traced through the dispersive glass.  One field point (the frame's centre): the
traced wavefront varies by < 0.5 nm RMS over the frame (``shift_invariance``), so the PSF is
shift-invariant to that.  The camera must be focused on the chart: its own focus error is
not part of the lenses' wavefront.

Steps 2-4 are `image_through_traced_lenses`, for any fine image laid out on the bench's
frame (a campaign passes its own synthetic chart); with ``mode="geometric"`` they use the
trace's ray PSF instead, the geometric self-check (`vissim.validation.dslr.wave_bench`).
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vissim.checks import OVERSAMPLE_RANGE, size_text
from vissim.bench.dslr.traced_wavefront import D_LINE_NM, TracedWavefront, trace_bench_wavefront
from vissim.bench.dslr.bench import DslrBench
from vissim.charts import Chart, ChartSpec, layout_chart, render_chart_angular
from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.psf.compute import PSF, compute_psf, suggested_size_px
from vissim.optics.blur.resample import SUBPIXELS_PER_PX, block_mean, magnify
from vissim.provenance import json_safe

__all__ = ["WaveTruth", "image_through_traced_lenses", "wave_truth"]

log = logging.getLogger(__name__)

@dataclass(frozen=True, eq=False)
class WaveTruth:
    pixels: np.ndarray
    provenance: dict


def _check(bench: DslrBench, oversample: int, mode: str) -> None:
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"the bench truth's optics must be 'wave' or 'geometric', got {mode!r}")
    low, high = OVERSAMPLE_RANGE
    if int(oversample) != oversample or not low <= oversample <= high:
        raise VissimInputError(
            f"oversample must be a whole number of sub-pixels within {low}-{high}, got {oversample!r}")
    if abs(bench.focus_distance_mm - bench.chart_distance_mm) > 1e-9 * bench.chart_distance_mm:
        raise VissimInputError(
            f"the wave truth needs the camera focused on the chart ({bench.chart_distance_mm:g} mm); "
            f"it is focused at {bench.focus_distance_mm:g} mm"
        )


@functools.lru_cache(maxsize=8)
def _traced_psf(bench: DslrBench, wavelength_nm: float, arcmin_per_px: float, mode: str) -> tuple[TracedWavefront, PSF]:
    """The bench's traced wavefront at ``wavelength_nm`` and its PSF (kept: a campaign item asks again)."""
    trace = trace_bench_wavefront(bench, wavelength_nm=wavelength_nm)
    front = trace.as_opd_map()
    size = suggested_size_px(front, arcmin_per_px, wavelength_nm=trace.wavelength_nm, mode="wave")
    return trace, compute_psf(front, wavelength_nm=trace.wavelength_nm, arcmin_per_px=arcmin_per_px, size_px=size,
                              mode=mode)


def image_through_traced_lenses(
    bench: DslrBench,
    fine: np.ndarray,
    *,
    oversample: int,
    wavelengths_nm: Sequence[float] = (D_LINE_NM,),
    weights: Sequence[float] | None = None,
    mode: str = "wave",
) -> WaveTruth:
    """``fine`` (a linear-light image on the bench's frame, ``oversample`` x finer per axis) on the sensor.

    Steps 2-4 of the module docstring: magnified by the lenses' spectacle magnification,
    convolved with the PSF of the traced OPD map (``mode`` ``"wave"``, or ``"geometric"``: the
    ray landing points), integrated onto the camera's pixels.  Both modes size the PSF's field
    with the *wave* estimate: for a traced OPD map the geometric estimate is too small (at
    0.2 arcmin/px it left 0.3-0.9 % of the ray PSF's energy outside for +/-2 D lenses, and more
    than the 1 % allowed for +4 D), the wave estimate none.  The energy outside is in the
    provenance (``psf[].energy_outside_field``).
    """
    _check(bench, oversample, mode)
    rows, cols = bench.size_px
    if np.shape(fine) != (rows * oversample, cols * oversample):
        raise VissimInputError(f"the fine image must be {size_text((rows * oversample, cols * oversample))} (the "
                               f"bench's {size_text((rows, cols))} frame, {oversample} times finer), got "
                               f"{size_text(np.shape(fine)) if np.ndim(fine) >= 2 else np.shape(fine)}")
    setup = bench.viewing_setup()
    step = bench.arcmin_per_px / oversample
    wavelengths = [float(w) for w in wavelengths_nm]
    weights = [1.0] * len(wavelengths) if weights is None else [float(w) for w in weights]
    magnified = magnify(fine, setup.magnification_matrix)
    traced, psfs = zip(*(_traced_psf(bench, w, step, mode) for w in wavelengths))
    out = np.zeros((rows, cols))
    for psf, weight in zip(psfs, weights):
        blurred = blur_image(magnified, psf, arcmin_per_px=step, padding="edge", dtype=np.float64)
        out += weight / sum(weights) * block_mean(blurred, oversample)
    provenance = {
        "kind": "bench wave truth" if mode == "wave" else "bench ray truth (traced)",
        "oversample": int(oversample),
        "magnification_matrix": [list(r) for r in setup.magnification_matrix],
        "traced": [t.as_json() for t in traced],
        "weights": weights,
        "psf": [{**{k: v for k, v in p.as_json().items() if k != "wavefront"},
                 "energy_outside_field": 1.0 - p.energy_in_field} for p in psfs],
        "bench": json_safe(bench),
    }
    log.info("%s: %d x %d px, %d wavelength(s), PSF %d px at %.3g arcmin/px", provenance["kind"], cols, rows,
             len(wavelengths), psfs[0].data.shape[0], step)
    return WaveTruth(out, provenance)


def wave_truth(
    bench: DslrBench,
    chart: ChartSpec | Chart,
    *,
    wavelengths_nm: Sequence[float] = (D_LINE_NM,),
    weights: Sequence[float] | None = None,
    oversample: int = SUBPIXELS_PER_PX,
    mode: str = "wave",
) -> WaveTruth:
    """The wave-optical image of ``chart`` on ``bench``'s sensor (module docstring).

    ``chart``: a `ChartSpec`, rendered here on the fine grid (`render_chart_angular`, centred, not snapped to
    pixels), or a `Chart` already rendered so (a campaign's synthetic chart): refused at another sampling or size.
    ``mode="geometric"``: the same trace's ray optics instead (the PSF of its ray landing
    points): the geometric self-check, which must match the Mitsuba render to its noise floor.
    """
    _check(bench, oversample, mode)
    rows, cols = bench.size_px
    step, shape = bench.arcmin_per_px / oversample, (rows * oversample, cols * oversample)
    fine = chart if isinstance(chart, Chart) else render_chart_angular(chart, step, size_px=shape, snap_to_pixels=False)
    layout = fine.layout
    if layout != layout_chart(fine.spec, arcmin_per_px=step, size_px=shape, snap_to_pixels=False):
        drawn = "in visual angle" if layout.rendering == "angular" else "for print"
        raise VissimInputError(f"the wave truth needs the chart in visual angle at {step:g} arcmin/px over "
                               f"{size_text(shape)}, centred and not snapped to pixels; the chart given was drawn "
                               f"{drawn} at {layout.arcmin_per_px:g} arcmin/px over {size_text(layout.shape_px)}")
    image = image_through_traced_lenses(bench, fine.pixels, oversample=oversample, wavelengths_nm=wavelengths_nm,
                                        weights=weights, mode=mode)
    provenance = {**image.provenance, "chart": fine.sidecar()}
    return WaveTruth(image.pixels.astype(np.float32), provenance)
