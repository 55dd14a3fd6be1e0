"""The eye's defaults are said once (`vissim.optics.eyes.defaults`): no other literal default for them in the package.

A default is a function parameter's default, a dataclass field's, a ``dict.get``'s fallback or an argparse
``default=``. For the model it is the literal name; for a pupil or a spectacle vertex, a number given to a name
that holds one (``pupil_mm``, ``vertex_mm``, ...); in the eye's own modules (a path naming an eye), also a number
or letter given to the light, the chart or the image (``wavelength_nm``, ``logmar``, ``arcmin_per_px``, ...). A
study's own choice gets its own named constant.
"""

from __future__ import annotations

import ast
from pathlib import Path

from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL

PACKAGE = Path(__file__).resolve().parents[1] / "vissim"
#: Where the defaults are said, and the model tables that name their own models.
ALLOWED = {"optics/eyes/defaults.py", "optics/eyes/models.py", "optics/eyes/dispersion.py"}
#: Names that hold an eye's pupil or spectacle vertex.
EYE_NUMBER_NAMES = ("pupil_mm", "iris_mm", "vertex_mm", "rx_vertex_mm")
#: Names that hold the eye's light, chart or image, in the eye's own modules (a path naming an eye): the DSLR and
#: depth benches keep the thesis's chart and sampling.
EYE_VIEW_NAMES = ("wavelength_nm", "wavelengths_nm", "logmar", "letter", "chart_distance_m", "arcmin_per_px",
                  "size_px")


def _defaults(tree: ast.AST):
    """(name, default node, line) of every default in ``tree`` (module doc)."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            positional = args.posonlyargs + args.args
            for arg, default in zip(positional[len(positional) - len(args.defaults):], args.defaults):
                yield arg.arg, default, default.lineno
            for arg, default in zip(args.kwonlyargs, args.kw_defaults):
                if default is not None:
                    yield arg.arg, default, default.lineno
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
            yield node.target.id, node.value, node.lineno
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
                and len(node.args) == 2 and isinstance(node.args[0], ast.Constant):
            yield str(node.args[0].value), node.args[1], node.lineno
        elif isinstance(node, ast.Call):
            for keyword in node.keywords:
                if keyword.arg == "default":
                    yield "default=", keyword.value, keyword.value.lineno


def _literal(value: ast.AST) -> bool:
    """A number or letter written out (alone or in a tuple); None and keywords such as "auto" are not defaults."""
    if isinstance(value, ast.Tuple):
        return bool(value.elts) and all(_literal(v) for v in value.elts)
    return isinstance(value, ast.Constant) and (isinstance(value.value, (int, float)) and not isinstance(value.value, bool)
                                                or isinstance(value.value, str) and len(value.value) == 1)


def _literal_defaults(package: Path = PACKAGE):
    found = []
    for path in sorted(package.rglob("*.py")):
        relative = path.relative_to(package).as_posix()
        if relative in ALLOWED:
            continue
        for name, value, line in _defaults(ast.parse(path.read_text(), str(path))):
            if "eye" in relative and name.endswith(EYE_VIEW_NAMES) and _literal(value):
                found.append(f"{relative}:{line} {name} = {ast.unparse(value)}")
                continue
            if not isinstance(value, ast.Constant):
                continue
            if value.value == DEFAULT_EYE_MODEL:
                found.append(f"{relative}:{line} {name} = {value.value!r}")
            elif name.endswith(EYE_NUMBER_NAMES) and isinstance(value.value, (int, float)) \
                    and not isinstance(value.value, bool):
                found.append(f"{relative}:{line} {name} = {value.value!r}")
    return found


def test_no_literal_eye_default_outside_the_defaults_module():
    assert _literal_defaults() == []


def test_the_scan_finds_a_literal_default_where_there_is_one(tmp_path):
    """The scan itself: a planted literal default of each kind is found (it can fail)."""
    (tmp_path / "planted.py").write_text(
        "def f(model='navarro-1985', *, pupil_mm=3.0):\n    return {}.get('vertex_mm', 12.0)\n")
    (tmp_path / "eye_planted.py").write_text(
        "def g(wavelengths_nm=(550.0,), letter='K', logmar=0.5, size_px='auto', wavelength_nm=None):\n    pass\n")
    assert len(_literal_defaults(tmp_path)) == 6
