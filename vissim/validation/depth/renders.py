"""A depth configuration built once, and the renders its item needs.

Each item needs renders (`DepthRenderSpec`): the blurred view at both seeds, the all-in-focus view
and the proximity (depth) pass (the RGB-D input: each pixel's nearest surface,
``DEPTH_PASS_STATISTIC``), and for the layered input each panel alone: its radiance and
coverage (and, for a tilted chart, its proximity pass).  The pinhole renders extend
``margin_px`` beyond the frame on every side (the settings' ``frame_margin``);
`vissim.validation.depth.item` computes the item.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

from vissim.bench.depth.scene import DepthScene
from vissim.bench.depth.scene_dict import DEPTH_PASS_CONTENT, DEPTH_PASS_STATISTIC
from vissim.bench.depth.viewers import CameraViewer, EyeViewer, equivalent_eye, viewing_setup
from vissim.optics.rx.viewing_setup import DepthViewer, ViewingSetup
from vissim.provenance import json_safe
from vissim.validation.depth.schema import DepthCampaignSettings, DepthConfiguration

__all__ = ["DepthBuilt", "DepthRenderSpec", "build_depth", "render_depth_spec", "render_specs"]


@dataclass(frozen=True)
class DepthRenderSpec:
    """Everything one render depends on (its key: `vissim.validation.engine.keys.render_key`)."""

    kind: ClassVar[str] = "depth"
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


@dataclass(frozen=True)
class DepthBuilt:
    """A configuration built once: the observer's equivalent eye (as a viewer, and as the `DepthViewer` the
    simulations blur with), its viewing setup and the frame margin."""

    configuration: DepthConfiguration
    eye: EyeViewer
    blur_eye: DepthViewer
    setup: ViewingSetup
    margin_px: int


def build_depth(config: DepthConfiguration, settings: DepthCampaignSettings) -> DepthBuilt:
    """What ``config``'s observer sees of its scene: equivalent eye and `ViewingSetup`, built once."""
    eye = equivalent_eye(config.viewer, config.scene)
    return DepthBuilt(config, eye, DepthViewer(eye.prescription, eye.pupil_diameter_mm, eye.accommodation_diopters),
                      viewing_setup(config.viewer, config.scene), config.frame_margin_px(settings))


def render_specs(built: DepthBuilt, settings: DepthCampaignSettings) -> dict[str, DepthRenderSpec]:
    """The renders of one configuration by name: ``truth_<i>``, ``all_in_focus``, ``proximity`` and
    per panel ``layer_<i>``, ``coverage_<i>`` (and ``layer_proximity_<i>`` for a tilted chart)."""
    config = built.configuration
    truth = {f"truth_{i}": DepthRenderSpec(config.scene, config.viewer, "blurred", "radiance", settings.spp, seed)
             for i, seed in enumerate(settings.seeds)}

    def pinhole(content, seed, panels=None, statistic="mean"):
        return DepthRenderSpec(config.scene, config.viewer, "all_in_focus", content, settings.aux_spp, seed,
                               settings.oversample, built.margin_px, panels, statistic)

    aux = {"all_in_focus": pinhole("radiance", settings.aux_seed),  # the RGB-D input; the masks need its depth
           "proximity": pinhole(DEPTH_PASS_CONTENT, settings.aux_seed, statistic=DEPTH_PASS_STATISTIC)}
    if "layered" in settings.inputs:
        for i, panel in enumerate(config.scene.panels):
            aux[f"layer_{i}"] = pinhole("radiance", settings.aux_seed, (i,))
            aux[f"coverage_{i}"] = pinhole("coverage", settings.aux_seed, (i,))
            if not hasattr(panel, "distance_m"):  # a tilted chart: its proximity varies across it
                aux[f"layer_proximity_{i}"] = pinhole("proximity", settings.aux_seed, (i,))
    return {**truth, **aux}

