"""One campaign item: simulations against the ground truth(s), with metrics, maps and images.

The truths: the bench render (and, for wave-optical simulations, the render convolved with the
aperture's diffraction) and, with ``wave_truth``, the wave bench (:mod:`vissim.validation.wave_bench`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import ndimage

from vissim.atomic import write_json_atomic
from vissim.charts import optotype_tile
from vissim.imageio import write_image
from vissim.provenance import json_safe, make_provenance
from vissim.validation.campaign import CampaignSettings, Configuration
from vissim.validation.metrics import compare_images, noise_floor
from vissim.validation.registration import register
from vissim.validation.renders import campaign_bench
from vissim.validation.simulate import add_bench_diffraction, block_mean, simulate, simulation_setup
from vissim.validation.wave_bench import WAVE_BENCH, compute_wave_bench, residual_budget

__all__ = ["compute_item", "synthetic_tile", "save_item_image"]

log = logging.getLogger(__name__)

#: Registration may not move an image further than this (px); more means a wrong crop.
MAX_SHIFT_PX = 6.0


#: The synthetic chart is simulated at this many sub-pixels per campaign pixel (per axis).
SYNTHETIC_OVERSAMPLE = 5


def synthetic_tile(configuration: Configuration, settings: CampaignSettings, oversample: int = 1) -> np.ndarray:
    """The synthetic chart tile: the same letter, size, contrast and position the bench shows.

    The letter is centred on the tile's centre (the bench's optical axis), not snapped to the
    pixel grid; ``oversample`` renders it on a grid that many times finer.
    """
    rows, cols = settings.tile_px
    return optotype_tile(
        configuration.letter,
        configuration.logmar,
        arcmin_per_px=settings.arcmin_per_px / oversample,
        shape_px=(rows * oversample, cols * oversample),
        polarity=configuration.polarity,
        viewing_distance_m=settings.chart_distance_m,
        snap_to_pixels=False,
    ).pixels


def save_item_image(item_dir: Path, name: str, pixels: np.ndarray, provenance: dict, preview: bool = True) -> str:
    """``name``.exr (provenance in its header) and, with ``preview``, ``name``.png (provenance sidecar)."""
    record = {**provenance, "image": name}
    write_image(item_dir / f"{name}.exr", np.asarray(pixels, np.float32), provenance=record, overwrite=True)
    if preview:
        write_image(item_dir / f"{name}.png", np.clip(np.asarray(pixels, np.float32), 0, 1), provenance=record,
                    overwrite=True)
    return f"items/{item_dir.name}/{name}.exr"


def _comparison(kind: str, input_name: str, reference_kind: str, reference_image: str, setup, registration: dict,
                simulated: np.ndarray, comparison, save, stem: str) -> dict:
    """One comparison's record in result.json, its simulation and maps saved as ``stem``*."""
    return {
        "simulation": kind,
        "input": input_name,
        "reference_kind": reference_kind,
        "reference_image": reference_image,
        "setup": setup.as_json(),
        "registration": registration,
        "metrics": comparison.as_json(),
        "images": {
            "simulation": save(stem, simulated),
            "ssim_map": save(f"{stem}_ssim", comparison.ssim_map, preview=False),
            "abs_diff_map": save(f"{stem}_ad", comparison.abs_diff_map, preview=False),
        },
    }


#: The wave bench's truth and a simulation share one grid: nothing is registered (module wave_bench).
UNREGISTERED = {"shift_rows_px": 0.0, "shift_cols_px": 0.0, "error": None, "upsample_factor": None,
                "method": "none: the wave truth and the simulation are laid out on one grid from one chart"}


