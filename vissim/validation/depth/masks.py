"""Where to compare a depth render with its simulation: panel interiors, occlusion bands, the frame.

From a rendered proximity map (dioptres, 0 = sky; `vissim.render.depth_render`) and the
observer's blur (`vissim.optics.rx.viewing_setup.ViewingSetup.blur_diameter_at_arcmin`), every pixel gets one
class:

* a **depth discontinuity** is a pixel whose 3 x 3 neighbourhood spans more than
  ``jump_diopters`` dioptres of proximity.  The default ``jump_diopters`` is the proximity step over which
  two blur discs differ by one pixel (``theta / pupil``): the occlusion threshold of
  `vissim.optics.depth.depth_map.blur_depth` (``occlusion_threshold_px = 1``).  A tilted chart's gradual
  depth stays below it; a panel edge (or a panel against the sky) does not.  A pixel split
  between two depths carries the whole jump in its window, so mixed pixels are caught;
* the **boundary band** is every pixel within ``r + margin_px`` of a discontinuity, where
  ``r`` is the largest geometric blur radius (px) in that discontinuity's 5 x 5 neighbourhood:
  there the render mixes light from both sides (and from behind the occluder's edge);
* the **frame** is every pixel within the scene's largest blur radius + ``margin_px`` of the
  image border (the render sees beyond the border; a simulation only pads);
* **interiors**: the rest, split into connected regions, each named after the panel whose
  proximity range holds the region's median (``sky`` below 1e-6 D).  A fronto panel takes a
  region whose proximities spread less than ``jump_diopters``; otherwise a tilted chart does.

So an interior pixel is at least one blur radius (plus the margin) from any depth
discontinuity: its render is the single-depth blur of its own panel.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.units import arcmin_to_rad, mm_to_m

ndimage = lazy_module("scipy.ndimage")

__all__ = ["RegionMasks", "depth_regions", "SKY"]

log = logging.getLogger(__name__)

SKY = "sky"
_SKY_PROXIMITY_D = 1e-6


@dataclass(frozen=True, eq=False)
class RegionMasks:
    """Boolean masks (H, W) of one image: ``interiors`` by region name, ``boundary``, ``frame``."""

    interiors: dict[str, np.ndarray]
    boundary: np.ndarray
    frame: np.ndarray
    discontinuities: np.ndarray
    blur_radius_px: np.ndarray
    jump_diopters: float

    def label_image(self) -> np.ndarray:
        """int8 map for figures: 0 frame/unused, 1 boundary, 2... interiors in ``interiors`` order."""
        out = np.zeros(self.boundary.shape, np.int8)
        out[self.boundary] = 1
        for i, mask in enumerate(self.interiors.values()):
            out[mask] = 2 + i
        return out


def _disc(radius: int) -> np.ndarray:
    y, x = np.mgrid[-radius : radius + 1, -radius : radius + 1]
    return x * x + y * y <= radius * radius + 1e-9


def depth_regions(
    proximity_diopters: np.ndarray,
    geometries,
    blur_radius_px,
    *,
    pupil_diameter_mm: float,
    arcmin_per_px: float,
    jump_diopters: float | None = None,
    margin_px: float = 1.0,
) -> RegionMasks:
    """Classify the pixels of a proximity map (module doc).

    ``geometries``: the scene's `PanelGeometry` list (names
    and proximity ranges).  ``blur_radius_px``: callable mapping proximity (D, array) to the
    geometric blur radius in pixels (largest meridian).
    """
    proximity = np.asarray(proximity_diopters, dtype=np.float64)
    if proximity.ndim != 2:
        raise VissimInputError(f"a proximity map must be (H, W) dioptres, got shape {proximity.shape}")
    if jump_diopters is None:
        jump_diopters = float(arcmin_to_rad(arcmin_per_px)) / mm_to_m(pupil_diameter_mm)
    radius = np.asarray(blur_radius_px(proximity), dtype=np.float64)
    spread = ndimage.maximum_filter(proximity, size=3, mode="nearest") - ndimage.minimum_filter(
        proximity, size=3, mode="nearest")
    discontinuities = spread > jump_diopters
    band = np.zeros(proximity.shape, bool)
    if discontinuities.any():
        local = ndimage.maximum_filter(radius, size=5, mode="nearest")
        reach = np.ceil(local + margin_px).astype(int)
        for r in np.unique(reach[discontinuities]):
            seeds = discontinuities & (reach == r)
            band |= ndimage.binary_dilation(seeds, structure=_disc(int(r)))
    edge = int(math.ceil(float(radius.max()) + margin_px))
    frame = np.zeros(proximity.shape, bool)
    if edge > 0:
        frame[:edge], frame[-edge:], frame[:, :edge], frame[:, -edge:] = True, True, True, True
    boundary = band & ~frame
    free = ~(band | frame)
    components, count = ndimage.label(free)
    interiors: dict[str, np.ndarray] = {}
    for index in range(1, count + 1):
        mask = components == index
        values = proximity[mask]
        name = _region_name(float(np.median(values)), float(np.ptp(values)), geometries, jump_diopters)
        if name is None:
            log.warning("an interior region of %d px (median %.3g D) matches no panel", mask.sum(), np.median(values))
            continue
        interiors[name] = interiors[name] | mask if name in interiors else mask
    order = [g.name for g in geometries if g.name in interiors] + ([SKY] if SKY in interiors else [])
    return RegionMasks({n: interiors[n] for n in order}, boundary, frame, discontinuities, radius, float(jump_diopters))


def _region_name(median_diopters: float, spread_diopters: float, geometries, jump_diopters: float) -> str | None:
    if median_diopters < _SKY_PROXIMITY_D:
        return SKY
    tolerance = 0.5 * jump_diopters
    candidates = [g for g in geometries
                  if g.proximity_range_diopters[0] - tolerance <= median_diopters <= g.proximity_range_diopters[1] + tolerance]
    if not candidates:
        return None
    fronto = [g for g in candidates if g.kind == "panel"]
    tilted = [g for g in candidates if g.kind != "panel"]
    pool = fronto if fronto and (spread_diopters < jump_diopters or not tilted) else (tilted or fronto)
    best = min(pool, key=lambda g: abs(0.5 * sum(g.proximity_range_diopters) - median_diopters))
    return best.name
