"""``vissim trial-lens``: JSON keys and values, readable output, exit codes for bad input."""

from __future__ import annotations

import json

import pytest

from vissim.cli import main


def run_json(capsys, *args: str) -> dict:
    assert main(["trial-lens", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_for_a_plus_2_lens_at_infinity(capsys):
    result = run_json(capsys, "--sphere", "2")
    for key in ("effective_sphere_diopters", "effective_cylinder_diopters", "effective_axis_deg",
                "magnification", "magnification_principal", "camera_prescription",
                "object_distance_m", "vertex_distance_mm"):
        assert key in result
    # Krueger 2015, Table 4.2: +2 D at 10 mm adds 2.0408 D; magnification 1/(1 - 0.02) (ERRATA 5).
    assert round(result["effective_sphere_diopters"], 4) == 2.0408
    assert result["effective_cylinder_diopters"] == 0.0
    assert result["magnification"] == pytest.approx(1 / 0.98, abs=1e-12)
    assert result["camera_prescription"] == "-2.04 DS"
    assert result["object_distance_m"] is None
    assert result["vertex_distance_mm"] == 10.0
    assert round(result["thesis_table_4_2"][0]["power_diopters"], 4) == 2.0408
    assert result["written"] == []  # --json's shared shape: the files written (none here)


def test_json_for_the_chart_at_914mm(capsys):
    result = run_json(capsys, "--sphere", "2", "--object-distance-m", "0.9144")
    # ERRATA item 4: about 1.996 D, not 2.041 D (exact trace in tests/test_trial_lens.py).
    assert round(result["effective_sphere_diopters"], 4) == 1.9960
    assert result["object_distance_m"] == 0.9144


def test_json_for_a_plus_cylinder_is_in_minus_cylinder_form(capsys):
    result = run_json(capsys, "--sphere", "0", "--cylinder", "2", "--axis", "90")
    # +2 DC x 90 adds 2/(1 - 0.02) D in the 180 meridian only: +2.0408 -2.0408 x 180.
    assert result["effective_sphere_diopters"] == pytest.approx(2 / 0.98, abs=1e-12)
    assert result["effective_cylinder_diopters"] == pytest.approx(-2 / 0.98, abs=1e-12)
    assert result["effective_axis_deg"] == 180.0
    principal = {row["meridian_deg"]: row["magnification"] for row in result["magnification_principal"]}
    assert principal == pytest.approx({180.0: 1 / 0.98, 90.0: 1.0}, abs=1e-12)


def test_thickness_without_index_uses_crown_glass(capsys):
    result = run_json(capsys, "--sphere", "2", "--thickness-mm", "3")
    assert result["lens"]["refractive_index"] == 1.523
    assert result["magnification"] > 1 / 0.98  # shape factor, about +0.4 %


def test_readable_output_shows_the_table_4_2_value(capsys):
    assert main(["trial-lens", "--sphere", "2", "--object-distance-m", "0.9144"]) == 0
    out = capsys.readouterr().out
    assert "+1.9960" in out
    assert "Table 4.2" in out and "+2.0408" in out
    assert "magnification" in out


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--sphere", "0", "--cylinder", "-2"], "--axis"),
        (["--sphere", "2", "--object-distance-m", "far"], "far"),
        (["--sphere", "2", "--object-distance-m", "0.005"], "0.005 m"),
        (["--sphere", "2", "--index", "0.9", "--thickness-mm", "2"], "0.9"),
        (["--sphere", "2", "--thickness-mm", "-1"], "--thickness-mm must be within 0-1000 mm, got '-1'"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, args, fragment):
    assert main(["trial-lens", *args]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0]
