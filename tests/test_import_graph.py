"""The package's import graph: no loops, and each heavy dependency behind one door.

Built from the source (every ``import``, module level or inside a function), so a loop that
only closes at run time is caught too.
"""

import ast
from pathlib import Path

from source_modules import MODULES, loops, owner


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _graph() -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        targets = {owner(n) for n in _imports(path) if n.split(".")[0] == "vissim"}
        # a package's __init__ is not a dependency of its own modules' imports of siblings
        graph[name] = {t for t in targets if t and t != name and t != "vissim"}
    return graph


def test_no_import_loops():
    found = loops(_graph())
    assert not found, "import loops: " + "; ".join(found)


def test_heavy_dependencies_stay_behind_their_doors():
    doors = {"mitsuba": "vissim.render", "drjit": "vissim.render", "rawpy": "vissim.imaging.raw",
             "OpenEXR": "vissim.imageio", "cupy": "vissim.optics.runtime.array_backend"}
    for name, path in MODULES.items():
        for imported in _imports(path):
            door = doors.get(imported.split(".")[0])
            assert door is None or name == door or name.startswith(door + "."), f"{name} imports {imported}"


def test_the_physics_core_imports_neither_bench_nor_render():
    for name, targets in _graph().items():
        if name.startswith("vissim.optics"):
            assert not {t for t in targets if t.startswith(("vissim.bench", "vissim.render", "vissim.validation"))}, name
