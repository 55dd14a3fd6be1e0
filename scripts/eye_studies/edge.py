"""A slanted edge seen by a schematic eye: the render's MTF (ISO 12233-style) against the trace's geometric MTF.

* **Render**: a black/white edge through the chart's centre, rolled ``roll_deg`` about the line of
  sight (a 1 x 2 texel bitmap on a rolled rectangle: a mathematically straight edge), at
  ``chart_distance_m`` (1 km: a vergence of 0.001 D), on the eye's axis, monochromatic.
* **Render MTF** (`edge_mtf`, after ISO 12233's slanted-edge method, sfrmat's steps): each row's edge
  position is the area of its dark share (`_edge_line`; sfrmat takes a derivative's centroid, which
  the render's noise biases here); a line fitted to them gives the edge; every
  pixel's signed distance from that line along its normal is binned at ¼ px (4x oversampled ESF,
  ``BIN_PX``); the LSF is the ESF's forward difference; a Hamming window centred on the LSF's
  centroid; |DFT| normalised at zero frequency.
* **Trace MTF** (`traced_edge_lsf`): rays from the chart's centre (1 km away on the axis: traced as
  at infinity, a collimated beam; the 0.001 D this leaves out blurs by 0.014 arcmin at 4 mm) aimed
  with `vissim.optics.raytrace.aim_collimated` at a square grid on the iris (``rays_across`` across,
  161 by default, those within the iris: uniform over the iris, so nearly over the entrance pupil;
  81 across moved the MTF by up to 0.0025 at 4-10 cyc/deg, 161 and 241 agree within 0.0005), traced through
  the eye (`vissim.optics.eyes.surfaces.split_at_stop`) to the retina; their landing offsets from
  the chief ray (mm) over the traced retinal scale (mm per degree: a chief ray 0.5° off axis,
  traced the same way) are the geometric PSF in visual angle.  Projected on the edge's normal, each
  ray spread over the pixel's footprint (the film's box pixel, 8 x 8 offsets), taken on the
  same ¼-px bins as the expected ESF of the pixels whose centres fall in each bin, differenced: the
  LSF the render's pipeline should see; then the same window and DFT.  Its MTF
  is the geometric MTF times the pixel's and the bins' (both carry them alike); `geometric_mtf`
  is the rays' own MTF (|mean exp(−2πi f s)|), reported alongside.
* **Noise band**: ``seeds`` renders of independent seeds (default 8); per frequency the seeds' MTF
  standard deviation σ is one render's noise; the render's MTF is their mean, whose standard error is
  σ / √seeds.  Both deviations are reported (`worst_deviation_in`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL, DEFAULT_EYE_PUPIL_MM

__all__ = ["BIN_PX", "EdgeMtf", "SlantedEdge", "edge_mtf", "traced_rays_deg", "traced_edge_lsf",
           "geometric_mtf", "slanted_edge"]

#: ESF bin, pixels (ISO 12233's 4x oversampling).
BIN_PX = 0.25
#: LSF half-length, pixels: the ESF used reaches this far either side of the edge.
HALF_SPAN_PX = 32


@dataclass(frozen=True)
class EdgeMtf:
    """An MTF at ``frequencies_cyc_per_deg``; ``edge_angle_deg``: the fitted edge's angle from the columns."""

    frequencies_cyc_per_deg: np.ndarray
    mtf: np.ndarray
    edge_angle_deg: float = float("nan")


def _edge_line(image: np.ndarray, plateau_px: int = 8) -> tuple[float, float]:
    """(a, b): the edge at column a + b·row (least squares over rows).  A row's edge column is the
    area of its dark share, Σ_c (bright − I)/(bright − dark) with the plateaus the mean of the image's
    first and last ``plateau_px`` columns: exact for any LSF symmetric about the edge, and unbiased
    by zero-mean noise (a derivative centroid is pulled towards the noisier bright side)."""
    left = float(image[:, :plateau_px].mean())
    right = float(image[:, -plateau_px:].mean())
    if abs(right - left) <= 0.0:
        raise VissimInputError("the edge image has no contrast between its left and right columns")
    share = (image - right) / (left - right)  # 1 on the left plateau, 0 on the right
    positions = share.sum(axis=1)
    b, a = np.polyfit(np.arange(image.shape[0], dtype=float) + 0.5, positions, 1)
    return float(a), float(b)


