"""Depth validation campaigns: renders of charts at several depths against :func:`vissim.optics.depth.blur_depth`.

A campaign TOML has a ``[depth_campaign]`` table (or ``[campaign]`` with ``kind = "depth"``)
of settings and ``[[config]]`` tables, each a scene file (``scene``, relative to the campaign
file) and an observer: an eye (``eye`` = prescription, ``pupil_mm``, ``accommodation_d``), the
DSLR (``camera = {f_number, focus_distance_m, focal_length_mm, lenses}``), or none (the scene
file's).  ``validation/depth.toml`` is the commented example.

Per configuration: the blurred render twice (``seeds``: the ground truth and its Monte-Carlo
noise floor) and the pinhole all-in-focus and depth renders (``aux_seed``, optionally
``oversample`` times finer); ``blur_depth`` of the all-in-focus image and depth for the
observer's equivalent eye (:func:`vissim.bench.depth_scene.equivalent_eye`), in geometric
and wave optics.  Mitsuba renders no diffraction, so ``geometric`` is compared with the render
and ``wave`` with the render convolved with the aperture's in-focus diffraction PSF (as
:func:`vissim.validation.simulate.add_bench_diffraction` does for the single-plane harness).
Metrics (:mod:`vissim.validation.depth_masks`) per panel interior, for the occlusion band and
for the whole image, each beside the same metric between the two seeds (the floor).

Run folder: as :mod:`vissim.validation.runner` (``campaign.json``, ``renders/<key>.exr`` keyed
by their inputs, ``items/<key>/result.json`` written last), so re-runs resume;
:func:`run_any_campaign` runs either kind of campaign file and builds its report.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.bench.depth_scene import (
    CameraViewer,
    DepthScene,
    EyeViewer,
    blur_diameter_arcmin,
    equivalent_eye,
    panel_geometries,
)
from vissim.bench.depth_scene_files import load_depth_scene_toml
from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.optics.prescription import Prescription
from vissim.optics.trial_lens import TrialLens
from vissim.provenance import json_safe, make_provenance
from vissim.validation.depth_masks import depth_regions, masked_metrics
from vissim.validation.fields import (
    MAX_SEED,
    MAX_SPP,
    choices,
    field_error,
    lenses,
    number,
    read_campaign_toml,
    seed_pair,
    table,
    tables,
    text,
    whole_number,
)
from vissim.validation.metrics import compare_images
from vissim.validation.runner import (
    RunSummary,
    _make_renders,
    check_run_options,
    connect_scheduler,
)

__all__ = ["DepthConfiguration", "DepthCampaignSettings", "DepthCampaign", "DepthRenderSpec", "load_depth_campaign",
           "is_depth_campaign", "render_depth_spec", "run_depth_campaign", "compute_depth_item", "run_any_campaign",
           "CampaignRun", "rebuild_any_report", "DEPTH_SIMULATIONS"]

log = logging.getLogger(__name__)

DEPTH_SIMULATIONS = ("geometric", "wave")
#: Bumped when the meaning of an item's inputs or results changes, so old results are not reused.
SCHEMA_VERSION = 1


@dataclass(frozen=True)
class DepthConfiguration:
    """One comparison: a scene (loaded from ``scene_file``) seen by one observer."""

    name: str
    scene_file: str
    scene: DepthScene
    viewer: EyeViewer | CameraViewer

    def as_json(self) -> dict:
        return {"name": self.name, "scene_file": self.scene_file, "viewer": json_safe(self.viewer),
                "viewer_label": self.viewer.label()}


@dataclass(frozen=True)
class DepthCampaignSettings:
    spp: int = 64
    aux_spp: int = 32
    seeds: tuple[int, int] = (1, 2)
    aux_seed: int = 3
    oversample: int = 1
    simulations: tuple[str, ...] = DEPTH_SIMULATIONS
    wavelength_nm: float = 550.0
    data_range: float = 1.0
    margin_px: float = 1.0
    layer_spacing_fraction: float = 0.5


@dataclass(frozen=True)
class DepthCampaign:
    name: str
    description: str
    settings: DepthCampaignSettings
    configurations: tuple[DepthConfiguration, ...]
    source: str = ""

    def item_key(self, configuration: DepthConfiguration) -> str:
        """Stable key of one item's inputs (scene content, observer, settings): equal inputs, equal key."""
        payload = {"schema": SCHEMA_VERSION, "settings": json_safe(self.settings),
                   "scene": json_safe(configuration.scene), "viewer": json_safe(configuration.viewer)}
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class DepthRenderSpec:
    """Everything one render depends on; ``key`` names its file in ``renders/``."""

    scene: DepthScene
    viewer: EyeViewer | CameraViewer
    view: str
    content: str
    spp: int
    seed: int
    oversample: int = 1

    @property
    def key(self) -> str:
        text = json.dumps({"schema": SCHEMA_VERSION, **self.as_json()}, sort_keys=True)
        return "depth-" + hashlib.sha256(text.encode()).hexdigest()[:16]

    def as_json(self) -> dict:
        return json_safe({f.name: getattr(self, f.name) for f in dataclasses.fields(self)})

    def render_scene(self) -> DepthScene:
        s = self.oversample
        if s == 1:
            return self.scene
        rows, cols = self.scene.size_px
        return dataclasses.replace(self.scene, arcmin_per_px=self.scene.arcmin_per_px / s, size_px=(rows * s, cols * s))