def compute_item(
    key: str,
    configuration: Configuration,
    settings: CampaignSettings,
    truth_a: np.ndarray,
    truth_b: np.ndarray | None,
    no_lens: np.ndarray,
    item_dir: Path,
    *,
    source: dict | None = None,
    render_provenance: dict | None = None,
) -> dict:
    """Compare every requested simulation with the ground truth; write images and result.json.

    ``truth_b`` is a second, independent ground truth (another seed or exposure) for the noise
    floor; without it the floor is reported as unknown.  ``render_provenance`` (the provenance
    of the renders or captures the item uses, by role) goes, as given, into every image's.
    """
    started = time.perf_counter()
    provenance = make_provenance(item=key, configuration=configuration.as_json(), settings=settings,
                                 source=source or {}, render_provenance=render_provenance or {})

    def save(name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(item_dir, name, pixels, provenance, preview)

    bench = campaign_bench(configuration, settings)
    lenses = bench.physical_lenses
    bench_setup = bench.viewing_setup(settings.wavelength_nm)  # trial_lens_effect once per item
    captured = bool(source and source.get("ground_truth") == "capture")
    # A photograph already carries the lens's diffraction; a render carries none (module simulate).
    truth_wave_a = truth_a if captured else add_bench_diffraction(truth_a, bench_setup, settings.arcmin_per_px)
    references = {"geometric": truth_a, "wave": truth_wave_a}
    floors = {"geometric": None, "wave": None}
    if truth_b is not None:
        truth_wave_b = truth_b if captured else add_bench_diffraction(truth_b, bench_setup, settings.arcmin_per_px)
        floors = {
            "geometric": noise_floor(truth_a, truth_b, settings.data_range).as_json(),
            "wave": noise_floor(truth_wave_a, truth_wave_b, settings.data_range).as_json(),
        }
    fine_synthetic = synthetic_tile(configuration, settings, SYNTHETIC_OVERSAMPLE)
    inputs = {"render": (no_lens, 1), "synthetic": (fine_synthetic, SYNTHETIC_OVERSAMPLE)}
    images = {
        "truth": save("truth", truth_a),
        "truth_diffracted": save("truth_diffracted", truth_wave_a),
        "no_lens_render": save("no_lens_render", no_lens),
        "synthetic": save("synthetic", block_mean(fine_synthetic, SYNTHETIC_OVERSAMPLE)),
    }
    # The wave bench (module wave_bench): the bench's chart through the traced lenses' wave PSF.
    # A capture's truth is the photograph; the virtual bench's wave optics does not stand in for it.
    traced_truth, budget = None, None
    if settings.wave_truth and not captured:
        traced_truth = compute_wave_bench(bench, configuration, settings, SYNTHETIC_OVERSAMPLE)
        images["wave_truth"] = save_item_image(item_dir, "wave_truth", traced_truth.pixels,
                                               {**provenance, "wave_truth": json_safe(traced_truth.provenance)})
        budget = residual_budget(bench, bench_setup, settings.wavelength_nm)
        floors[WAVE_BENCH] = None  # noise-free: no floor
    comparisons = []
    # Fine inputs are moved onto the bench's letter position once per item (the offset is the
    # letter's placement, the same for every simulation): shifting the fine image is accurate,
    # shifting an under-sampled result at the campaign's sampling is not.
    prealigned: dict[str, tuple[np.ndarray, tuple[float, float]]] = {}
    for kind in settings.simulations:
        setup = simulation_setup(kind, bench_setup, lenses, configuration, settings)
        reference_kind = "geometric" if setup.mode == "geometric" else "wave"
        reference = references[reference_kind]
        for input_name in settings.inputs:
            image, oversample = inputs[input_name]
            if oversample > 1 and input_name not in prealigned:
                coarse = register(reference, simulate(setup, image, settings, oversample=oversample), upsample_factor=100)
                offset = (coarse.shift_rows_px, coarse.shift_cols_px)
                shifted = ndimage.shift(image, (offset[0] * oversample, offset[1] * oversample), order=3, mode="nearest")
                prealigned[input_name] = (shifted, offset)
            image, offset = prealigned.get(input_name, (image, (0.0, 0.0)))
            simulated = simulate(setup, image, settings, oversample=oversample)
            registration = register(reference, simulated, upsample_factor=100)
            registration = replace(registration, shift_rows_px=offset[0] + registration.shift_rows_px,
                                   shift_cols_px=offset[1] + registration.shift_cols_px)
            if math.hypot(*registration.shift_px) > MAX_SHIFT_PX:
                log.warning("%s: %s/%s registered by %.1f px (> %.0f): check the crop", configuration.name, kind,
                            input_name, math.hypot(*registration.shift_px), MAX_SHIFT_PX)
            comparison = compare_images(reference, registration.registered, data_range=settings.data_range)
            comparisons.append(_comparison(kind, input_name, reference_kind,
                                           "truth" if reference_kind == "geometric" else "truth_diffracted", setup,
                                           registration.as_json(), registration.registered, comparison, save,
                                           f"{kind}_{input_name}"))
        if traced_truth is not None and setup.mode == "wave":
            # the synthetic chart as laid out, unshifted: the truth is laid out from the same chart
            simulated = simulate(setup, fine_synthetic, settings, oversample=SYNTHETIC_OVERSAMPLE)
            comparison = compare_images(traced_truth.pixels, simulated, data_range=settings.data_range)
            comparisons.append(_comparison(kind, "synthetic", WAVE_BENCH, "wave_truth", setup, UNREGISTERED, simulated,
                                           comparison, save, f"{kind}_synthetic_{WAVE_BENCH}"))
    result = {
        "key": key,
        "configuration": configuration.as_json(),
        "lens_label": configuration.lens_label(),
        "lenses": [
            {"sphere_diopters": l.sphere_diopters, "cylinder_diopters": l.cylinder_diopters, "axis_deg": l.axis_deg,
             "refractive_index": l.refractive_index, "center_thickness_mm": l.center_thickness_mm}
            for l in lenses
        ],
        "noise_floor": floors,
        "comparisons": comparisons,
        "wave_bench": budget,
        "images": images,
        "source": source or {},
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result, overwrite=True)  # last: marks the item finished
    return result
