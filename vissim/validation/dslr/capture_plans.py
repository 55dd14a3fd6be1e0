"""Items whose truth is a real capture: the captures each uses, checked and read before anything is written.

Each capture file is checked (presence, sha256) and decoded to its tile once per run, however
many configurations use it; every item gets its own copy of the tile.
"""

from __future__ import annotations

import copy

import numpy as np

from vissim.validation.dslr.captures import Capture, capture_provenance, capture_tile, load_manifest, open_capture
from vissim.validation.engine.protocol import ItemPlan

__all__ = ["capture_item_plans"]


class _RunCaptures:
    """A run's manifest: each capture checked and decoded at most once, its tile and provenance kept."""

    def __init__(self, campaign):
        self.settings = campaign.settings
        self.captures: dict[str, Capture] = load_manifest(campaign.manifest) if campaign.manifest else {}
        self._opened: dict[str, object] = {}  # capture id -> its RawImage until tiled (then None), or why not usable
        self._tiles: dict[str, tuple[np.ndarray, dict]] = {}

    def _open(self, capture_id: str):
        if capture_id not in self._opened:
            self._opened[capture_id] = open_capture(self.captures[capture_id])
        return self._opened[capture_id]

    def problem(self, capture_id: str) -> str | None:
        """Why the capture cannot be used (`open_capture`: absent file, wrong checksum), or None."""
        opened = self._open(capture_id)
        return opened if isinstance(opened, str) else None

    def tile(self, capture: Capture) -> tuple[np.ndarray, dict]:
        """The capture's tile on the campaign's grid (a copy of its own) and its provenance."""
        if capture.id not in self._tiles:
            raw = self._open(capture.id)
            tile = capture_tile(capture, self.settings.arcmin_per_px, self.settings.tile_px, raw=raw)
            self._tiles[capture.id] = tile, capture_provenance(capture, raw)
            self._opened[capture.id] = None  # usable; its full-sensor decode is not kept for the rest of the run
        tile, provenance = self._tiles[capture.id]
        return tile.copy(), copy.deepcopy(provenance)


def _capture_plan(campaign, config, captures: _RunCaptures) -> tuple | str:
    """The captures (truth, repeat | None, no-lens) an item uses, or why it is skipped.

    Each capture's own file (presence, sha256) is checked before what it refers to, so a
    corrupt capture is reported as such, not as a missing reference.
    """
    if campaign.manifest is None:
        return f"{config.name}: capture {config.capture!r} but the campaign names no manifest"

    def checked(capture_id: str):  # the capture, or why the item is skipped
        if capture_id not in captures.captures:
            return f"{config.name}: capture {capture_id!r} is not in {campaign.manifest}"
        problem = captures.problem(capture_id)
        return f"{config.name}: skipped, {problem}" if problem else captures.captures[capture_id]

    capture = checked(config.capture)
    if isinstance(capture, str):
        return capture
    if capture.no_lens_capture is None:
        return f"{config.name}: capture {capture.id!r} names no no_lens_capture (the simulation input)"
    references = (capture.repeat_capture, capture.no_lens_capture)
    plan = [capture, *(None if c is None else checked(c) for c in references)]
    return next((p for p in plan if isinstance(p, str)), tuple(plan))


def _capture_inputs(plan: tuple, captures: _RunCaptures):
    """(truth_a, truth_b | None, no_lens) tiles of a capture plan, and their provenance."""
    read = [None if c is None else captures.tile(c) for c in plan]
    tiles = [None if r is None else r[0] for r in read]
    provenance = {name: None if r is None else r[1] for name, r in zip(("truth_a", "truth_b", "no_lens"), read)}
    return (*tiles, provenance)


def capture_item_plans(campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
    """The `ItemPlan` of each captured item to do (its tiles read now, so an unreadable capture stops the run
    before it writes), and a message per item skipped (an absent or corrupt capture)."""
    if not todo:
        return {}, []
    captures = _RunCaptures(campaign)
    plans, skipped = {}, []
    for key, index in todo:
        config = campaign.configurations[index]
        plan = _capture_plan(campaign, config, captures)
        if isinstance(plan, str):
            skipped.append(plan)
            continue
        truth_a, truth_b, no_lens, provenance = _capture_inputs(plan, captures)
        given = {"truth_a": truth_a, "no_lens": no_lens}
        if truth_b is not None:
            given["truth_b"] = truth_b
        plans[key] = ItemPlan(given=given, given_provenance=provenance,
                              source={"ground_truth": "capture", "capture": config.capture})
    return plans, skipped
