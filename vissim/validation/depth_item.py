"""One depth-campaign item: simulate a configuration from its renders and compare per region.

Per configuration: the blurred render twice (``seeds``: the ground truth and its Monte-Carlo
noise floor) and the pinhole all-in-focus and depth renders (``aux_seed``, optionally
``oversample`` times finer); ``blur_depth`` of the all-in-focus image and depth for the
observer's equivalent eye (:func:`vissim.bench.depth_viewers.equivalent_eye`), in geometric
and wave optics.  Mitsuba renders no diffraction, so ``geometric`` is compared with the render
and ``wave`` with the render convolved with the aperture's in-focus diffraction PSF (as
:func:`vissim.validation.simulate.add_bench_diffraction` does for the single-plane harness).
Metrics (:mod:`vissim.validation.depth_masks`) per panel interior, for the occlusion band and
for the whole image, each beside the same metric between the two seeds (the floor).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.bench.depth_scene import panel_geometries
from vissim.bench.depth_viewers import equivalent_eye, viewing_setup
from vissim.provenance import make_provenance
from vissim.validation.depth_campaign import DepthCampaignSettings, DepthConfiguration
from vissim.validation.depth_masks import depth_regions, masked_metrics
from vissim.validation.metrics import compare_images

__all__ = ["compute_depth_item"]


def _region_table(comparison, masks, data_range: float) -> dict:
    maps = (comparison.squared_error_map, comparison.abs_diff_map, comparison.ssim_map)
    table = {name: masked_metrics(*maps, mask, data_range) for name, mask in masks.interiors.items()}
    table["boundary"] = masked_metrics(*maps, masks.boundary, data_range)
    table["frame"] = masked_metrics(*maps, masks.frame, data_range)
    table["all"] = comparison.as_json()
    table["all"]["n_px"] = int(np.prod(comparison.shape[:2]))
    return table


def compute_depth_item(key: str, config: DepthConfiguration, settings: DepthCampaignSettings, images: dict,
                       item_dir: Path, *, render_provenance: dict | None = None) -> dict:
    """Simulate, compare per region, write images and ``result.json`` (last) for one configuration.

    ``images``: the renders by name (``truth_0``, ``truth_1``, ``all_in_focus``, ``proximity``).
    """
    from vissim.optics.depth import blur_depth
    from vissim.render.depth_render import proximity_to_depth_m
    from vissim.validation.item import save_item_image
    from vissim.validation.simulate import add_bench_diffraction, block_mean

    started = time.perf_counter()
    provenance = make_provenance(item=key, configuration=config.as_json(), settings=settings,
                                 render_provenance=render_provenance or {})

    def _save(item_dir: Path, name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(item_dir, name, pixels, provenance, preview)

    scene, s = config.scene, settings.oversample
    eye, setup = equivalent_eye(config.viewer, scene), viewing_setup(config.viewer, scene)
    truth_a, truth_b = images["truth_0"], images["truth_1"]
    proximity = block_mean(images["proximity"], s)
    geometries = panel_geometries(scene)

    def radius_px(p):
        with np.errstate(divide="ignore"):
            distance = np.where(p > 1e-9, 1.0 / np.maximum(p, 1e-9), np.inf)
        return 0.5 * setup.blur_diameter_at_arcmin(distance) / scene.arcmin_per_px

    masks = depth_regions(proximity, geometries, radius_px, pupil_diameter_mm=eye.pupil_diameter_mm,
                          arcmin_per_px=scene.arcmin_per_px, margin_px=settings.margin_px)
    saved = {"truth": _save(item_dir, "truth", truth_a), "all_in_focus": _save(item_dir, "all_in_focus",
                                                                                block_mean(images["all_in_focus"], s)),
             "proximity": _save(item_dir, "proximity_diopters", proximity, preview=False),
             "regions": _save(item_dir, "regions", masks.label_image().astype(np.float32), preview=False)}
    comparisons = []
    for mode in settings.simulations:
        result = blur_depth(images["all_in_focus"], proximity_to_depth_m(images["proximity"]),
                            eye_prescription=eye.prescription, pupil_diameter_mm=eye.pupil_diameter_mm,
                            arcmin_per_px=scene.arcmin_per_px / s, accommodation_diopters=eye.accommodation_diopters,
                            wavelength_nm=settings.wavelength_nm, mode=mode,
                            layer_spacing_fraction=settings.layer_spacing_fraction)
        simulated = block_mean(result.image, s)
        if mode == "wave":  # the render convolved with the aperture's in-focus diffraction at the campaign's wavelength
            aperture = replace(setup, wavelength_nm=settings.wavelength_nm)
            reference, other = (add_bench_diffraction(t, aperture, scene.arcmin_per_px) for t in (truth_a, truth_b))
            saved["truth_diffracted"] = _save(item_dir, "truth_diffracted", reference)
        else:
            reference, other = truth_a, truth_b
        comparison = compare_images(reference, simulated, data_range=settings.data_range)
        floor = compare_images(reference, other, data_range=settings.data_range)
        comparisons.append({
            "simulation": mode,
            "reference_image": "truth" if mode == "geometric" else "truth_diffracted",
            "regions": _region_table(comparison, masks, settings.data_range),
            "noise_floor": _region_table(floor, masks, settings.data_range),
            "depth_blur": {k: v for k, v in result.as_json().items() if k != "layers"},
            "images": {"simulation": _save(item_dir, f"sim_{mode}", simulated),
                       "abs_diff_map": _save(item_dir, f"sim_{mode}_ad", comparison.abs_diff_map, preview=False)},
        })
    result_json = {
        "key": key,
        "configuration": config.as_json(),
        "equivalent_eye": {"prescription": eye.prescription.format(4), "pupil_diameter_mm": eye.pupil_diameter_mm,
                           "accommodation_diopters": eye.accommodation_diopters},
        "panels": [{"name": g.name, "letters": scene.panels[g.index].chart.letters,
                    "logmar": scene.panels[g.index].chart.logmar,
                    "distance_left_m": g.distance_left_m, "distance_right_m": g.distance_right_m,
                    "blur_diameter_arcmin": [float(setup.blur_diameter_at_arcmin(d))
                                             for d in (g.distance_left_m, g.distance_right_m)]} for g in geometries],
        "masks": {"jump_diopters": masks.jump_diopters, "margin_px": settings.margin_px,
                  "regions": list(masks.interiors) + ["boundary", "frame"],
                  "definition": "interior: >= blur radius + margin from any depth discontinuity and the frame; "
                                "boundary: within that of a discontinuity; frame: within the largest blur radius + "
                                "margin of the image border (see vissim.validation.depth_masks)"},
        "comparisons": comparisons,
        "images": saved,
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result_json, overwrite=True)  # last: marks the item finished
    return result_json
