"""One campaign item: simulations against the ground truth(s), with metrics, maps and images.

The truths: the bench render (and, for wave-optical simulations, the render convolved with the
aperture's diffraction) and, with ``wave_truth``, the wave bench (`vissim.validation.dslr.wave_bench`).
With the wave bench, a rendered item also gets the geometric self-check: the lens trace's ray
optics applied to the synthetic chart (simulation ``traced_rays``), against the render.

How a simulation is aligned onto its truth: `vissim.validation.dslr.align`.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.charts import Chart, render_chart_angular
from vissim.fit.capture import fit_bench_item
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.optics.blur.resample import SUBPIXELS_PER_PX, block_mean
from vissim.provenance import json_safe, make_provenance
from vissim.validation.dslr.align import MAX_SHIFT_PX, UNREGISTERED, align
from vissim.validation.dslr.renders import DslrBuilt
from vissim.validation.dslr.schema import CampaignSettings, Configuration
from vissim.validation.dslr.simulate import SimulationSetup, simulate, simulation_setup
from vissim.validation.dslr.wave_bench import (
    TRACED_RAYS,
    WAVE_BENCH,
    compute_wave_bench,
    residual_budget,
    traced_ray_image,
    traced_rays_setup,
    wave_bench_chart,
)
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.metrics import added_scores
from vissim.validation.engine.truth import add_bench_diffraction, cached_psf

__all__ = ["compute_item", "synthetic_chart"]

log = logging.getLogger(__name__)


def synthetic_chart(configuration: Configuration, settings: CampaignSettings, oversample: int = 1) -> Chart:
    """The synthetic chart tile: the chart the bench shows (`wave_bench_chart`), rendered in visual angle.

    The letter is centred on the tile's centre (the bench's optical axis), not snapped to the
    pixel grid; ``oversample`` renders it on a grid that many times finer.
    """
    rows, cols = settings.tile_px
    return render_chart_angular(wave_bench_chart(configuration, settings), settings.arcmin_per_px / oversample,
                                size_px=(rows * oversample, cols * oversample), snap_to_pixels=False)


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
        "metrics": {**comparison.as_json(), **added_scores(comparison)},
        "images": {
            "simulation": save(stem, simulated),
            "ssim_map": save(f"{stem}_ssim", comparison.ssim_map, preview=False),
            "abs_diff_map": save(f"{stem}_ad", comparison.abs_diff_map, preview=False),
        },
    }


@dataclass
class _Item:
    """One item being computed: its inputs, truths, the images saved so far and its comparisons."""

    built: DslrBuilt
    settings: CampaignSettings
    item_dir: Path
    provenance: dict
    captured: bool
    inputs: dict  # name -> (image, oversample)
    references: dict = field(default_factory=dict)  # reference kind -> truth image
    floors: dict = field(default_factory=dict)
    images: dict = field(default_factory=dict)
    comparisons: list = field(default_factory=list)
    offsets: dict = field(default_factory=dict)  # each input's latest fine alignment: the next one's start

    def save(self, name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(self.item_dir, name, pixels, self.provenance, preview)

    def compare_with_render(self, kind: str, input_name: str, reference_kind: str, setup: dict, simulate_fine) -> None:
        """``simulate_fine`` of an input, aligned onto the render's truth (`align`), compared and recorded."""
        image, oversample = self.inputs[input_name]
        reference = self.references[reference_kind]
        registration, record = align(reference, simulate_fine, image, oversample,
                                     self.offsets.get(input_name, (0.0, 0.0)))
        if oversample > 1:
            self.offsets[input_name] = registration.shift_px
        if math.hypot(*registration.shift_px) > MAX_SHIFT_PX:
            log.warning("%s: %s/%s registered by %.1f px (> %.0f): check the crop", self.built.configuration.name,
                        kind, input_name, math.hypot(*registration.shift_px), MAX_SHIFT_PX)
        comparison = compare_images(reference, registration.registered, data_range=self.settings.data_range)
        self.comparisons.append(_comparison(kind, input_name, reference_kind,
                                            "truth" if reference_kind == "geometric" else "truth_diffracted", setup,
                                            record, registration.registered, comparison, self.save,
                                            f"{kind}_{input_name}"))


def _truths(item: _Item, truth_a: np.ndarray, truth_b: np.ndarray | None) -> None:
    """The references (the render; for wave optics the render + the aperture's diffraction) and their floors.

    A photograph already carries the lens's diffraction; a render carries none (module simulate).
    """
    settings, setup = item.settings, item.built.setup

    def diffracted(truth):
        return truth if item.captured else add_bench_diffraction(truth, setup, settings.arcmin_per_px)

    item.references = {"geometric": truth_a, "wave": diffracted(truth_a)}
    item.floors = {"geometric": None, "wave": None}
    if truth_b is not None:
        item.floors = {"geometric": noise_floor(truth_a, truth_b, settings.data_range).as_json(),
                       "wave": noise_floor(item.references["wave"], diffracted(truth_b), settings.data_range).as_json()}
    item.images |= {"truth": item.save("truth", truth_a),
                    "truth_diffracted": item.save("truth_diffracted", item.references["wave"])}


def _wave_bench(item: _Item, fine_chart: Chart):
    """The wave bench (module wave_bench): the chart through the traced lenses' wave PSF, and its residual budget.

    None for a capture: the virtual bench's wave optics does not stand in for a photograph.
    """
    if not item.settings.wave_truth or item.captured:
        return None, None
    bench, settings = item.built.bench, item.settings
    traced = compute_wave_bench(bench, fine_chart, settings, SUBPIXELS_PER_PX)
    item.images["wave_truth"] = save_item_image(item.item_dir, "wave_truth", traced.pixels,
                                                {**item.provenance, "wave_truth": json_safe(traced.provenance)})
    item.floors[WAVE_BENCH] = None  # noise-free: no floor
    return traced, residual_budget(bench, item.built.setup, settings.wavelength_nm)


