"""Walk a run folder: every image a campaign wrote carries provenance (EXR header, PNG sidecar)."""

import json
from pathlib import Path

from vissim.imageio import read_image


def image_provenance(run_dir: Path) -> dict[Path, dict]:
    """Each EXR's and PNG's provenance; fails on an image without one."""
    found = {}
    for path in sorted(run_dir.rglob("*")):
        if path.suffix == ".exr":
            provenance = read_image(path).provenance
        elif path.suffix == ".png":
            sidecar = path.with_name(path.name + ".json")
            assert sidecar.is_file(), f"{path} has no provenance sidecar"
            provenance = json.loads(sidecar.read_text())
        else:
            continue
        assert provenance.get("vissim_version") and provenance.get("inputs"), f"{path}: {provenance}"
        found[path] = provenance
    assert found, f"no images under {run_dir}"
    return found


def json_without_provenance(run_dir: Path) -> list[Path]:
    """Result and report JSON files (not sidecars) that lack a ``provenance`` key."""
    files = [run_dir / "campaign.json", run_dir / "metrics.json", *run_dir.glob("items/*/result.json")]
    return [p for p in files if "provenance" not in json.loads(p.read_text())]
