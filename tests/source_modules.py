"""vissim's modules as read from its source (nothing imported), for the import-graph and layer tests."""

from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "vissim"


def source_modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module under ``vissim/`` (a package by its ``__init__``)."""
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


MODULES = source_modules()


def owner(name: str) -> str:
    """The vissim module a dotted name lives in ('' when none)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def loops(graph: dict[str, set[str]]) -> list[str]:
    """Every cycle a depth-first walk of ``graph`` meets, as 'a -> b -> a'."""
    found, state = [], {}  # state: 1 on the path, 2 done

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append(" -> ".join(path[path.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for start in sorted(graph):
        if start not in state:
            visit(start, [start])
    return found
