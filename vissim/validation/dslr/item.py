"""One campaign item: simulations against the ground truth(s), with metrics, maps and images.

The truths: the bench render (and, for wave-optical simulations, the render convolved with the
aperture's diffraction) and, with ``wave_truth``, the wave bench (`vissim.validation.dslr.wave_bench`).
With the wave bench, a rendered item also gets the geometric self-check: the lens trace's ray
optics applied to the synthetic chart (simulation ``traced_rays``), against the render.

**Alignment.**  A simulation of the bench's no-lens render is registered onto the truth and
shifted there (cubic spline): that render exists only at the campaign's sampling.  A
simulation of the synthetic chart is aligned on the fine grid instead: the fine chart is
shifted by the accumulated offset, simulated and registered again, until the remaining
registration is below `ALIGN_TOLERANCE_PX` (at most `MAX_ALIGN_PASSES` passes);
the simulated image is compared as it comes, never resampled.  One registration of the
under-sampled result is biased by 0.01-0.03 px, and shifting it by a spline costs accuracy:
together they held six astigmatic configurations of the thesis campaign (N, K x 180, Z x 90)
at -0.1...+1.8 dB over the noise floor, for geometric optics that reaches it elsewhere.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
from scipy import ndimage

from vissim.atomic import write_json_atomic
from vissim.charts import optotype_tile
from vissim.fit.capture import fit_bench_item
from vissim.optics.resample import SUBPIXELS_PER_PX
from vissim.provenance import json_safe, make_provenance
from vissim.validation.dslr.schema import CampaignSettings, Configuration
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.imaging.registration import Registration, register
from vissim.validation.dslr.renders import DslrBuilt
from vissim.optics.resample import block_mean
from vissim.validation.dslr.simulate import simulate, simulation_setup
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.truth import add_bench_diffraction
from vissim.validation.dslr.wave_bench import (
    TRACED_RAYS,
    WAVE_BENCH,
    compute_wave_bench,
    residual_budget,
    traced_ray_image,
    traced_rays_setup,
)

__all__ = ["compute_item", "synthetic_tile"]

log = logging.getLogger(__name__)

#: Registration may not move an image further than this (px); more means a wrong crop.
MAX_SHIFT_PX = 6.0


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


def _comparison(kind: str, input_name: str, reference_kind: str, reference_image: str, setup: dict,
                registration: dict, simulated: np.ndarray, comparison, save, stem: str) -> dict:
    """One comparison's record in result.json, its simulation and maps saved as ``stem``*."""
    return {
        "simulation": kind,
        "input": input_name,
        "reference_kind": reference_kind,
        "reference_image": reference_image,
        "setup": setup,
        "registration": registration,
        "metrics": comparison.as_json(),
        "images": {
            "simulation": save(stem, simulated),
            "ssim_map": save(f"{stem}_ssim", comparison.ssim_map, preview=False),
            "abs_diff_map": save(f"{stem}_ad", comparison.abs_diff_map, preview=False),
        },
    }


#: The fine pre-alignment stops when the registration left is below this in both axes (px) ...
ALIGN_TOLERANCE_PX = 0.01
#: ... or after this many simulations (the thesis campaign: 1-3 passes for 482 of its 497 fine
#: alignments; 15 reached 4, 11 of them with one 0.01 px step left).
MAX_ALIGN_PASSES = 4
#: Registrations resolve 1/100 px: "below 0.01 px" is then "measured as 0", within 0.005 px.
REGISTRATION_UPSAMPLE = 100
FINE_ALIGNMENT = ("fine pre-alignment: the fine input shifted (cubic spline) by the accumulated registration "
                  f"(cross-correlation, normalization=None) until < {ALIGN_TOLERANCE_PX:g} px is left; "
                  "the simulated image itself is not resampled")


def _fine_shift(image: np.ndarray, offset_px: tuple[float, float], oversample: int) -> np.ndarray:
    if offset_px == (0.0, 0.0):
        return image
    return ndimage.shift(image, (offset_px[0] * oversample, offset_px[1] * oversample), order=3, mode="nearest")


def align(reference: np.ndarray, simulate_fine, image: np.ndarray, oversample: int,
          start_px: tuple[float, float] = (0.0, 0.0)) -> tuple[Registration, dict]:
    """``simulate_fine(image)`` aligned onto ``reference``: the registration (with the image) and its record.

    ``oversample == 1`` (the no-lens render): one registration, the result shifted onto the
    reference.  Finer inputs: the module docstring's fine pre-alignment, from ``start_px`` (a
    previous simulation's offset; the letter's placement is the same for every simulation).
    The recorded shift is the offset applied to the input, in campaign pixels.
    """
    if oversample == 1:
        registration = register(reference, simulate_fine(image), upsample_factor=REGISTRATION_UPSAMPLE)
        return registration, registration.as_json()
    offset = (float(start_px[0]), float(start_px[1]))
    for passes in range(1, MAX_ALIGN_PASSES + 1):
        simulated = simulate_fine(_fine_shift(image, offset, oversample))
        residual = register(reference, simulated, upsample_factor=REGISTRATION_UPSAMPLE)
        if max(abs(residual.shift_rows_px), abs(residual.shift_cols_px)) < ALIGN_TOLERANCE_PX:
            break
        if passes < MAX_ALIGN_PASSES:
            offset = (offset[0] + residual.shift_rows_px, offset[1] + residual.shift_cols_px)
    else:
        log.info("fine alignment stopped after %d passes with (%.3f, %.3f) px left", MAX_ALIGN_PASSES,
                 residual.shift_rows_px, residual.shift_cols_px)
    registration = replace(residual, shift_rows_px=offset[0], shift_cols_px=offset[1], registered=simulated)
    record = {**registration.as_json(), "method": FINE_ALIGNMENT, "passes": passes,
              "residual_px": [residual.shift_rows_px, residual.shift_cols_px]}
    return registration, record