def render_depth_spec(spec: DepthRenderSpec):
    """Render one spec with Mitsuba on this machine (a worker process or a Dask worker).

    Returns the :class:`vissim.render.run.RenderResult`: pixels, variant and the spp used.
    """
    from vissim.render.depth_render import (
        render_view,  # the Mitsuba door, imported where it runs
    )

    result = render_view(spec.render_scene(), spec.viewer, view=spec.view, content=spec.content, spp=spec.spp,
                         seed=spec.seed)
    return result


def _specs(config: DepthConfiguration, settings: DepthCampaignSettings) -> dict[str, DepthRenderSpec]:
    truth = {f"truth_{i}": DepthRenderSpec(config.scene, config.viewer, "blurred", "radiance", settings.spp, seed)
             for i, seed in enumerate(settings.seeds)}
    aux = {name: DepthRenderSpec(config.scene, config.viewer, "all_in_focus", content, settings.aux_spp,
                                 settings.aux_seed, settings.oversample)
           for name, content in (("all_in_focus", "radiance"), ("proximity", "proximity"))}
    return {**truth, **aux}


# -- loading ---------------------------------------------------------------------------
_err = field_error
_read_toml = read_campaign_toml

#: [depth_campaign] numbers: (unit, lowest, highest).
NUMBER_SETTINGS = {
    "wavelength_nm": ("nm", 200.0, 2000.0),
    "data_range": ("(linear reflectance)", 1e-3, 1e3),
    "margin_px": ("px", 0.0, 1000.0),
    "layer_spacing_fraction": ("(of a blur-free depth step)", 1e-3, 1.0),
}
#: [depth_campaign] whole numbers: (unit, lowest, highest).
WHOLE_SETTINGS = {
    "spp": ("samples per pixel", 1, MAX_SPP),
    "aux_spp": ("samples per pixel", 1, MAX_SPP),
    "aux_seed": ("(a seed)", 0, MAX_SEED),
    "oversample": ("(sub-pixels per pixel per axis)", 1, 16),
}


def is_depth_campaign(doc: dict) -> bool:
    """A ``[depth_campaign]`` table, or ``[campaign]`` with ``kind = "depth"``."""
    head = doc.get("campaign", {})
    return "depth_campaign" in doc or (isinstance(head, dict) and head.get("kind") == "depth")