def _windowed_mtf(lsf: np.ndarray, arcmin_per_px: float) -> tuple[np.ndarray, np.ndarray]:
    positions = np.arange(len(lsf), dtype=float)
    centre = float(np.sum(positions * np.abs(lsf)) / np.sum(np.abs(lsf)))
    half = 0.5 * len(lsf)
    window = np.where(np.abs(positions - centre) <= half,
                      0.54 + 0.46 * np.cos(np.pi * (positions - centre) / half), 0.0)
    spectrum = np.abs(np.fft.rfft(lsf * window))
    step_deg = BIN_PX * arcmin_per_px / 60.0
    return np.fft.rfftfreq(len(lsf), d=step_deg), spectrum / spectrum[0]


def _bins() -> np.ndarray:
    return np.arange(-HALF_SPAN_PX, HALF_SPAN_PX + BIN_PX / 2, BIN_PX)


def edge_mtf(image: np.ndarray, arcmin_per_px: float) -> EdgeMtf:
    """The ISO 12233-style MTF of a near-vertical edge in ``image`` (module doc)."""
    image = np.asarray(image, dtype=float)
    a, b = _edge_line(image)
    rows, cols = np.indices(image.shape, dtype=float)
    distance = (cols + 0.5 - (a + b * (rows + 0.5))) / math.hypot(1.0, b)
    edges = _bins()
    index = np.digitize(distance.ravel(), edges) - 1
    inside = (index >= 0) & (index < len(edges) - 1)
    sums = np.bincount(index[inside], image.ravel()[inside], len(edges) - 1)
    counts = np.bincount(index[inside], minlength=len(edges) - 1)
    if np.any(counts == 0):
        raise VissimInputError("an ESF bin is empty: the edge is too close to a pixel column (slant it more)")
    esf = sums / counts
    lsf = np.diff(esf)
    frequencies, mtf = _windowed_mtf(lsf * np.sign(np.sum(lsf)), arcmin_per_px)
    return EdgeMtf(frequencies, mtf, math.degrees(math.atan(b)))


def traced_rays_deg(model: str, pupil_mm: float, wavelength_nm: float, rays_across: int = 161) -> np.ndarray:
    """The geometric PSF's rays: (N, 2) landing offsets from the chief ray, degrees of visual angle (module doc)."""
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.traced_wavefront import iris_from_entrance_pupil_mm, trace_to_retina

    eye = eye_model(model)
    iris_mm = iris_from_entrance_pupil_mm(eye, pupil_mm, wavelength_nm)
    axis = (np.arange(rays_across) - (rays_across - 1) / 2) * iris_mm / rays_across
    x, y = np.meshgrid(axis, axis)
    keep = np.hypot(x, y) <= 0.5 * iris_mm
    targets = np.concatenate([[[0.0, 0.0]], np.stack([x[keep], y[keep]], axis=1)]) + [eye.stop_decentre_nasal_mm, 0.0]
    landing = trace_to_retina(eye, targets, wavelength_nm, field_deg=(0.0, 0.0))[0].points_mm[:, :2]
    chief = trace_to_retina(eye, targets[:1], wavelength_nm, field_deg=(0.5, 0.0))[0].points_mm[:, :2]
    mm_per_deg = abs(chief[0, 0] - landing[0, 0]) / 0.5
    return (landing[1:] - landing[0]) / mm_per_deg


def geometric_mtf(offsets_deg: np.ndarray, normal, frequencies_cyc_per_deg) -> np.ndarray:
    """|mean over rays of exp(−2πi f s)|, s the rays' offsets along ``normal`` (unit 2-vector), degrees."""
    s = offsets_deg @ np.asarray(normal, dtype=float)
    f = np.asarray(frequencies_cyc_per_deg, dtype=float)[:, None]
    return np.abs(np.mean(np.exp(-2j * np.pi * f * s[None, :]), axis=1))


def traced_edge_lsf(offsets_deg: np.ndarray, edge_angle_deg: float, arcmin_per_px: float,
                    footprint: int = 8) -> np.ndarray:
    """The LSF on the render pipeline's bins: the rays spread over the box pixel's footprint (module doc)."""
    angle = math.radians(edge_angle_deg)
    normal = np.array([math.cos(angle), -math.sin(angle)])
    s_px = offsets_deg @ normal * 60.0 / arcmin_per_px
    sub = (np.arange(footprint) + 0.5) / footprint - 0.5
    du, dv = np.meshgrid(sub, sub)
    spread = (du * normal[0] + dv * normal[1]).ravel()
    samples = np.sort((s_px[:, None] + spread[None, :]).ravel())
    edges = _bins()
    within = (np.arange(footprint) + 0.5) / footprint  # pixel centres spread over each bin
    centres = edges[:-1, None] + BIN_PX * within[None, :]
    bright = 1.0 - np.searchsorted(samples, -centres, side="right") / len(samples)  # P(d + s > 0)
    return np.diff(bright.mean(axis=1))