def _simulations(item: _Item, traced_truth) -> None:
    """Every simulation of every input against the render, and the wave-optical ones against the wave bench."""
    settings, built = item.settings, item.built
    for kind in settings.simulations:
        setup = simulation_setup(kind, built.setup, built.lenses, built.configuration, settings)
        reference_kind = "geometric" if setup.mode == "geometric" else "wave"
        for input_name in settings.inputs:
            oversample = item.inputs[input_name][1]
            item.compare_with_render(kind, input_name, reference_kind, setup.as_json(),
                                     lambda image, setup=setup, oversample=oversample:
                                     simulate(setup, image, settings, oversample=oversample))
        if traced_truth is not None and setup.mode == "wave":
            _against_wave_bench(item, setup, traced_truth)


def _against_wave_bench(item: _Item, setup: SimulationSetup, traced_truth) -> None:
    """The synthetic chart as laid out, unshifted, against the wave truth laid out from the same chart."""
    fine = item.inputs["synthetic"][0]
    simulated = simulate(setup, fine, item.settings, oversample=SUBPIXELS_PER_PX)
    comparison = compare_images(traced_truth.pixels, simulated, data_range=item.settings.data_range)
    item.comparisons.append(_comparison(setup.kind, "synthetic", WAVE_BENCH, "wave_truth", setup.as_json(),
                                        UNREGISTERED, simulated, comparison, item.save,
                                        f"{setup.kind}_synthetic_{WAVE_BENCH}"))


def _self_check(item: _Item) -> None:
    """The geometric self-check (module wave_bench): the trace's ray optics against the render."""
    bench = item.built.bench
    item.compare_with_render(TRACED_RAYS, "synthetic", "geometric", traced_rays_setup(bench),
                             lambda image: traced_ray_image(bench, image, SUBPIXELS_PER_PX))


def _wave_psf(item: _Item) -> dict | None:
    """The wave simulation's PSF at the synthetic chart's sampling, saved with its numbers (the report's PSF figures
    read it); None without a wave simulation."""
    if "wave" not in item.settings.simulations:
        return None
    built, settings = item.built, item.settings
    setup = simulation_setup("wave", built.setup, built.lenses, built.configuration, settings).setup
    step = settings.arcmin_per_px / SUBPIXELS_PER_PX
    psf = cached_psf(setup, step, "wave")
    image = save_item_image(item.item_dir, "psf_wave", psf.data, item.provenance, preview=False)
    return {"image": image, "simulation": "wave", "arcmin_per_px": psf.arcmin_per_px,
            "pupil_diameter_mm": psf.pupil_diameter_mm, "wavelength_nm": psf.wavelengths_nm[0], "mode": psf.mode,
            "pixel": psf.pixel, "energy_in_field": psf.energy_in_field}


def compute_item(key: str, built: DslrBuilt, settings: CampaignSettings, truth_a: np.ndarray,
                 truth_b: np.ndarray | None, no_lens: np.ndarray, item_dir: Path, *, source: dict | None = None,
                 render_provenance: dict | None = None) -> dict:
    """Compare every requested simulation with the ground truth; write images and result.json.

    ``truth_b`` is a second, independent ground truth (another seed or exposure) for the noise
    floor; without it the floor is reported as unknown.  ``render_provenance`` (the provenance
    of the renders or captures the item uses, by role) goes, as given, into every image's.
    """
    started = time.perf_counter()
    configuration, source = built.configuration, source or {}
    provenance = make_provenance(item=key, configuration=configuration.as_json(), settings=settings, source=source,
                                 render_provenance=render_provenance or {})
    fine_chart = synthetic_chart(configuration, settings, SUBPIXELS_PER_PX)  # the simulations' and the wave bench's
    fine_chart.pixels.setflags(write=False)
    fine_synthetic = fine_chart.pixels
    item = _Item(built, settings, item_dir, provenance, source.get("ground_truth") == "capture",
                 {"render": (no_lens, 1), "synthetic": (fine_synthetic, SUBPIXELS_PER_PX)})
    _truths(item, truth_a, truth_b)
    item.images |= {"no_lens_render": item.save("no_lens_render", no_lens),
                    "synthetic": item.save("synthetic", block_mean(fine_synthetic, SUBPIXELS_PER_PX))}
    traced_truth, budget = _wave_bench(item, fine_chart)
    _simulations(item, traced_truth)
    if traced_truth is not None:
        _self_check(item)
    fit = None
    if settings.fit_rx and configuration.lenses:  # the refraction the capture shows, beside vergence theory
        fit = fit_bench_item(truth_a, no_lens, built.bench, arcmin_per_px=settings.arcmin_per_px,
                             photograph=item.captured)
    result = {
        "key": key,
        "configuration": configuration.as_json(),
        "lens_label": configuration.lens_label(),
        "lenses": [{k: v for k, v in asdict(l).items() if k != "back_surface_diopters"} for l in built.lenses],
        "noise_floor": item.floors,
        "comparisons": item.comparisons,
        "wave_bench": budget,
        "fit_rx": fit,
        "psf": _wave_psf(item),
        "images": item.images,
        "source": source,
        "seconds": time.perf_counter() - started,
        "provenance": provenance,
    }
    write_json_atomic(item_dir / "result.json", result, overwrite=True)  # last: marks the item finished
    return result
