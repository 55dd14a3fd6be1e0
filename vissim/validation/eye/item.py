"""One eye-bench item: its two renders, the ray PSF, every simulation scored against the render.

A row's ``over_floor_db`` is its PSNR minus the noise floor's (the two seeds' renders against each
other): a simulation that matches the render to its noise scores about +3 dB (its error is one
render's noise, the floor's two).  The geometric self-check (``traced_rays``) must reach
`SELF_CHECK_MARGIN_DB`.  An assumption's ``cost_db`` is the schematic wave-optics simulation's PSNR
minus that of the same simulation with the assumption put in (> 0: the assumption costs that much).
"""

from __future__ import annotations

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.imaging.registration import register
from vissim.optics.blur.convolve import blur_image
from vissim.optics.eyes.retina_map import ray_psf
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.metrics import PSNR, SSIM, added_scores, metric_float
from vissim.validation.eye.simulate import (COSTS, SIMULATIONS, EyeScene, diffraction_psf, margin_px, reference_of,
                                            simulate)

__all__ = ["compute_eye_item", "SELF_CHECK_MARGIN_DB", "IMAGE_PEAK_VALUE", "applies", "self_check_passes"]

#: The geometric self-check's required margin over the render's noise floor, dB.
SELF_CHECK_MARGIN_DB = 2.0


def self_check_passes(result: dict) -> bool:
    """The self-check's two criteria: at least `SELF_CHECK_MARGIN_DB` over the noise floor, and an SSIM against the
    render at least the two renders' SSIM with each other (an item's ``result.json``, old ones too)."""
    row = next(x for x in result["rows"] if x["simulation"] == "traced_rays")
    floor_ssim = metric_float(result["noise_floor"].get(SSIM.name))
    return row["over_floor_db"] >= SELF_CHECK_MARGIN_DB and not (row[SSIM.name] < floor_ssim)
#: The chart's placement is searched until less than this is left (image px), in at most this many passes.
ALIGN_TOLERANCE_PX, MAX_ALIGN_PASSES = 0.01, 4
#: The images' data range for PSNR and SSIM (the chart's white is 0.9).
IMAGE_PEAK_VALUE = 1.0


def applies(where: str, bench) -> bool:
    """Whether an assumption of `COSTS` applies to the rendered ``bench`` (``where``: its scope)."""
    return {"always": True, "photopic": bench.spectrum == "photopic",
            "off axis": tuple(bench.field_deg) != (0.0, 0.0), "lens": bool(bench.lenses)}[where]


def item_ray_psf(scene: EyeScene):
    """The ray PSF of the rendered bench's eye, lens and chart, in its light (`vissim.optics.eyes.retina_map.ray_psf`)."""
    view, light, bench = scene.view, scene.light, scene.bench
    return ray_psf(view.eye, field_deg=view.field_deg, chart_distance_m=view.chart_distance_m, lens=view.lens,
                   vertex_mm=view.vertex_mm, wavelengths_nm=light.wavelengths_nm, weights=light.weights,
                   sensor_wavelength_nm=bench.wavelength_nm, arcmin_per_px=bench.arcmin_per_px,
                   oversample=scene.oversample, rays_across=scene.rays_across, phase=bench.phase_plane)


def chart_offset_px(truth: np.ndarray, scene: EyeScene, ray, margin: int) -> tuple[tuple[float, float], dict, np.ndarray]:
    """Where the render placed its chart (rows, cols; image px): the ray-trace simulation registered onto the
    render, its chart shifted by the sum, until less than `ALIGN_TOLERANCE_PX` is left (`MAX_ALIGN_PASSES`).
    Also returns the ray-trace simulation at that offset (the self-check's image, not simulated again)."""
    offset = (0.0, 0.0)
    for passes in range(1, MAX_ALIGN_PASSES + 1):
        simulated = simulate("traced_rays", scene, ray, margin, offset)
        left = register(truth, simulated, upsample_factor=100)
        if max(abs(left.shift_rows_px), abs(left.shift_cols_px)) < ALIGN_TOLERANCE_PX:
            break
        offset = (offset[0] + left.shift_rows_px, offset[1] + left.shift_cols_px)
    else:
        simulated = simulate("traced_rays", scene, ray, margin, offset)
    return offset, {"shift_rows_px": offset[0], "shift_cols_px": offset[1], "passes": passes,
                    "left_px": [left.shift_rows_px, left.shift_cols_px]}, simulated


def _row(simulation: str, reference: np.ndarray, simulated: np.ndarray, floor_db: float) -> dict:
    metrics = compare_images(reference, simulated, data_range=IMAGE_PEAK_VALUE)
    psnr = PSNR.value(metrics, None)
    return {"simulation": simulation, "reference": reference_of(simulation), PSNR.name: psnr,
            SSIM.name: SSIM.value(metrics, None), "over_floor_db": psnr - floor_db, **added_scores(metrics)}


def compute_eye_item(key: str, configuration, settings, built, images: dict, item_dir, render_provenance: dict) -> dict:
    """Simulate and score one item (module doc); writes its images and ``result.json`` (last)."""
    truth_a = np.asarray(images["truth_0"], np.float64).squeeze()
    truth_b = np.asarray(images["truth_1"], np.float64).squeeze()
    floor = noise_floor(truth_a, truth_b, IMAGE_PEAK_VALUE)
    scene = EyeScene(built.bench, settings.oversample, settings.rays_across)
    ray = item_ray_psf(scene)
    margin = margin_px(ray, settings.oversample)
    offset, placement, traced = chart_offset_px(truth_a, scene, ray, margin)
    with_diffraction = np.asarray(blur_image(truth_a, diffraction_psf(scene), arcmin_per_px=scene.bench.arcmin_per_px,
                                             padding="edge"), np.float64)
    swaps = [name for name, where in COSTS.values() if applies(where, scene.bench)]
    rows, saved = [], {}
    made = [name for name in SIMULATIONS if name != "schematic" or scene.bench.spectrum != "photopic"]
    for simulation in made + swaps:
        simulated = traced if simulation == "traced_rays" else simulate(simulation, scene, ray, margin, offset)
        reference = with_diffraction if reference_of(simulation) != "render" else truth_a
        rows.append(_row(simulation, reference, simulated, floor.psnr_db))
        if simulation in made:
            saved[simulation] = save_item_image(item_dir, simulation, simulated, {"simulation": simulation})
    by_name = {r["simulation"]: r for r in rows}
    costs = {assumption: by_name["schematic_wave"][PSNR.name] - by_name[name][PSNR.name]
             for assumption, (name, _) in COSTS.items() if name in by_name}
    saved["render"] = save_item_image(item_dir, "render", truth_a, render_provenance.get("truth_0", {}))
    result = {"key": key, "configuration": configuration.as_json(), "noise_floor": floor.as_json(),
              "chart_placement": placement, "rows": rows, "costs_db": costs,
              "ray_psf": {"rays": ray.rays, "step_arcmin": ray.step_arcmin, "magnification": ray.magnification.tolist()},
              "images": saved}
    result["self_check_pass"] = self_check_passes(result)
    write_json_atomic(item_dir / "result.json", result, overwrite=True)
    return result
