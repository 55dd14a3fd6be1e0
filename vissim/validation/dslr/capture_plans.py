"""Items whose truth is a real capture: the captures each uses, checked and read before anything is written."""

from __future__ import annotations

from vissim.validation.dslr.captures import capture_problem, capture_provenance, capture_tile, load_manifest, read_capture
from vissim.validation.engine.protocol import ItemPlan

__all__ = ["capture_item_plans"]


def _capture_plan(campaign, config, captures: dict) -> tuple | str:
    """The captures (truth, repeat | None, no-lens) an item uses, or why it is skipped.

    Each capture's own file (presence, sha256) is checked before what it refers to, so a
    corrupt capture is reported as such, not as a missing reference.
    """
    if campaign.manifest is None:
        return f"{config.name}: capture {config.capture!r} but the campaign names no manifest"

    def checked(capture_id: str):  # the capture, or why the item is skipped
        if capture_id not in captures:
            return f"{config.name}: capture {capture_id!r} is not in {campaign.manifest}"
        problem = capture_problem(captures[capture_id])
        return f"{config.name}: skipped, {problem}" if problem else captures[capture_id]

    capture = checked(config.capture)
    if isinstance(capture, str):
        return capture
    if capture.no_lens_capture is None:
        return f"{config.name}: capture {capture.id!r} names no no_lens_capture (the simulation input)"
    references = (capture.repeat_capture, capture.no_lens_capture)
    plan = [capture, *(None if c is None else checked(c) for c in references)]
    return next((p for p in plan if isinstance(p, str)), tuple(plan))


def _capture_inputs(campaign, plan: tuple):
    """(truth_a, truth_b | None, no_lens) tiles of a capture plan, and their provenance."""
    settings = campaign.settings
    raws = [None if c is None else read_capture(c) for c in plan]
    tiles = [None if c is None else capture_tile(c, settings.arcmin_per_px, settings.tile_px, raw=r)
             for c, r in zip(plan, raws)]
    provenance = {name: None if c is None else capture_provenance(c, r)
                  for name, c, r in zip(("truth_a", "truth_b", "no_lens"), plan, raws)}
    return (*tiles, provenance)


def capture_item_plans(campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
    """The `ItemPlan` of each captured item to do (its tiles read now, so an unreadable capture stops the run
    before it writes), and a message per item skipped (an absent or corrupt capture)."""
    if not todo:
        return {}, []
    captures = load_manifest(campaign.manifest) if campaign.manifest else {}
    plans, skipped = {}, []
    for key, index in todo:
        config = campaign.configurations[index]
        plan = _capture_plan(campaign, config, captures)
        if isinstance(plan, str):
            skipped.append(plan)
            continue
        truth_a, truth_b, no_lens, provenance = _capture_inputs(campaign, plan)
        given = {"truth_a": truth_a, "no_lens": no_lens}
        if truth_b is not None:
            given["truth_b"] = truth_b
        plans[key] = ItemPlan(given=given, given_provenance=provenance,
                              source={"ground_truth": "capture", "capture": config.capture})
    return plans, skipped
