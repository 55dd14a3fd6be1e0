"""The optics package is laid out by stage: no two modules share a basename, and its root is nearly empty.

Read from the tree with pathlib (nothing is imported). A shared basename (two ``wavefront.py``) makes a
short reference (`wavefront.trace_eye_wavefront`) ambiguous; new modules go into a stage's sub-package.
"""

from collections import defaultdict
from pathlib import Path

OPTICS = Path(__file__).resolve().parents[1] / "vissim" / "optics"
#: How many modules (besides ``__init__.py``) the optics root may hold.
ROOT_LIMIT = 4


def test_no_two_optics_modules_share_a_basename():
    found = defaultdict(list)
    for path in sorted(OPTICS.rglob("*.py")):
        if path.name != "__init__.py":
            found[path.name].append(path.relative_to(OPTICS).as_posix())
    shared = {name: paths for name, paths in found.items() if len(paths) > 1}
    assert not shared, f"modules sharing a basename under vissim/optics: {shared}"


def test_the_optics_root_holds_few_modules():
    root = sorted(p.name for p in OPTICS.glob("*.py") if p.name != "__init__.py")
    assert len(root) <= ROOT_LIMIT, f"vissim/optics/ holds {len(root)} modules; move them into a stage: {root}"


def test_every_optics_subpackage_is_a_package():
    for folder in sorted(p for p in OPTICS.rglob("*") if p.is_dir() and p.name != "__pycache__"):
        if any(folder.glob("*.py")):
            assert (folder / "__init__.py").is_file(), f"{folder.relative_to(OPTICS)} has no __init__.py"
