"""One depth-campaign item: simulate a configuration from its renders and compare per region.

Per configuration: the blurred render twice (``seeds``: the ground truth and its Monte-Carlo
noise floor) and the pinhole all-in-focus and depth renders (``aux_seed``, optionally
``oversample`` times finer); ``blur_depth`` of the all-in-focus image and depth for the
observer's equivalent eye (`vissim.bench.depth_viewers.equivalent_eye`), in geometric
and wave optics; and the same from the *layered* input -- every panel rendered alone, radiance
and coverage -- by `vissim.optics.depth.layered.composite_layers`, which needs no guess
behind occluding edges.  The pinhole renders extend beyond the frame by the scene's largest blur
radius (``frame_margin``), and the simulations are cropped to the frame.  Mitsuba renders no diffraction, so ``geometric`` is compared with the render
and ``wave`` with the render convolved with the aperture's in-focus diffraction PSF (`vissim.validation.engine.truth.add_bench_diffraction`, as for the DSLR bench).
Metrics (`vissim.validation.depth.masks`) per panel interior, for the occlusion band and
for the whole image, each beside the same metric between the two seeds (the floor).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.bench.depth.scene import panel_geometries
from vissim.provenance import make_provenance
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.optics.blur.resample import block_mean
from vissim.validation.depth.masks import depth_regions
from vissim.validation.depth.renders import DepthBuilt
from vissim.validation.depth.schema import DepthCampaignSettings
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.metrics import MEAN_ABS_DIFF, PSNR, SSIM, added_metrics, added_scores
from vissim.validation.engine.truth import add_bench_diffraction

__all__ = ["compute_depth_item"]


def _region_metrics(comparison, mask: np.ndarray) -> dict:
    """The pixels, PSNR (dB), MSE, mean |difference| and mean SSIM of ``comparison`` over ``mask``."""
    n = int(mask.sum())
    if n == 0:
        return {"n_px": 0, PSNR.name: None, "mse": None, MEAN_ABS_DIFF.name: None, SSIM.name: None,
                **{m.name: None for m in added_metrics()}}
    psnr = PSNR.value(comparison, mask)
    return {"n_px": n, PSNR.name: psnr if math.isfinite(psnr) else "inf",
            "mse": float(comparison.squared_error_map[mask].mean()),
            MEAN_ABS_DIFF.name: MEAN_ABS_DIFF.value(comparison, mask), SSIM.name: SSIM.value(comparison, mask),
            **added_scores(comparison, mask)}


def _region_table(comparison, masks) -> dict:
    table = {name: _region_metrics(comparison, mask) for name, mask in masks.interiors.items()}
    table["boundary"] = _region_metrics(comparison, masks.boundary)
    table["frame"] = _region_metrics(comparison, masks.frame)
    table["all"] = {**comparison.as_json(), **added_scores(comparison)}
    table["all"]["n_px"] = int(np.prod(comparison.shape[:2]))
    return table


def _scene_layers(scene, images: dict) -> list:
    """Each panel rendered alone, as a `SceneLayer` (campaign sampling / oversample).

    A fronto panel's proximity is ``1 / distance``; a tilted chart's is its own proximity pass
    divided by its coverage (the pass holds the pixel's mean proximity, 0 where it sees nothing).
    """
    from vissim.optics.depth.layered import SceneLayer

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


@dataclass
class _DepthItem:
    """One depth item being computed: its configuration built once, renders, regions and comparisons."""

    built: DepthBuilt
    settings: DepthCampaignSettings
    item_dir: Path
    provenance: dict
    renders: dict
    saved: dict = field(default_factory=dict)
    references: dict = field(default_factory=dict)  # optics -> (truth, its noise floor)
    comparisons: list = field(default_factory=list)

    def save(self, name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(self.item_dir, name, pixels, self.provenance, preview)

    def frame(self, pixels: np.ndarray) -> np.ndarray:
        """Integrated onto the campaign's pixels, the margin cropped."""
        pixels, margin = block_mean(pixels, self.settings.oversample), self.built.margin_px
        return pixels if margin == 0 else pixels[margin:-margin, margin:-margin]


def _regions(item: _DepthItem):
    """The regions (panel interiors, occlusion band, frame) from the depth pass, and the images that show them."""
    scene, setup = item.built.configuration.scene, item.built.setup
    proximity = item.frame(item.renders["proximity"])

    def radius_px(p):
        with np.errstate(divide="ignore"):
            distance = np.where(p > 1e-9, 1.0 / np.maximum(p, 1e-9), np.inf)
        return 0.5 * setup.blur_diameter_at_arcmin(distance) / scene.arcmin_per_px

    masks = depth_regions(proximity, panel_geometries(scene), radius_px,
                          pupil_diameter_mm=item.built.eye.pupil_diameter_mm, arcmin_per_px=scene.arcmin_per_px,
                          margin_px=item.settings.margin_px)
    item.saved |= {"truth": item.save("truth", item.renders["truth_0"]),
                   "all_in_focus": item.save("all_in_focus", item.frame(item.renders["all_in_focus"])),
                   "proximity": item.save("proximity_diopters", proximity, preview=False),
                   "regions": item.save("regions", masks.label_image().astype(np.float32), preview=False)}
    return masks


def _simulate(item: _DepthItem, source: str, mode: str, layers):
    """One simulation of the item: from the RGB-D renders (`blur_depth`) or the scene's layers (`composite_layers`)."""
    from vissim.optics.depth.depth_map import blur_depth
    from vissim.optics.depth.layered import composite_layers
    from vissim.render.depth_render import proximity_to_depth_m

    settings, s, scene = item.settings, item.settings.oversample, item.built.configuration.scene
    common = dict(eye=item.built.blur_eye, arcmin_per_px=scene.arcmin_per_px / s, wavelength_nm=settings.wavelength_nm,
                  layer_spacing_fraction=settings.layer_spacing_fraction, mode=mode, crop_px=item.built.margin_px * s)
    if source == "rgbd":
        return blur_depth(item.renders["all_in_focus"], proximity_to_depth_m(item.renders["proximity"]), **common)
    return composite_layers(layers, **common)


def _references(item: _DepthItem, mode: str):
    """The truth for ``mode`` and its noise floor (the two seeds compared), made once per mode: wave optics
    against the render + the aperture's in-focus diffraction."""
    if mode not in item.references:
        truths = (item.renders["truth_0"], item.renders["truth_1"])
        if mode == "wave":
            aperture = replace(item.built.setup, wavelength_nm=item.settings.wavelength_nm)
            scene = item.built.configuration.scene
            truths = tuple(add_bench_diffraction(t, aperture, scene.arcmin_per_px) for t in truths)
            item.saved["truth_diffracted"] = item.save("truth_diffracted", truths[0])
        item.references[mode] = (truths[0], noise_floor(truths[0], truths[1], item.settings.data_range))
    return item.references[mode]


def _compare(item: _DepthItem, source: str, mode: str, layers, masks) -> None:
    """One simulation against the render, per region, beside the two seeds' floor over the same pixels."""
    started = time.perf_counter()
    result = _simulate(item, source, mode, layers)
    simulated = block_mean(result.image, item.settings.oversample)
    reference, floor = _references(item, mode)
    data_range = item.settings.data_range
    comparison = compare_images(reference, simulated, data_range=data_range)
    tag = f"{mode}_{source}"
    item.comparisons.append({
        "simulation": f"{mode} {source}",
        "optics": mode,
        "input": source,
        "reference_image": "truth" if mode == "geometric" else "truth_diffracted",
        "regions": _region_table(comparison, masks),
        "noise_floor": _region_table(floor, masks),
        "depth_blur": {k: v for k, v in result.as_json().items() if k != "layers"},
        "seconds": time.perf_counter() - started,
        "images": {"simulation": item.save(f"sim_{tag}", simulated),
                   "abs_diff_map": item.save(f"sim_{tag}_ad", comparison.abs_diff_map, preview=False)},
    })


def _panels_record(built: DepthBuilt) -> list[dict]:
    scene, setup = built.configuration.scene, built.setup
    return [{"name": g.name, "letters": scene.panels[g.index].chart.letters, "logmar": scene.panels[g.index].chart.logmar,
             "distance_left_m": g.distance_left_m, "distance_right_m": g.distance_right_m,
             "blur_diameter_arcmin": [float(setup.blur_diameter_at_arcmin(d))
                                      for d in (g.distance_left_m, g.distance_right_m)]}
            for g in panel_geometries(scene)]


def _masks_record(masks, settings: DepthCampaignSettings) -> dict:
    return {"jump_diopters": masks.jump_diopters, "margin_px": settings.margin_px,
            "regions": list(masks.interiors) + ["boundary", "frame"],
            "definition": "interior: >= blur radius + margin from any depth discontinuity and the frame; "
                          "boundary: within that of a discontinuity; frame: within the largest blur radius + "
                          "margin of the image border (see vissim.validation.depth.masks)"}


def compute_depth_item(key: str, built: DepthBuilt, settings: DepthCampaignSettings, images: dict,
                       item_dir: Path, *, render_provenance: dict | None = None) -> dict:
    """Simulate, compare per region, write images and ``result.json`` (last) for one configuration.

    ``images``: the renders by name (`vissim.validation.depth.renders.render_specs`).
    """
    started = time.perf_counter()
    config, eye = built.configuration, built.eye
    provenance = make_provenance(item=key, configuration=config.as_json(), settings=settings,
                                 render_provenance=render_provenance or {})
    item = _DepthItem(built, settings, item_dir, provenance, images)
    masks = _regions(item)
    layers = _scene_layers(config.scene, images) if "layered" in settings.inputs else None
    for source in settings.inputs:
        for mode in settings.simulations:
            _compare(item, source, mode, layers, masks)
    result = {
        "key": key,
        "configuration": config.as_json(),
        "equivalent_eye": {**asdict(eye), "prescription": eye.prescription.format(4),
                           "power_matrix_diopters": [list(r) for r in eye.prescription.power_matrix()]},
        "panels": _panels_record(built),
        "frame_margin_px": built.margin_px,
        "masks": _masks_record(masks, settings),
        "comparisons": item.comparisons,
        "images": item.saved,
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result, overwrite=True)  # last: marks the item finished
    return result