def _settings(head: dict, source: str) -> DepthCampaignSettings:
    known = {f.name for f in dataclasses.fields(DepthCampaignSettings)}
    unknown = set(head) - known - {"name", "description", "kind"}
    if unknown:
        raise _err(source, "[depth_campaign]", f"unknown setting(s) {sorted(unknown)}; known: {sorted(known)}")
    kwargs: dict[str, Any] = {}
    for key, (unit, lo, hi) in NUMBER_SETTINGS.items():
        if key in head:
            kwargs[key] = number(head[key], source, f"depth_campaign.{key}", unit, lo=lo, hi=hi)
    for key, (unit, lo, hi) in WHOLE_SETTINGS.items():
        if key in head:
            kwargs[key] = whole_number(head[key], source, f"depth_campaign.{key}", unit, lo=lo, hi=hi)
    if "seeds" in head:
        kwargs["seeds"] = seed_pair(head["seeds"], source, "depth_campaign.seeds")
    if "simulations" in head:
        kwargs["simulations"] = choices(head["simulations"], DEPTH_SIMULATIONS, source, "depth_campaign.simulations")
    for key in ("name", "description"):
        if key in head:
            text(head[key], source, f"depth_campaign.{key}")
    return DepthCampaignSettings(**kwargs)


#: Camera fields: (unit, lowest, highest).
CAMERA_FIELDS = {
    "f_number": ("(f-number)", 0.5, 128.0),
    "focus_distance_m": ("m", 0.01, 1000.0),
    "focal_length_mm": ("mm", 1.0, 1000.0),
    "vertex_distance_mm": ("mm", 0.0, 200.0),
}


def _eye(raw: dict, viewer, source: str, where: str) -> EyeViewer:
    base_eye = viewer if isinstance(viewer, EyeViewer) else EyeViewer()
    rx = base_eye.prescription
    if "eye" in raw:
        try:
            rx = Prescription.parse(text(raw["eye"], source, f"{where}.eye"))
        except VissimInputError as exc:
            raise _err(source, f"{where}.eye", str(exc)) from None
    pupil = number(raw.get("pupil_mm", base_eye.pupil_diameter_mm), source, f"{where}.pupil_mm", "mm", lo=0.5, hi=10.0)
    accommodation = number(raw.get("accommodation_d", base_eye.accommodation_d), source, f"{where}.accommodation_d",
                           "dioptres", lo=0.0, hi=20.0)
    try:
        return EyeViewer(rx, pupil, accommodation)
    except VissimInputError as exc:
        raise _err(source, where, str(exc)) from None


def _camera(camera: Any, viewer, source: str, where: str) -> CameraViewer:
    allowed = set(CAMERA_FIELDS) | {"lenses"}
    if not isinstance(camera, dict) or set(camera) - allowed:
        raise _err(source, where, f"a table of {sorted(allowed)}, got {camera!r}")
    kwargs: dict[str, Any] = {k: number(v, source, f"{where}.{k}", CAMERA_FIELDS[k][0], lo=CAMERA_FIELDS[k][1],
                                        hi=CAMERA_FIELDS[k][2]) for k, v in camera.items() if k != "lenses"}
    specs = lenses(camera.get("lenses", []), source, f"{where}.lenses")
    kwargs["lenses"] = tuple(TrialLens(s.sphere_diopters, s.cylinder_diopters, s.axis_deg) for s in specs)
    try:
        return dataclasses.replace(viewer if isinstance(viewer, CameraViewer) else CameraViewer(), **kwargs)
    except VissimInputError as exc:
        raise _err(source, where, str(exc)) from None


