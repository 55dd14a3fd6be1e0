"""The keys that name an item's and a render's files by their inputs: equal inputs, equal key.

One schema version for every bench kind; it is bumped when the meaning of an item's or a
render's inputs or results changes, so that old ones are not reused (3: the DSLR geometric
self-check's row, synthetic inputs aligned on the fine grid and the prescription fit of each
capture; the depth pass holding each pixel's nearest surface).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from vissim.optics.psf.compute import SIMULATOR_REVISION
from vissim.provenance import json_safe

__all__ = ["SCHEMA_VERSION", "item_key", "render_key", "render_path", "item_dir"]

SCHEMA_VERSION = 3
KEY_HEX_DIGITS = 16


def _digest(payload: dict) -> str:
    text = json.dumps(json_safe(payload), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_HEX_DIGITS]


def item_key(settings, inputs: dict) -> str:
    """An item's key: the schema, the simulator's revision, the campaign settings and the item's ``inputs``.

    ``inputs`` is what the bench kind says its configuration's results depend on (never its name).
    """
    return _digest({"schema": SCHEMA_VERSION, "simulator": SIMULATOR_REVISION, "settings": settings, **inputs})


def render_key(kind: str, spec) -> str:
    """A render's key: the schema, the bench kind and everything the render spec holds (``spec.as_json()``)."""
    return f"{kind}-{_digest({'schema': SCHEMA_VERSION, 'kind': kind, **spec.as_json()})}"


def render_path(run_dir: Path, key: str) -> Path:
    return Path(run_dir) / "renders" / f"{key}.exr"


def item_dir(run_dir: Path, key: str) -> Path:
    return Path(run_dir) / "items" / key
