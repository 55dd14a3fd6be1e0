"""The bench's wave-optical ground truth: the chart imaged through the traced trial lenses.

Mitsuba renders ray optics.  The wave truth images the same chart with the wavefront the
bench's own lenses add, traced exactly (:mod:`vissim.bench.bench_wavefront`), by wave optics:

1. the chart on a grid ``oversample`` times finer than the camera's pixels, in visual angle
   (:func:`~vissim.charts.render_chart_angular`, the chart's real distance);
2. magnified by the lenses' spectacle magnification (the bench's :class:`ViewingSetup`; the
   trace's tilt at the frame's corners agrees with it to 2e-5);
3. convolved with the wave PSF of the traced OPD map (:class:`~vissim.optics.opd_map.OpdMap`)
   over the camera's entrance pupil, pixel-integrated at the fine sampling;
4. integrated onto the camera's pixels (block means).

Deterministic and noise-free; monochromatic at ``wavelength_nm`` (the d line by default, where
the glass has the index Mitsuba renders) or polychromatic over several wavelengths with
weights, each traced through the dispersive glass.  One field point (the frame's centre): the
traced wavefront varies by < 0.5 nm RMS over the frame (``shift_invariance``), so the PSF is
shift-invariant to that.  The camera must be focused on the chart: its own focus error is
not part of the lenses' wavefront.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vissim.bench.bench_wavefront import D_LINE_NM, trace_bench_wavefront
from vissim.bench.dslr import DslrBench
from vissim.charts import ChartSpec, chart_sidecar, render_chart_angular
from vissim.errors import VissimInputError
from vissim.optics.blur import blur_image
from vissim.optics.psf import compute_psf, suggested_size_px
from vissim.optics.resample import block_mean, magnify
from vissim.provenance import json_safe

__all__ = ["WaveTruth", "wave_truth", "WAVE_TRUTH_OVERSAMPLE"]

log = logging.getLogger(__name__)

#: Sub-pixels per camera pixel (per axis) at which the chart is imaged before integration.
WAVE_TRUTH_OVERSAMPLE = 5


@dataclass(frozen=True, eq=False)
class WaveTruth:
    pixels: np.ndarray
    provenance: dict


def wave_truth(
    bench: DslrBench,
    chart: ChartSpec,
    *,
    wavelengths_nm: Sequence[float] = (D_LINE_NM,),
    weights: Sequence[float] | None = None,
    oversample: int = WAVE_TRUTH_OVERSAMPLE,
    mode: str = "wave",
) -> WaveTruth:
    """The wave-optical image of ``chart`` on ``bench``'s sensor (module docstring).

    ``mode="geometric"``: the same trace's ray optics instead (the PSF of its ray landing
    points): the geometric self-check, which must match the Mitsuba render to its noise floor.
    """
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"the bench truth's optics must be 'wave' or 'geometric', got {mode!r}")
    setup = bench.viewing_setup()
    if abs(bench.focus_distance_mm - bench.chart_distance_mm) > 1e-9 * bench.chart_distance_mm:
        raise VissimInputError(
            f"the wave truth needs the camera focused on the chart ({bench.chart_distance_mm:g} mm); "
            f"it is focused at {bench.focus_distance_mm:g} mm"
        )
    if int(oversample) != oversample or not 1 <= oversample <= 16:
        raise VissimInputError(f"oversample must be a whole number of sub-pixels within 1-16, got {oversample!r}")
    wavelengths = [float(w) for w in wavelengths_nm]
    weights = [1.0] * len(wavelengths) if weights is None else [float(w) for w in weights]
    rows, cols = bench.size_px
    step = bench.arcmin_per_px / oversample
    fine = render_chart_angular(chart, step, shape_px=(rows * oversample, cols * oversample), snap_to_pixels=False)
    magnified = magnify(fine.pixels, setup.magnification_matrix)
    traced = [trace_bench_wavefront(bench, wavelength_nm=w) for w in wavelengths]
    out = np.zeros((rows, cols))
    psfs = []
    for trace, weight in zip(traced, weights):
        front = trace.as_opd_map()
        size = suggested_size_px(front, step, wavelength_nm=trace.wavelength_nm, mode=mode)
        psf = compute_psf(front, wavelength_nm=trace.wavelength_nm, arcmin_per_px=step, size_px=size, mode=mode)
        blurred = blur_image(magnified, psf, arcmin_per_px=step, padding="edge", dtype=np.float64)
        out += weight / sum(weights) * block_mean(blurred, oversample)
        psfs.append(psf)
    provenance = {
        "kind": "bench wave truth" if mode == "wave" else "bench ray truth (traced)",
        "oversample": int(oversample),
        "magnification_matrix": [list(r) for r in setup.magnification_matrix],
        "traced": [t.as_json() for t in traced],
        "weights": weights,
        "psf": [{k: v for k, v in p.as_json().items() if k != "wavefront"} for p in psfs],
        "chart": chart_sidecar(chart, fine.layout),
        "bench": json_safe(bench),
    }
    log.info("wave truth: %d x %d px, %d wavelength(s), PSF %d px at %.3g arcmin/px", cols, rows, len(wavelengths),
             psfs[0].data.shape[0], step)
    return WaveTruth(out.astype(np.float32), provenance)