def _configuration(raw: dict, base: Path, source: str, where: str) -> DepthConfiguration:
    unknown = set(raw) - {"name", "scene", "eye", "pupil_mm", "accommodation_d", "camera"}
    if unknown:
        raise _err(source, where, f"unknown field(s) {sorted(unknown)}")
    if "scene" not in raw:
        raise _err(source, where, "needs scene = a depth scene file (relative to the campaign file)")
    scene_file = (base / text(raw["scene"], source, f"{where}.scene")).resolve()
    if not scene_file.is_file():
        raise _err(source, f"{where}.scene", f"{scene_file} is not a file")
    try:
        loaded = load_depth_scene_toml(scene_file)
    except VissimInputError as exc:
        raise _err(source, f"{where}.scene", str(exc)) from None
    eye_keys = {"eye", "pupil_mm", "accommodation_d"} & set(raw)
    if eye_keys and "camera" in raw:
        raise _err(source, where, "give an eye (eye, pupil_mm, accommodation_d) or a camera, not both")
    viewer = loaded.viewer
    if eye_keys:
        viewer = _eye(raw, viewer, source, where)
    elif "camera" in raw:
        viewer = _camera(raw["camera"], viewer, source, f"{where}.camera")
    name = text(raw["name"], source, f"{where}.name") if "name" in raw else ""
    return DepthConfiguration(name or f"{scene_file.stem}: {viewer.label()}", str(scene_file), loaded.scene, viewer)


def load_depth_campaign(path: str | Path, *, check_memory: bool = True) -> DepthCampaign:
    """Read and validate a depth campaign TOML file (module doc); ``check_memory`` as :func:`load_campaign`."""
    path = Path(path)
    source = str(path)
    raw = _read_toml(path)
    if not is_depth_campaign(raw):
        raise _err(source, "top level",
                   "not a depth campaign: add [depth_campaign] (or kind = \"depth\" in [campaign])")
    unknown = set(raw) - {"depth_campaign", "campaign", "config"}
    if unknown:
        raise _err(source, "top level", f"unknown table(s) {sorted(unknown)}; use [depth_campaign] and [[config]]")
    key = "depth_campaign" if "depth_campaign" in raw else "campaign"
    head = table(raw[key], source, f"[{key}]")
    settings = _settings(head, source)
    configs = [_configuration(c, path.parent, source, f"config[{i}]")
               for i, c in enumerate(tables(raw, "config", source))]
    if not configs:
        raise _err(source, "top level", "no configurations: add [[config]] tables")
    campaign = DepthCampaign(head.get("name", path.stem), head.get("description", ""), settings, tuple(configs), source)
    if check_memory:
        from vissim.validation.preflight import check_depth_campaign_memory

        check_depth_campaign_memory(campaign)
    return campaign


