"""The package's import graph: no loops, and each heavy dependency behind one door.

Built from the source (every ``import``, module level or inside a function), so a loop that
only closes at run time is caught too.
"""

import ast
from pathlib import Path

import vissim

PACKAGE = Path(vissim.__file__).parent


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


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
    modules = _modules()

    def owner(name):  # the vissim module a dotted name lives in
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name

    graph = {}
    for name, path in modules.items():
        targets = {owner(n) for n in _imports(path) if n.split(".")[0] == "vissim"}
        # a package's __init__ is not a dependency of its own modules' imports of siblings
        graph[name] = {t for t in targets if t and t != name and t != "vissim"}
    return graph


def test_no_import_loops():
    graph = _graph()
    state: dict[str, int] = {}  # 1 on the path, 2 done
    loops = []

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                loops.append(path[path.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for start in sorted(graph):
        if start not in state:
            visit(start, [start])
    assert not loops, "import loops: " + "; ".join(" -> ".join(loop) for loop in loops)


def test_heavy_dependencies_stay_behind_their_doors():
    doors = {"mitsuba": "vissim.render", "drjit": "vissim.render", "rawpy": "vissim.validation.raw",
             "OpenEXR": "vissim.imageio", "cupy": "vissim.optics.array_backend"}
    for name, path in _modules().items():
        for imported in _imports(path):
            door = doors.get(imported.split(".")[0])
            assert door is None or name == door or name.startswith(door + "."), f"{name} imports {imported}"


def test_the_physics_core_imports_neither_bench_nor_render():
    for name, targets in _graph().items():
        if name.startswith("vissim.optics"):
            assert not {t for t in targets if t.startswith(("vissim.bench", "vissim.render", "vissim.validation"))}, name
