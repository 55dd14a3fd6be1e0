"""One set of ranges (`vissim.checks`): the API, the command line and the campaign files refuse alike.

The vertex distance once had three limits (>= 0 in `DslrBench`, <= 200 mm in campaigns,
<= 1000 mm in ``fit-rx``); it now has `VERTEX_DISTANCE_RANGE_MM`, checked by one function.
"""

import ast
from pathlib import Path

import pytest

from vissim.atv.virtual import AtvApparatus
from vissim.bench.dslr.bench import DslrBench
from vissim.bench.atv.tube import AtvEye
from vissim.bench.depth.viewers import EyeViewer
from vissim.checks import (ACCOMMODATION_RANGE_DIOPTERS, TRIAL_LENS_RANGE_DIOPTERS, VERTEX_DISTANCE_RANGE_MM,
                           accommodation_diopters, trial_lens_diopters, vertex_distance_mm)
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import TrialLens, TrialLensSetup, thesis_table_4_2_power

API = {
    "DslrBench": lambda mm: DslrBench(vertex_distance_mm=mm),
    "TrialLensSetup": lambda mm: TrialLensSetup((TrialLens(2.0),), vertex_distance_mm=mm),
    "AtvApparatus": lambda mm: AtvApparatus(trial_lens_vertex_mm=mm),
    "thesis_table_4_2_power": lambda mm: thesis_table_4_2_power(2.0, mm),
    "checks": vertex_distance_mm,
}


def test_the_vertex_distance_range_holds_a_trial_frame():
    # the thesis's bench: 10 mm; spectacles: 12-15 mm; 200 mm: the widest any campaign took before
    assert VERTEX_DISTANCE_RANGE_MM == (0.0, 200.0)


@pytest.mark.parametrize("api", sorted(API))
def test_every_api_takes_the_range_and_refuses_beyond_it(api):
    low, high = VERTEX_DISTANCE_RANGE_MM
    for inside in (low, 10.0, high):
        API[api](inside)
    for outside in (low - 1.0, high + 1.0):
        with pytest.raises(VissimInputError, match=r"within 0-200 mm"):
            API[api](outside)


