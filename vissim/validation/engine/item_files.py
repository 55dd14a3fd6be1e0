"""An item's files: each image as EXR (with provenance in its header) and a PNG preview."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vissim.imageio import write_image

__all__ = ["save_item_image"]


def save_item_image(item_dir: Path, name: str, pixels: np.ndarray, provenance: dict, preview: bool = True) -> str:
    """``name``.exr (provenance in its header) and, with ``preview``, ``name``.png (provenance sidecar)."""
    record = {**provenance, "image": name}
    write_image(item_dir / f"{name}.exr", np.asarray(pixels, np.float32), provenance=record, overwrite=True)
    if preview:
        write_image(item_dir / f"{name}.png", np.clip(np.asarray(pixels, np.float32), 0, 1), provenance=record,
                    overwrite=True)
    return f"items/{item_dir.name}/{name}.exr"
