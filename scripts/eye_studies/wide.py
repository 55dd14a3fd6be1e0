"""A wide chart over 0-20° of the field: the render against the field-dependent blur and one on-axis PSF.

* **Chart**: a checkerboard of ``square_arcmin`` squares (reflectance 0.1 / 0.9), uniform in visual
  angle from the chart's centre (squares of equal angle: x = D tan α), at ``chart_distance_m`` (1 km:
  the traced eye's object at infinity is 0.001 D away).
* **Render**: `vissim.render.eye_render` with ``field_deg = (centre, 0)`` (OSA's frame, as every
  ``--field-deg``): the eye turned so that the image's centre lies at field x = ``centre``, the image
  ``width_deg`` wide (field x from −0.5° to ``width_deg`` − 0.5°), geometric (no diffraction),
  monochromatic at the model's reference wavelength by default (at another wavelength both place
  the image about the reference wavelength's chief ray, so both show the transverse chromatic
  aberration).
* **Simulations**, on the chart as the sensor's pixels see it (`scenes.ideal_image`, computed
  ``MARGIN_PX`` wider on every side and cropped after the blur, so that no padding rule enters):
  `vissim.optics.eyes.field_blur.blur_eye` in ``mode="geometric"`` with the image's field centre, its
  PSF varying over the field (2° nodes); and the same with one PSF, the on-axis one, everywhere (``field_deg = (0, 0)``, one node).
* **Score**: PSNR (data range 1, the chart's reflectance) of each simulation against the render
  (divided by its white radiance) over two column bands: on axis (visual angle 0-2° from the eye's
  axis) and off axis (18-20°) (`vissim.imaging.metrics.compare_images`); and the render's own noise
  floor there (`vissim.imaging.metrics.noise_floor`: two seeds), which a perfect simulation exceeds by
  `vissim.validation.engine.summary.PERFECT_MARGIN_DB` (3.01 dB), as on every bench.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from vissim.imaging.metrics import compare_images, noise_floor
from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL, DEFAULT_EYE_PUPIL_MM
from vissim.optics.eyes.field_blur import node_field_deg

__all__ = ["MARGIN_PX", "WideChart", "checkerboard", "wide_chart"]

#: Extra pixels of chart on every side of the simulated image, cropped after the blur.
MARGIN_PX = 48
BANDS_DEG = {"on axis": (0.0, 2.0), "off axis": (18.0, 20.0)}


def checkerboard(distance_mm: float, square_arcmin: float, dark: float = 0.1, bright: float = 0.9):
    """The chart function: squares of ``square_arcmin`` of visual angle from the chart's centre."""

    def chart(x_mm, y_mm):
        ax = np.degrees(np.arctan(x_mm / distance_mm)) * 60.0 / square_arcmin
        ay = np.degrees(np.arctan(y_mm / distance_mm)) * 60.0 / square_arcmin
        return np.where((np.floor(ax) + np.floor(ay)) % 2 == 0, bright, dark)

    return chart


@dataclass(frozen=True)
class WideChart:
    """PSNR, dB, per band (`BANDS_DEG`): field-dependent blur, on-axis PSF, render noise floor; timings."""

    field_dependent_db: dict
    single_psf_db: dict
    noise_floor_db: dict
    render_seconds: float
    simulation_seconds: float
    seconds: float


def _band_columns(width_px: int, arcmin_per_px: float, centre_deg: float, band) -> slice:
    """The columns whose centres lie ``band`` = (from, to) degrees of OSA x (`node_field_deg`'s map)."""
    angle = node_field_deg(0.0, np.arange(width_px), (1, width_px), arcmin_per_px, (centre_deg, 0.0))[0]
    inside = np.nonzero((angle >= band[0]) & (angle <= band[1]))[0]
    return slice(int(inside[0]), int(inside[-1]) + 1)