# -- one item ---------------------------------------------------------------------------
def _diffracted(image: np.ndarray, pupil_mm: float, settings: DepthCampaignSettings,
                arcmin_per_px: float) -> np.ndarray:
    """``image`` convolved with the in-focus diffraction PSF of a ``pupil_mm`` aperture."""
    from vissim.optics.blur import blur_image
    from vissim.validation.simulate import _psf

    psf = _psf(Prescription(0.0), pupil_mm, settings.wavelength_nm, arcmin_per_px, "wave")
    return blur_image(image, psf, arcmin_per_px=arcmin_per_px, padding="edge")


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
    from vissim.validation.simulate import block_mean

    started = time.perf_counter()
    provenance = make_provenance(item=key, configuration=config.as_json(), settings=settings,
                                 render_provenance=render_provenance or {})

    def _save(item_dir: Path, name: str, pixels: np.ndarray, preview: bool = True) -> str:
        return save_item_image(item_dir, name, pixels, provenance, preview)

    scene, s = config.scene, settings.oversample
    eye = equivalent_eye(config.viewer, scene)
    truth_a, truth_b = images["truth_0"], images["truth_1"]
    proximity = block_mean(images["proximity"], s)
    geometries = panel_geometries(scene)

    def radius_px(p):
        with np.errstate(divide="ignore"):
            distance = np.where(p > 1e-9, 1.0 / np.maximum(p, 1e-9), np.inf)
        return 0.5 * blur_diameter_arcmin(config.viewer, distance, scene) / scene.arcmin_per_px

    masks = depth_regions(proximity, geometries, radius_px, pupil_diameter_mm=eye.pupil_diameter_mm,
                          arcmin_per_px=scene.arcmin_per_px, margin_px=settings.margin_px)
    saved = {"truth": _save(item_dir, "truth", truth_a), "all_in_focus": _save(item_dir, "all_in_focus",
                                                                                block_mean(images["all_in_focus"], s)),
             "proximity": _save(item_dir, "proximity_d", proximity, preview=False),
             "regions": _save(item_dir, "regions", masks.label_image().astype(np.float32), preview=False)}
    comparisons = []
    for mode in settings.simulations:
        result = blur_depth(images["all_in_focus"], proximity_to_depth_m(images["proximity"]),
                            eye_prescription=eye.prescription, pupil_diameter_mm=eye.pupil_diameter_mm,
                            arcmin_per_px=scene.arcmin_per_px / s, accommodation_d=eye.accommodation_d,
                            wavelength_nm=settings.wavelength_nm, mode=mode,
                            layer_spacing_fraction=settings.layer_spacing_fraction)
        simulated = block_mean(result.image, s)
        if mode == "wave":
            reference = _diffracted(truth_a, eye.pupil_diameter_mm, settings, scene.arcmin_per_px)
            other = _diffracted(truth_b, eye.pupil_diameter_mm, settings, scene.arcmin_per_px)
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
                           "accommodation_d": eye.accommodation_d},
        "panels": [{"name": g.name, "letters": scene.panels[g.index].chart.letters,
                    "logmar": scene.panels[g.index].chart.logmar,
                    "distance_left_m": g.distance_left_m, "distance_right_m": g.distance_right_m,
                    "blur_diameter_arcmin": [float(blur_diameter_arcmin(config.viewer, d, scene))
                                             for d in (g.distance_left_m, g.distance_right_m)]} for g in geometries],
        "masks": {"jump_d": masks.jump_d, "margin_px": settings.margin_px,
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


# -- running ----------------------------------------------------------------------------
def run_depth_campaign(campaign: DepthCampaign, run_dir: str | Path, *, workers: int = 1, scheduler: str | None = None,
                       spp: int | None = None, render: Callable[[DepthRenderSpec], Any] | None = None,
                       show_progress: bool = True) -> RunSummary:
    """Run (or resume) a depth campaign into ``run_dir``; renders are reused by key.

    Options and the scheduler are checked before the first file is written.
    """
    render = render or render_depth_spec
    run_dir = Path(run_dir)
    check_run_options(run_dir, workers, spp)
    if spp is not None:
        campaign = dataclasses.replace(campaign, settings=dataclasses.replace(campaign.settings, spp=spp))
    keys = [campaign.item_key(c) for c in campaign.configurations]
    todo = [(k, c) for k, c in zip(keys, campaign.configurations)
            if not (run_dir / "items" / k / "result.json").exists()]
    needed = {spec.key: spec for _, c in todo for spec in _specs(c, campaign.settings).values()}
    pending = [s for s in needed.values() if not (run_dir / "renders" / f"{s.key}.exr").exists()]
    client = connect_scheduler(scheduler) if scheduler and pending else None
    try:
        write_json_atomic(run_dir / "campaign.json", {
            "kind": "depth", "name": campaign.name, "description": campaign.description, "source": campaign.source,
            "settings": json_safe(campaign.settings), "items": keys,
            "configurations": [c.as_json() for c in campaign.configurations],
            "provenance": make_provenance(campaign=campaign.source)}, overwrite=True)
        log.info("%d of %d depth items to do; %d renders to make, %d reused", len(todo), len(keys), len(pending),
                 len(needed) - len(pending))
        if pending:
            _make_renders(pending, run_dir, workers, client, render, show_progress)
    finally:
        if client is not None:
            client.close()
    for key, config in todo:
        renders = {name: read_image(run_dir / "renders" / f"{spec.key}.exr")
                   for name, spec in _specs(config, campaign.settings).items()}
        compute_depth_item(key, config, campaign.settings, {name: r.pixels for name, r in renders.items()},
                           run_dir / "items" / key,
                           render_provenance={name: r.provenance for name, r in renders.items()})
    return RunSummary(run_dir, len(keys), len(keys) - len(todo), len(pending), len(needed) - len(pending))


@dataclass(frozen=True)
class CampaignRun:
    """What :func:`run_any_campaign` did: the kind, the run summary, the report files and summary lines."""

    kind: str  # "depth" or "single-plane"
    summary: RunSummary
    report_files: tuple[Path, ...]
    lines: tuple[str, ...]

    def text(self) -> str:
        return "\n".join(self.lines)


def run_any_campaign(path: str | Path, out: str | Path, *, workers: int = 1, scheduler: str | None = None,
                     spp: int | None = None, show_progress: bool = True) -> CampaignRun:
    """Run the campaign file at ``path`` into ``out`` -- a depth campaign or a single-plane one -- and report it."""
    path, out = Path(path), Path(out)
    if is_depth_campaign(_read_toml(path)):
        from vissim.validation.depth_report import (
            build_depth_report,
            depth_summary_lines,
        )

        campaign = load_depth_campaign(path)
        summary = run_depth_campaign(campaign, out, workers=workers, scheduler=scheduler, spp=spp,
                                     show_progress=show_progress)
        written = build_depth_report(out)
        lines = depth_summary_lines(out)
        kind = "depth"
    else:
        from vissim.validation.campaign import load_campaign
        from vissim.validation.report import build_report
        from vissim.validation.runner import run_campaign

        summary = run_campaign(load_campaign(path), out, workers=workers, scheduler=scheduler, spp=spp,
                               show_progress=show_progress)
        written = build_report(out)
        lines = _single_plane_lines(out)
        kind = "single-plane"
    head = (f"{summary.items_total} items ({summary.items_reused} reused), {summary.renders_made} renders made, "
            f"{summary.renders_reused} reused")
    report = out / ("report.html" if (out / "report.html").exists() else "tables.md")
    return CampaignRun(kind, summary, tuple(written), (head, *lines, f"report: {report} ({len(written)} files)"))


def rebuild_any_report(run_dir: str | Path) -> tuple[list[Path], list[str]]:
    """Rebuild the report of a run folder of either kind (``vissim report``): (files written, summary lines)."""
    run_dir = Path(run_dir)
    order = run_dir / "campaign.json"
    if not order.exists():
        raise VissimInputError(f"{run_dir} is not a vissim run folder (no campaign.json)")
    if json.loads(order.read_text()).get("kind") == "depth":
        from vissim.validation.depth_report import (
            build_depth_report,
            depth_summary_lines,
        )

        return build_depth_report(run_dir), depth_summary_lines(run_dir)
    from vissim.validation.report import build_report

    return build_report(run_dir), _single_plane_lines(run_dir)


def _single_plane_lines(run_dir: Path) -> list[str]:
    """The terminal summary of a single-plane run: one line per comparison."""
    from vissim.validation.report import load_results, metrics_rows

    lines = [f"{'configuration':44s} {'simulation':>16s} {'input':>9s} {'SSIM':>7s} {'PSNR dB':>8s} {'floor dB':>8s}"]
    for r in metrics_rows(load_results(run_dir)):
        lines.append(f"{r['configuration'][:44]:44s} {r['simulation']:>16s} {r['input']:>9s} {r['ssim']:7.4f} "
                     f"{r['psnr_db']:8.2f} {r['noise_floor_psnr_db']:8.2f}")
    return lines
