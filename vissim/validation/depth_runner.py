"""Running a depth campaign: its render specs, the renders, then every item.

Run folder: as `vissim.validation.runner` (``campaign.json``, ``renders/<key>.exr`` keyed
by their inputs, ``items/<key>/result.json`` written last), so re-runs resume.  Each item needs
renders (`DepthRenderSpec`): the blurred view at both seeds, the all-in-focus view and
the proximity (depth) pass (the RGB-D input: each pixel's nearest surface,
``DEPTH_PASS_STATISTIC``), and for the layered input each panel alone: its radiance and
coverage (and, for a tilted chart, its proximity pass).  The pinhole renders extend
``margin_px`` beyond the frame on every side (the settings' ``frame_margin``);
`vissim.validation.depth_item` computes the item.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from vissim.bench.depth.scene import DepthScene
from vissim.bench.depth.scene_dict import DEPTH_PASS_CONTENT, DEPTH_PASS_STATISTIC
from vissim.bench.depth.viewers import CameraViewer, EyeViewer
from vissim.imageio import read_image
from vissim.progress import Progress, counter
from vissim.provenance import json_safe
from vissim.validation.depth_campaign import (SCHEMA_VERSION, DepthCampaign, DepthCampaignSettings,
                                              DepthConfiguration)
from vissim.validation.depth_item import compute_depth_item
from vissim.validation.runner import RunSummary, make_missing_renders, plan_run, progress_of

__all__ = ["DepthRenderSpec", "render_depth_spec", "render_specs", "run_depth_campaign"]

log = logging.getLogger(__name__)


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
    margin_px: int = 0  # pixels (campaign grid) beyond the frame on every side
    panels: tuple[int, ...] | None = None  # only these panels (a layer); None: the whole scene
    statistic: str = "mean"  # a pixel from its samples (render.run.PIXEL_STATISTICS)

    @property
    def key(self) -> str:
        text = json.dumps({"schema": SCHEMA_VERSION, **self.as_json()}, sort_keys=True)
        return "depth-" + hashlib.sha256(text.encode()).hexdigest()[:16]

    def as_json(self) -> dict:
        return json_safe(self)

    def render_scene(self) -> DepthScene:
        scene, s = self.scene.with_margin(self.margin_px), self.oversample
        if s == 1:
            return scene
        rows, cols = scene.size_px
        return dataclasses.replace(scene, arcmin_per_px=scene.arcmin_per_px / s, size_px=(rows * s, cols * s))


def render_depth_spec(spec: DepthRenderSpec):
    """Render one spec with Mitsuba on this machine (a worker process or a Dask worker).

    Returns the `vissim.render.run.RenderResult`: pixels, variant and the spp used.
    """
    from vissim.render.depth_render import (
        render_view,  # the Mitsuba door, imported where it runs
    )

    return render_view(spec.render_scene(), spec.viewer, view=spec.view, content=spec.content, spp=spec.spp,
                       seed=spec.seed, panels=spec.panels, statistic=spec.statistic)


def render_specs(config: DepthConfiguration, settings: DepthCampaignSettings) -> dict[str, DepthRenderSpec]:
    """The renders of one configuration by name: ``truth_<i>``, ``all_in_focus``, ``proximity`` and
    per panel ``layer_<i>``, ``coverage_<i>`` (and ``layer_proximity_<i>`` for a tilted chart)."""
    truth = {f"truth_{i}": DepthRenderSpec(config.scene, config.viewer, "blurred", "radiance", settings.spp, seed)
             for i, seed in enumerate(settings.seeds)}
    margin = config.frame_margin_px(settings)

    def pinhole(content, seed, panels=None, statistic="mean"):
        return DepthRenderSpec(config.scene, config.viewer, "all_in_focus", content, settings.aux_spp, seed,
                               settings.oversample, margin, panels, statistic)

    aux = {"all_in_focus": pinhole("radiance", settings.aux_seed),  # the RGB-D input; the masks need its depth
           "proximity": pinhole(DEPTH_PASS_CONTENT, settings.aux_seed, statistic=DEPTH_PASS_STATISTIC)}
    if "layered" in settings.inputs:
        for i, panel in enumerate(config.scene.panels):
            aux[f"layer_{i}"] = pinhole("radiance", settings.aux_seed, (i,))
            aux[f"coverage_{i}"] = pinhole("coverage", settings.aux_seed, (i,))
            if not hasattr(panel, "distance_m"):  # a tilted chart: its proximity varies across it
                aux[f"layer_proximity_{i}"] = pinhole("proximity", settings.aux_seed, (i,))
    return {**truth, **aux}


def run_depth_campaign(campaign: DepthCampaign, run_dir: str | Path, *, workers: int = 1, scheduler: str | None = None,
                       spp: int | None = None, render: Callable[[DepthRenderSpec], Any] | None = None,
                       show_progress: bool = True, progress: Progress | None = None) -> RunSummary:
    """Run (or resume) a depth campaign into ``run_dir``; renders are reused by key.

    Options and the scheduler are checked before the first file is written.  ``progress`` and
    ``show_progress`` as `vissim.validation.runner.run_campaign`'s.
    """
    render = render or render_depth_spec
    run_dir = Path(run_dir)
    campaign, keys, todo = plan_run(campaign, run_dir, workers, spp)
    needed = {spec.key: spec for _, c in todo for spec in render_specs(c, campaign.settings).values()}
    record = {"kind": "depth", "name": campaign.name, "description": campaign.description, "source": campaign.source,
              "settings": json_safe(campaign.settings), "items": keys,
              "configurations": [c.as_json() for c in campaign.configurations]}
    with progress_of(show_progress, progress) as report:
        made = make_missing_renders(run_dir, needed, record, workers=workers, scheduler=scheduler, render=render,
                                    progress=report, items=f"{len(todo)} of {len(keys)} depth items")
        advance = counter(report, "items", len(todo))
        for key, config in todo:
            renders = {name: read_image(run_dir / "renders" / f"{spec.key}.exr")
                       for name, spec in render_specs(config, campaign.settings).items()}
            compute_depth_item(key, config, campaign.settings, {name: r.pixels for name, r in renders.items()},
                               run_dir / "items" / key,
                               render_provenance={name: r.provenance for name, r in renders.items()})
            advance()
    return RunSummary(run_dir, len(keys), len(keys) - len(todo), made, len(needed) - made)
