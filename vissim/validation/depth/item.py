"""One depth-campaign item: simulate a configuration from its renders and compare per region.

Per configuration: the blurred render twice (``seeds``: the ground truth and its Monte-Carlo
noise floor) and the pinhole all-in-focus and depth renders (``aux_seed``, optionally
``oversample`` times finer); ``blur_depth`` of the all-in-focus image and depth for the
observer's equivalent eye (`vissim.bench.depth_viewers.equivalent_eye`), in geometric
and wave optics; and the same from the *layered* input -- every panel rendered alone, radiance
and coverage -- by `vissim.optics.depth_layers.composite_layers`, which needs no guess
behind occluding edges.  The pinhole renders extend beyond the frame by the scene's largest blur
radius (``frame_margin``), and the simulations are cropped to the frame.  Mitsuba renders no diffraction, so ``geometric`` is compared with the render
and ``wave`` with the render convolved with the aperture's in-focus diffraction PSF (`vissim.validation.engine.truth.add_bench_diffraction`, as for the DSLR bench).
Metrics (`vissim.validation.depth.masks`) per panel interior, for the occlusion band and
for the whole image, each beside the same metric between the two seeds (the floor).
"""

from __future__ import annotations

import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.bench.depth.scene import panel_geometries
from vissim.provenance import make_provenance
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.optics.resample import block_mean
from vissim.validation.depth.masks import depth_regions, masked_metrics
from vissim.validation.depth.renders import DepthBuilt
from vissim.validation.depth.schema import DepthCampaignSettings
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.truth import add_bench_diffraction

__all__ = ["compute_depth_item"]


def _region_table(comparison, masks, data_range: float) -> dict:
    maps = (comparison.squared_error_map, comparison.abs_diff_map, comparison.ssim_map)
    table = {name: masked_metrics(*maps, mask, data_range) for name, mask in masks.interiors.items()}
    table["boundary"] = masked_metrics(*maps, masks.boundary, data_range)
    table["frame"] = masked_metrics(*maps, masks.frame, data_range)
    table["all"] = comparison.as_json()
    table["all"]["n_px"] = int(np.prod(comparison.shape[:2]))
    return table


def _scene_layers(scene, images: dict) -> list:
    """Each panel rendered alone, as a `SceneLayer` (campaign sampling / oversample).

    A fronto panel's proximity is ``1 / distance``; a tilted chart's is its own proximity pass
    divided by its coverage (the pass holds the pixel's mean proximity, 0 where it sees nothing).
    """
    from vissim.optics.depth_layers import SceneLayer

    layers = []
    for i, panel in enumerate(scene.panels):
        coverage = np.clip(images[f"coverage_{i}"], 0.0, 1.0)
        if hasattr(panel, "distance_m"):
            proximity = 1.0 / panel.distance_m
        else:
            ends = sorted((1.0 / panel.distance_left_m, 1.0 / panel.distance_right_m))
            with np.errstate(divide="ignore", invalid="ignore"):
                proximity = np.where(coverage > 1e-6, images[f"layer_proximity_{i}"] / coverage, ends[0])
            proximity = np.clip(proximity, *ends)
        layers.append(SceneLayer(images[f"layer_{i}"], coverage, proximity))
    return layers


