"""Imports run down the layers, never to another module's private name, and packages form no loop.

Read from the source with ``ast`` (nothing is imported), every ``import`` at any depth. The
layers, lowest first (docs/conventions.md, "Layers"):

1. core: ``units``, ``errors``, ``checks``, ``atomic``, ``provenance``, ``progress``, ``thesis``, ``spectra``,
   ``lazy_import``
2. ``optics``: the physics (prescriptions, wavefronts, PSFs, blur, depth)
3. imaging: ``imageio``, ``imaging`` (image registration), ``optotypes``, ``acuity``,
   ``charts``, ``chart_defaults``, ``chart_demo``
4. ``bench``: the benches' geometry and scenes as plain data
5. ``render`` (the Mitsuba door) and ``fit`` (prescriptions fitted to captures)
6. ``validation`` (campaigns) and ``atv`` (ATV data, predictions, procedures)
7. ``cli``, ``__main__`` and the package root ``vissim`` (the lazy public API)

A module may import its own layer or any below it. Packages in one layer may import each
other, but not in a loop. The root's dunder metadata (``from vissim import __version__``) is
not an import of the API. A name or module starting with one underscore is
private to its module (a private module, such as ``cli/_common.py``, to its package).
"""

import ast
import subprocess
import sys
from pathlib import Path

from source_modules import MODULES, PACKAGE, loops, owner

from vissim.validation.engine.registry import BENCH_KINDS, bench_kind_names

LAYERS = [
    {"units", "errors", "checks", "atomic", "provenance", "progress", "thesis", "spectra", "lazy_import", "vocabulary"},
    {"optics"},
    {"imageio", "imaging", "optotypes", "acuity", "charts", "chart_defaults", "chart_demo"},
    {"bench"},
    {"render", "fit"},
    {"validation", "atv"},
    {"cli", "__main__", ""},  # "": the package root, vissim/__init__.py
]


def _package(module: str) -> str:
    """``vissim.optics.psf.compute`` -> ``optics``; the root -> ``""``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _layer(module: str) -> int:
    package = _package(module)
    found = [i for i, layer in enumerate(LAYERS) if package in layer]
    assert found, f"{module}: package {package!r} has no layer; add it to LAYERS and the docstring"
    return found[0]


def _private(part: str) -> bool:
    return part.startswith("_") and not part.startswith("__")


def _imports(path: Path) -> list[tuple[str, int]]:
    """(dotted vissim name, line) for every import and every ``module._name`` use of an imported module."""
    tree = ast.parse(path.read_text())
    found, aliases = [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append((alias.name, node.lineno))
                aliases[alias.asname or alias.name.split(".")[0]] = alias.name if alias.asname else alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "vissim" and all(a.name.startswith("__") for a in node.names):
                continue  # the root's metadata (__version__)
            for alias in node.names:
                full = f"{node.module}.{alias.name}"
                found.append((full, node.lineno))
                if full in MODULES:
                    aliases[alias.asname or alias.name] = full
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            chain, value = [node.attr], node.value
            while isinstance(value, ast.Attribute):
                chain.append(value.attr)
                value = value.value
            if isinstance(value, ast.Name) and value.id in aliases:
                found.append((".".join([aliases[value.id], *reversed(chain)]), node.lineno))
    return [(name, line) for name, line in found if name.split(".")[0] == "vissim"]


def _edges():
    """(importer, imported module, imported dotted name, line) for every import of a vissim name."""
    for module, path in sorted(MODULES.items()):
        for name, line in _imports(path):
            target = owner(name)
            if target and target != module:
                yield module, target, name, line


def test_imports_run_down_the_layers():
    upward = sorted({f"{m} (layer {_layer(m) + 1}) imports {t} (layer {_layer(t) + 1}), line {line}"
                     for m, t, _, line in _edges() if _layer(t) > _layer(m)})
    assert not upward, "imports up the layers:\n" + "\n".join(upward)


def test_no_module_imports_another_modules_private_name():
    wrong = []
    for module, target, name, line in _edges():
        parts = name.split(".")
        for i, part in enumerate(parts[1:], start=2):
            home = ".".join(parts[:i - 1])  # a private part belongs to the module or package above it
            if _private(part) and not (module == home or module.startswith(home + ".")):
                wrong.append(f"{module} imports {name}, line {line}")
                break
    assert not wrong, "private names used outside their module:\n" + "\n".join(sorted(set(wrong)))


def test_no_loops_between_packages():
    graph: dict[str, set[str]] = {}
    for module, target, _, _ in _edges():
        if _package(module) != _package(target):
            graph.setdefault(_package(module), set()).add(_package(target))
    found = loops(graph)
    assert not found, "loops between packages: " + "; ".join(found)


def test_the_rules_catch_what_they_name(tmp_path):
    """The parser sees an upward import, a private name and a private attribute of a module."""
    source = tmp_path / "probe.py"
    source.write_text("import vissim.optics.blur.convolve as b\nfrom vissim.optics.depth.depth_map import _x\n"
                      "from vissim.cli import blur\nb._padding(1)\nblur._y\n")
    names = {name for name, _ in _imports(source)}
    assert {"vissim.optics.blur.convolve", "vissim.optics.depth.depth_map._x", "vissim.cli.blur",
            "vissim.optics.blur.convolve._padding", "vissim.cli.blur._y"} <= names
    assert _layer("vissim.cli.blur") > _layer("vissim.bench.dslr.bench") > _layer("vissim.optics.psf.compute") > _layer("vissim.units")


def test_loading_a_campaign_imports_neither_the_harness_nor_scikit_image():
    """Parsing a campaign file needs the loader and the memory preflight, not the item, fit or registration."""
    root = PACKAGE.parent
    code = ("import sys; sys.path.insert(0, sys.argv[1]); from vissim.validation.engine.loader import load_campaign; "
            "load_campaign(sys.argv[2]); "
            "print(sorted(m for m in ('skimage', 'vissim.fit', 'vissim.validation.dslr.item', 'vissim.imaging.registration', "
            "'mitsuba', 'rawpy') if m in sys.modules))")
    for toml in ("quick.toml", "thesis.toml"):
        done = subprocess.run([sys.executable, "-c", code, str(root), str(root / "validation" / toml)],
                              capture_output=True, text=True, cwd=root, timeout=120)
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == "[]", f"{toml}: {done.stdout}"


#: Inside ``validation``: the engine knows no bench kind, and no bench kind knows another
#: (each imports the engine and the layers below; the registry names kinds as strings).  The kinds'
#: packages are read from the registry: ``vissim.validation.eye.kind`` -> ``vissim.validation.eye``.
BENCH_KIND_PACKAGES = tuple(sorted({module.rsplit(".", 1)[0] for module in BENCH_KINDS.values()}))


def test_the_layer_rules_see_every_registered_kind():
    assert set(bench_kind_names()) >= {"dslr", "depth", "eye"}
    assert all(package in MODULES for package in BENCH_KIND_PACKAGES), BENCH_KIND_PACKAGES


def test_the_engine_imports_no_bench_kind_and_kinds_not_each_other():
    def kind_of(module):
        return next((k for k in BENCH_KIND_PACKAGES if module == k or module.startswith(k + ".")), None)

    wrong = sorted({f"{m} imports {t}, line {line}" for m, t, _, line in _edges()
                    if kind_of(t) and (m.startswith("vissim.validation.engine") or kind_of(m) not in (None, kind_of(t)))})
    assert not wrong, "bench kinds imported across the engine's plug-in line:\n" + "\n".join(wrong)