@dataclass(frozen=True)
class SlantedEdge:
    """The study's result: the seeds' MTFs, the traced MTF on the same frequencies, timings."""

    frequencies_cyc_per_deg: np.ndarray
    render_mtfs: np.ndarray  # (seeds, frequencies)
    traced_mtf: np.ndarray
    geometric_mtf: np.ndarray
    edge_angle_deg: float
    seconds: float

    @property
    def render_mtf(self) -> np.ndarray:
        return self.render_mtfs.mean(axis=0)

    @property
    def seed_sigma(self) -> np.ndarray:
        """One render's MTF noise per frequency: the standard deviation over the seeds (ddof 1)."""
        return self.render_mtfs.std(axis=0, ddof=1)

    @property
    def standard_error(self) -> np.ndarray:
        """The seeds' mean MTF's noise: ``seed_sigma`` / √seeds."""
        return self.seed_sigma / math.sqrt(len(self.render_mtfs))

    def _band(self, max_cyc_per_deg: float) -> np.ndarray:
        f = self.frequencies_cyc_per_deg
        return (f > 0.0) & (f <= max_cyc_per_deg)

    def worst_deviation(self, max_cyc_per_deg: float) -> float:
        """max |mean render MTF − traced MTF| over (0, ``max_cyc_per_deg``]."""
        band = self._band(max_cyc_per_deg)
        return float(np.max(np.abs(self.render_mtf - self.traced_mtf)[band]))

    def worst_deviation_in(self, noise: np.ndarray, max_cyc_per_deg: float) -> float:
        """max over (0, ``max_cyc_per_deg``] of |mean render MTF − traced MTF| / ``noise`` (per frequency)."""
        band = self._band(max_cyc_per_deg)
        return float(np.max(np.abs(self.render_mtf - self.traced_mtf)[band] / noise[band]))


def _edge_chart(chart_distance_m: float, roll_deg: float, half_width_deg: float):
    from .scenes import ChartRaster

    distance_mm = 1000.0 * chart_distance_m
    side_mm = 4.0 * distance_mm * math.tan(math.radians(half_width_deg))
    data = np.array([[0.0, 1.0]], dtype=np.float32)
    return ChartRaster(data, side_mm, side_mm, distance_mm, roll_deg)


def slanted_edge(*, model: str = DEFAULT_EYE_MODEL, pupil_mm: float = DEFAULT_EYE_PUPIL_MM, wavelength_nm: float = 550.0,
                 roll_deg: float = 5.0, size_px: int = 128, arcmin_per_px: float = 0.5, spp: int = 1024,
                 seeds: int = 8, chart_distance_m: float = 1000.0) -> SlantedEdge:
    """Run the study (module doc): a `SlantedEdge`."""
    from vissim.render.eye_render import EyeRender, eye_scene_dict
    from .scenes import render_settings, with_chart

    start = time.perf_counter()
    half_deg = 0.5 * size_px * arcmin_per_px / 60.0
    chart = _edge_chart(chart_distance_m, roll_deg, half_deg)
    mtfs, angles = [], []
    for seed in range(seeds):
        settings = EyeRender(model=model, pupil_mm=pupil_mm, wavelength_nm=wavelength_nm, size_px=(size_px, size_px),
                             arcmin_per_px=arcmin_per_px, spp=spp, seed=seed, chart_distance_m=chart_distance_m)
        pixels = render_settings(settings, with_chart(eye_scene_dict(settings), chart)).pixels
        result = edge_mtf(pixels, arcmin_per_px)
        mtfs.append(result.mtf)
        angles.append(result.edge_angle_deg)
    frequencies = result.frequencies_cyc_per_deg
    angle = float(np.mean(angles))
    offsets = traced_rays_deg(model, pupil_mm, wavelength_nm)
    _, traced = _windowed_mtf(traced_edge_lsf(offsets, angle, arcmin_per_px), arcmin_per_px)
    normal = (math.cos(math.radians(angle)), -math.sin(math.radians(angle)))
    return SlantedEdge(frequencies, np.array(mtfs), traced, geometric_mtf(offsets, normal, frequencies), angle,
                       time.perf_counter() - start)