def compute_depth_item(key: str, built: DepthBuilt, settings: DepthCampaignSettings, images: dict,
                       item_dir: Path, *, render_provenance: dict | None = None) -> dict:
    """Simulate, compare per region, write images and ``result.json`` (last) for one configuration.

    ``images``: the renders by name (``truth_0``, ``truth_1``, ``all_in_focus``, ``proximity``).
    """
    from vissim.optics.depth import blur_depth
    from vissim.optics.depth_layers import composite_layers
    from vissim.optics.setup import Eye
    from vissim.render.depth_render import proximity_to_depth_m

    started = time.perf_counter()
    config = built.configuration
    provenance = make_provenance(item=key, configuration=config.as_json(), settings=settings,
                                 render_provenance=render_provenance or {})

    def _save(item_dir: Path, name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(item_dir, name, pixels, provenance, preview)

    scene, s = config.scene, settings.oversample
    eye, setup, margin = built.eye, built.setup, built.margin_px
    truth_a, truth_b = images["truth_0"], images["truth_1"]

    def frame(pixels):  # integrated onto the campaign's pixels, the margin cropped
        pixels = block_mean(pixels, s)
        return pixels if margin == 0 else pixels[margin:-margin, margin:-margin]

    proximity = frame(images["proximity"])
    geometries = panel_geometries(scene)

    def radius_px(p):
        with np.errstate(divide="ignore"):
            distance = np.where(p > 1e-9, 1.0 / np.maximum(p, 1e-9), np.inf)
        return 0.5 * setup.blur_diameter_at_arcmin(distance) / scene.arcmin_per_px

    masks = depth_regions(proximity, geometries, radius_px, pupil_diameter_mm=eye.pupil_diameter_mm,
                          arcmin_per_px=scene.arcmin_per_px, margin_px=settings.margin_px)
    saved = {"truth": _save(item_dir, "truth", truth_a), "all_in_focus": _save(item_dir, "all_in_focus",
                                                                                frame(images["all_in_focus"])),
             "proximity": _save(item_dir, "proximity_diopters", proximity, preview=False),
             "regions": _save(item_dir, "regions", masks.label_image().astype(np.float32), preview=False)}
    eye_kwargs = dict(eye=Eye(eye.prescription, eye.pupil_diameter_mm, eye.accommodation_diopters),
                      arcmin_per_px=scene.arcmin_per_px / s, wavelength_nm=settings.wavelength_nm,
                      layer_spacing_fraction=settings.layer_spacing_fraction)
    layers = _scene_layers(scene, images) if "layered" in settings.inputs else None
    references = {}
    comparisons = []
    for source in settings.inputs:
        for mode in settings.simulations:
            started_sim = time.perf_counter()
            if source == "rgbd":
                result = blur_depth(images["all_in_focus"], proximity_to_depth_m(images["proximity"]), mode=mode,
                                    crop_px=margin * s, **eye_kwargs)
            else:
                result = composite_layers(layers, mode=mode, crop_px=margin * s, **eye_kwargs)
            simulated = block_mean(result.image, s)
            if mode not in references:
                if mode == "wave":  # the render convolved with the aperture's in-focus diffraction
                    aperture = replace(setup, wavelength_nm=settings.wavelength_nm)
                    references[mode] = tuple(add_bench_diffraction(t, aperture, scene.arcmin_per_px)
                                             for t in (truth_a, truth_b))
                    saved["truth_diffracted"] = _save(item_dir, "truth_diffracted", references[mode][0])
                else:
                    references[mode] = (truth_a, truth_b)
            reference, other = references[mode]
            comparison = compare_images(reference, simulated, data_range=settings.data_range)
            floor = noise_floor(reference, other, settings.data_range)
            name = f"{mode} {source}"
            tag = f"{mode}_{source}"
            comparisons.append({
                "simulation": name,
                "optics": mode,
                "input": source,
                "reference_image": "truth" if mode == "geometric" else "truth_diffracted",
                "regions": _region_table(comparison, masks, settings.data_range),
                "noise_floor": _region_table(floor, masks, settings.data_range),
                "depth_blur": {k: v for k, v in result.as_json().items() if k != "layers"},
                "seconds": time.perf_counter() - started_sim,
                "images": {"simulation": _save(item_dir, f"sim_{tag}", simulated),
                           "abs_diff_map": _save(item_dir, f"sim_{tag}_ad", comparison.abs_diff_map, preview=False)},
            })
    result_json = {
        "key": key,
        "configuration": config.as_json(),
        "equivalent_eye": {**asdict(eye), "prescription": eye.prescription.format(4)},
        "panels": [{"name": g.name, "letters": scene.panels[g.index].chart.letters,
                    "logmar": scene.panels[g.index].chart.logmar,
                    "distance_left_m": g.distance_left_m, "distance_right_m": g.distance_right_m,
                    "blur_diameter_arcmin": [float(setup.blur_diameter_at_arcmin(d))
                                             for d in (g.distance_left_m, g.distance_right_m)]} for g in geometries],
        "frame_margin_px": margin,
        "masks": {"jump_diopters": masks.jump_diopters, "margin_px": settings.margin_px,
                  "regions": list(masks.interiors) + ["boundary", "frame"],
                  "definition": "interior: >= blur radius + margin from any depth discontinuity and the frame; "
                                "boundary: within that of a discontinuity; frame: within the largest blur radius + "
                                "margin of the image border (see vissim.validation.depth.masks)"},
        "comparisons": comparisons,
        "images": saved,
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result_json, overwrite=True)  # last: marks the item finished
    return result_json
