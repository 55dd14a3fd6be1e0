"""How the DSLR report names things: a figure column's title, the camera's resulting Rx, the trial lens, a group."""

from __future__ import annotations

import math

from vissim.validation.dslr.schema import lens_label_of, trial_lens_phrase

__all__ = ["arcmin_per_px_of", "column_title", "camera_rx", "group_of"]


def arcmin_per_px_of(result: dict, campaign: dict | None = None) -> float | None:
    """The campaign's sampling (arcmin per pixel) an item's images are at, or None if not recorded."""
    settings = (campaign or {}).get("settings") or (result.get("provenance") or {}).get("inputs", {}).get("settings")
    value = (settings or {}).get("arcmin_per_px")
    return float(value) if value is not None and math.isfinite(float(value)) else None


def column_title(result: dict, comparison: dict | None = None) -> str:
    """A figure column's header: the letter and its LogMAR, the trial lens, the camera's resulting Rx (`camera_rx`)."""
    config = result["configuration"]
    title = f"{config['letter']}, LogMAR {config['logmar']:.1f}\n{trial_lens_phrase(lens_label_of(result))}"
    if comparison is not None:
        title += f"\ncamera Rx {camera_rx(result, comparison)}"
    return title


def camera_rx(result: dict, comparison: dict | None = None) -> str:
    """The camera's resulting prescription behind the trial lenses: the bench's (the matched wave or geometric
    simulation's), which thesis mode replaces with its own; that comparison's if neither ran."""
    matched = next((c for c in result["comparisons"] if c["simulation"] in ("wave", "geometric")), comparison)
    return matched["setup"]["camera_prescription"] if matched else "—"


def group_of(configuration: dict) -> str:
    """A configuration's group (its ``group`` field: its sweep's name, or the item itself); else its name."""
    return configuration.get("group") or configuration["name"]