def _raster(settings, square_arcmin: float, chart_distance_m: float):
    from .scenes import ChartRaster

    distance_mm = 1000.0 * chart_distance_m
    rows, cols = settings.size_px
    half_x = math.radians(0.5 * (cols + 4 * MARGIN_PX) * settings.arcmin_per_px / 60.0 + abs(settings.field_deg[0]))
    half_y = math.radians(0.5 * (rows + 4 * MARGIN_PX) * settings.arcmin_per_px / 60.0 + 1.0)
    texel_mm = distance_mm * math.radians(settings.arcmin_per_px / 60.0) / 8.0
    return ChartRaster.from_function(checkerboard(distance_mm, square_arcmin), 2 * distance_mm * math.tan(half_x),
                                     2 * distance_mm * math.tan(half_y), distance_mm, texel_mm)


def _simulations(raster, settings) -> dict:
    from vissim.optics.eyes.field_blur import blur_eye
    from .scenes import ideal_image

    rows, cols = settings.size_px
    padded = (rows + 2 * MARGIN_PX, cols + 2 * MARGIN_PX)
    the_eye = settings.eye
    ideal = ideal_image(raster, the_eye.optics, padded, settings.arcmin_per_px, settings.field_deg)
    options = dict(arcmin_per_px=settings.arcmin_per_px, wavelength_nm=settings.wavelength_nm, mode="geometric",
                   padding="edge", dtype=np.float64)
    crop = (slice(MARGIN_PX, MARGIN_PX + rows), slice(MARGIN_PX, MARGIN_PX + cols))
    varying = blur_eye(ideal, the_eye, field_deg=settings.field_deg, **options)[crop]
    single = blur_eye(ideal, the_eye, field_deg=(0.0, 0.0), field_step_deg=1e3, **options)[crop]
    return {"field dependent": varying, "single psf": single}


def wide_chart(*, model: str = DEFAULT_EYE_MODEL, pupil_mm: float = DEFAULT_EYE_PUPIL_MM, wavelength_nm: float | None = None,
               width_deg: float = 21.0, rows: int = 96, arcmin_per_px: float = 1.0, square_arcmin: float = 8.0,
               spp: int = 256, seed: int = 0, chart_distance_m: float = 1000.0) -> WideChart:
    """Run the study (module doc): a `WideChart`."""
    from vissim.render.eye_render import EyeRender, eye_scene_dict
    from .scenes import render_settings, with_chart

    from vissim.optics.eyes.models import eye_model

    start = time.perf_counter()
    if wavelength_nm is None:
        wavelength_nm = eye_model(model).reference_wavelength_nm
    cols = int(round(width_deg * 60.0 / arcmin_per_px))
    centre_deg = 0.5 * width_deg - 0.5  # columns from -0.5 deg to width - 0.5 deg
    settings = EyeRender(model=model, pupil_mm=pupil_mm, wavelength_nm=wavelength_nm, size_px=(rows, cols),
                         arcmin_per_px=arcmin_per_px, spp=spp, seed=seed, chart_distance_m=chart_distance_m,
                         field_deg=(centre_deg, 0.0))
    raster = _raster(settings, square_arcmin, chart_distance_m)
    render_start = time.perf_counter()
    renders = []
    for s in (seed, seed + 1):
        other = dataclasses.replace(settings, seed=s)
        scene = eye_scene_dict(other)
        white = float(np.max(scene["chart"]["emitter"]["radiance"]["data"]))  # `with_chart`'s radiance of 1
        renders.append(render_settings(other, with_chart(scene, raster)).pixels / white)
    render_seconds = time.perf_counter() - render_start
    sim_start = time.perf_counter()
    simulated = _simulations(raster, settings)
    simulation_seconds = time.perf_counter() - sim_start
    scores = {name: {} for name in simulated}
    floor = {}
    for band, limits in BANDS_DEG.items():
        columns = _band_columns(cols, arcmin_per_px, centre_deg, limits)
        for name, image in simulated.items():
            scores[name][band] = compare_images(renders[0][:, columns], image[:, columns], data_range=1.0).psnr_db
        floor[band] = noise_floor(renders[0][:, columns], renders[1][:, columns], data_range=1.0).psnr_db
    return WideChart(scores["field dependent"], scores["single psf"], floor, render_seconds, simulation_seconds,
                     time.perf_counter() - start)