#: The wave bench's truth and a simulation share one grid: nothing is registered (module wave_bench).
UNREGISTERED = {"shift_rows_px": 0.0, "shift_cols_px": 0.0, "error": None, "upsample_factor": None,
                "method": "none: the wave truth and the simulation are laid out on one grid from one chart"}


def compute_item(
    key: str,
    built: DslrBuilt,
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
    configuration = built.configuration
    provenance = make_provenance(item=key, configuration=configuration.as_json(), settings=settings,
                                 source=source or {}, render_provenance=render_provenance or {})

    def save(name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(item_dir, name, pixels, provenance, preview)

    bench, lenses, bench_setup = built.bench, built.lenses, built.setup
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
    fine_synthetic = synthetic_tile(configuration, settings, SUBPIXELS_PER_PX)
    inputs = {"render": (no_lens, 1), "synthetic": (fine_synthetic, SUBPIXELS_PER_PX)}
    images = {
        "truth": save("truth", truth_a),
        "truth_diffracted": save("truth_diffracted", truth_wave_a),
        "no_lens_render": save("no_lens_render", no_lens),
        "synthetic": save("synthetic", block_mean(fine_synthetic, SUBPIXELS_PER_PX)),
    }
    # The wave bench (module wave_bench): the bench's chart through the traced lenses' wave PSF.
    # A capture's truth is the photograph; the virtual bench's wave optics does not stand in for it.
    traced_truth, budget = None, None
    if settings.wave_truth and not captured:
        traced_truth = compute_wave_bench(bench, configuration, settings, SUBPIXELS_PER_PX)
        images["wave_truth"] = save_item_image(item_dir, "wave_truth", traced_truth.pixels,
                                               {**provenance, "wave_truth": json_safe(traced_truth.provenance)})
        budget = residual_budget(bench, bench_setup, settings.wavelength_nm)
        floors[WAVE_BENCH] = None  # noise-free: no floor
    comparisons = []
    offsets: dict[str, tuple[float, float]] = {}  # each input's latest fine alignment: the next one's start

    def compare_with_render(kind: str, input_name: str, reference_kind: str, setup: dict, simulate_fine) -> None:
        image, oversample = inputs[input_name]
        reference = references[reference_kind]
        registration, record = align(reference, simulate_fine, image, oversample, offsets.get(input_name, (0.0, 0.0)))
        if oversample > 1:
            offsets[input_name] = registration.shift_px
        if math.hypot(*registration.shift_px) > MAX_SHIFT_PX:
            log.warning("%s: %s/%s registered by %.1f px (> %.0f): check the crop", configuration.name, kind,
                        input_name, math.hypot(*registration.shift_px), MAX_SHIFT_PX)
        comparison = compare_images(reference, registration.registered, data_range=settings.data_range)
        comparisons.append(_comparison(kind, input_name, reference_kind,
                                       "truth" if reference_kind == "geometric" else "truth_diffracted", setup,
                                       record, registration.registered, comparison, save, f"{kind}_{input_name}"))

    for kind in settings.simulations:
        setup = simulation_setup(kind, bench_setup, lenses, configuration, settings)
        reference_kind = "geometric" if setup.mode == "geometric" else "wave"
        for input_name in settings.inputs:
            oversample = inputs[input_name][1]
            compare_with_render(kind, input_name, reference_kind, setup.as_json(),
                                lambda image, setup=setup, oversample=oversample: simulate(setup, image, settings,
                                                                                           oversample=oversample))
        if traced_truth is not None and setup.mode == "wave":
            # the synthetic chart as laid out, unshifted: the truth is laid out from the same chart
            simulated = simulate(setup, fine_synthetic, settings, oversample=SUBPIXELS_PER_PX)
            comparison = compare_images(traced_truth.pixels, simulated, data_range=settings.data_range)
            comparisons.append(_comparison(kind, "synthetic", WAVE_BENCH, "wave_truth", setup.as_json(), UNREGISTERED,
                                           simulated, comparison, save, f"{kind}_synthetic_{WAVE_BENCH}"))
    if traced_truth is not None:
        # The geometric self-check (module wave_bench): the trace's ray optics against the render.
        compare_with_render(TRACED_RAYS, "synthetic", "geometric", traced_rays_setup(bench),
                            lambda image: traced_ray_image(bench, image, SUBPIXELS_PER_PX))
    fit = None
    if settings.fit_rx and configuration.lenses:  # the refraction the capture shows, beside vergence theory
        fit = fit_bench_item(truth_a, no_lens, bench, arcmin_per_px=settings.arcmin_per_px, photograph=captured)
    result = {
        "key": key,
        "configuration": configuration.as_json(),
        "lens_label": configuration.lens_label(),
        "lenses": [{k: v for k, v in asdict(l).items() if k != "back_surface_diopters"} for l in lenses],
        "noise_floor": floors,
        "comparisons": comparisons,
        "wave_bench": budget,
        "fit_rx": fit,
        "images": images,
        "source": source or {},
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result, overwrite=True)  # last: marks the item finished
    return result