@pytest.mark.parametrize("value, refused", [("200", False), ("201", True), ("-1", True)])
def test_fit_rx_takes_the_same_range(tmp_path, capsys, value, refused):
    missing = str(tmp_path / "missing.exr")  # a refused --vertex-mm is caught before any file is read
    code = main(["fit-rx", missing, "--reference", missing, "--pupil-mm", "3.6", "--vertex-mm", value,
                 "--object-distance-m", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert ("--vertex-mm" in err) is refused, err


# -- every numeric bound lives in vissim/checks.py -------------------------------------------
VISSIM = Path(__file__).resolve().parents[1] / "vissim"
#: Keywords that pass a range's bounds (lower ones first).
LOWER_KEYWORDS = {"lo", "low", "minimum"}
UPPER_KEYWORDS = {"hi", "high", "maximum", "max_magnitude"}
#: A lower bound of 0 or 1 is a sign or a count (>= 0, >= 1), not a range to name.
SIGN_OR_COUNT = {0, 1}
#: Limits outside vissim/checks.py that bound no value a user gives: internal budgets, tolerances and
#: design rules, each beside the code it governs.
NOT_INPUT_BOUNDS = {
    "DISSIMILARITY_RANGE": "a report figure's axis", "DIFFERENCE_RANGE": "a report figure's scale",
    "MAX_SHIFT_PX": "the alignment's own search", "MAX_NORMAL_CONDITION": "a least-squares fit's method switch", "MAX_ALIGN_PASSES": "the alignment's own iterations",
    "MAX_HANDSHAKE_BYTES": "the scheduler protocol's message size",
    "MIN_AIR_GAP_MM": "a layout rule on derived lens positions",
    "MIN_EDGE_MM": "a realistic lens's design rule", "MIN_CENTER_MM": "a realistic lens's design rule",
    "MAX_LENSES_IN_HOLDER": "the holder's capacity, a fact of the apparatus",
    "MAX_DEPTH": "the path tracer's bounces", "MAX_WAVEFRONT": "Mitsuba's wavefront size",
    "MIN_LLVM_MAJOR": "a dependency's version",
    "MIN_WINDOW_POINTS": "the ATV analysis's fitting window",
    "MAX_TOLERANCE_CODE": "a tolerance on the thesis's printed sums",
    "MAX_INVALID_ANSWERS": "the interactive procedure's patience",
    "MIN_RESOLVED_BLUR_PX": "a fit's decision threshold", "MAX_UNEXPLAINED_FRACTION": "a fit's decision threshold",
    "MIN_REFERENCE_SHARPNESS": "a fit's test of a measured image",
    "MIN_CONTRAST_OVER_NOISE": "a fit's test of a measured image",
    "MAX_CORRELATION_LAG_PX": "the noise model's reach",
    "MAX_TERMS": "an occlusion computation's size", "MAX_ENERGY_OUTSIDE": "a PSF field's truncation tolerance",
    "MIN_PUPIL_CELLS": "the wave PSF's internal sampling", "MAX_INTERNAL_SIZE": "the wave PSF's internal sampling",
    "MIN_RAYS": "the geometric PSF's ray budget", "MAX_RAYS": "the geometric PSF's ray budget",
    "MAX_ARRAYS": "the workspace cache", "MAX_KEPT_BYTES": "the workspace cache",
    "MAX_NEWTON": "the ray tracer's iteration budget", "MAX_GRIN_STEPS": "the GRIN integrator's step budget",
    "MAX_MONOMIAL_ORDER": "which of two exact ways a Zernike sum is evaluated",
}


def _literal(node) -> float | None:
    """The number a node writes literally (``30.0``, ``-30.0``, ``1 << 20``), else None."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        inner = _literal(node.operand)
        return None if inner is None else -inner
    if isinstance(node, ast.BinOp):
        left, right = _literal(node.left), _literal(node.right)
        return None if left is None or right is None else 1.0  # any arithmetic of literals: a literal
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return node.value
    return None


def _bounds_written_as_literals(tree: ast.AST) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            for kw in node.keywords:
                value = _literal(kw.value)
                if value is not None and (kw.arg in UPPER_KEYWORDS
                                          or (kw.arg in LOWER_KEYWORDS and value not in SIGN_OR_COUNT)):
                    found.append(f"line {node.lineno}: {kw.arg}={ast.unparse(kw.value)}")
            name = getattr(node.func, "id", getattr(node.func, "attr", ""))
            if name.endswith("_range") or name.lstrip("_") == "within":
                literals = [ast.unparse(a) for a in node.args if _literal(a) is not None]
                if len(literals) >= 2:
                    found.append(f"line {node.lineno}: {name}(..., {', '.join(literals)})")
        if isinstance(node, ast.Dict):  # {key: (unit, lowest, highest)} tables
            for value in node.values:
                if isinstance(value, ast.Tuple) and any(isinstance(e, ast.Constant) and isinstance(e.value, str)
                                                        for e in value.elts):
                    numbers = [e for e in value.elts if _literal(e) is not None]
                    bounds = numbers[1:] if numbers and _literal(numbers[0]) in SIGN_OR_COUNT else numbers
                    found += [f"line {value.lineno}: {ast.unparse(value)}"] if bounds else []
        if isinstance(node, ast.Assign) and node.col_offset == 0:
            for target in node.targets:
                for name in [t.id for t in ast.walk(target) if isinstance(t, ast.Name)]:
                    constant = name.startswith(("MAX_", "MIN_")) or "_RANGE" in name
                    if constant and name not in NOT_INPUT_BOUNDS:
                        found.append(f"line {node.lineno}: {name} (a range belongs in vissim/checks.py)")
    return found


def test_no_module_writes_a_numeric_bound_of_its_own():
    """Every value range is a named constant of `vissim.checks`: a bound written as a number elsewhere
    (``hi=180.0``, ``_range(x, ..., -20.0, 20.0)``, ``("mm", 0.0, 25.0)``, ``MAX_TILE_PX = ...``) is a
    second range that can drift from the first. Limits that bound no input are listed, with why."""
    offenders = {}
    for path in sorted(VISSIM.rglob("*.py")):
        relative = path.relative_to(VISSIM).as_posix()
        if relative == "checks.py":
            continue
        found = _bounds_written_as_literals(ast.parse(path.read_text(encoding="utf-8")))
        if found:
            offenders[relative] = found
    assert not offenders, offenders


# -- quantities two readers once bounded differently ------------------------------------------
def _campaign_lens(diopters):
    from vissim.validation.engine.fields import lens

    return lens(diopters, "campaign.toml", "item[0].lenses[0]")


def _scene_lens(diopters):
    from vissim.bench.scene_toml import parse_trial_lenses

    return parse_trial_lenses([{"sphere_diopters": diopters}], "scene.toml [[holder.lenses]]")


def _atv_trial(diopters):
    from vissim.atv.records import Trial

    return Trial(diopters, "R", 0.5, 10.0, 100.0)


TRIAL_LENS_READERS = {"checks": trial_lens_diopters, "campaign file": _campaign_lens, "bench scene file": _scene_lens,
                      "ATV subject file": _atv_trial}  # the ATV subject files once stopped at +-20 D


@pytest.mark.parametrize("reader", sorted(TRIAL_LENS_READERS))
def test_every_reader_of_a_trial_lens_takes_one_range(reader):
    low, high = TRIAL_LENS_RANGE_DIOPTERS
    assert (low, high) == (-30.0, 30.0)  # trial sets go to +-20 D; beyond +-30 D a lens is no trial lens
    for inside in (low, -25.0, 25.0, high):
        TRIAL_LENS_READERS[reader](inside)
    for outside in (low - 0.25, high + 0.25):
        with pytest.raises(VissimInputError, match=r"-30\D+30 (D|dioptres)"):
            TRIAL_LENS_READERS[reader](outside)


ACCOMMODATION_READERS = {  # the ATV eye once stopped at 15 D, the depth scene file's eye at none
    "checks": accommodation_diopters,
    "AtvEye": lambda d: AtvEye(accommodation_diopters=d),
    "EyeViewer": lambda d: EyeViewer(accommodation_diopters=d),
}


@pytest.mark.parametrize("reader", sorted(ACCOMMODATION_READERS))
def test_every_reader_of_an_eyes_accommodation_takes_one_range(reader):
    low, high = ACCOMMODATION_RANGE_DIOPTERS
    assert (low, high) == (0.0, 20.0)
    for inside in (low, 17.5, high):
        ACCOMMODATION_READERS[reader](inside)
    with pytest.raises(VissimInputError, match=r"accommodation must be .*20 dioptres, got 20.5"):
        ACCOMMODATION_READERS[reader](high + 0.5)


@pytest.mark.parametrize("bounds, unit, text", [((0.0, 10.0), "dioptres", "within 0-10 dioptres"),
                                                ((-5.0, 5.0), "mm", "within -5 to 5 mm"),
                                                ((0.0, 0.0), "dioptres", "0 dioptres only")])
def test_a_range_is_named_one_way_and_a_one_value_range_as_that_value(bounds, unit, text):
    """Issue 33: a range of one value read "within 0-0 dioptres"; every refusal names it by `range_text`."""
    from vissim.checks import number_within, range_text

    assert range_text(bounds, unit) == text
    with pytest.raises(VissimInputError) as info:
        number_within(bounds[1] + 1.0, "x", unit, bounds)
    assert f"x must be {text}, got" in str(info.value) and "0-0" not in str(info.value)
