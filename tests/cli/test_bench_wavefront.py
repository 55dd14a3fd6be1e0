"""``vissim bench wavefront``: the traced Zernike table, RMS and added power; one error line for bad input.

Expected values: vergence theory of the bench's rendered (1.03 mm thick) +2 D lens,
``trial_lens_effect`` = +1.9925 D at 914.4 mm (1.9960 D for a thin lens, ERRATA item 4).
"""

from __future__ import annotations

import json

import pytest

from vissim.cli import main

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def run_json(capsys, *args: str) -> dict:
    assert main(["bench", "wavefront", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_has_the_zernike_table_rms_and_added_power(capsys):
    result = run_json(capsys, "--sphere", "2")
    assert set(result["zernike_um"]) >= {"2,0", "4,0", "8,0"} and "1,1" not in result["zernike_um"]
    assert result["zernike_um"]["2,0"] > 0  # a plus lens makes the camera myopic: c(2,0) > 0
    assert result["rms_um"] == pytest.approx(abs(result["zernike_um"]["2,0"]), rel=1e-4)
    assert result["effective_sphere_diopters"] == pytest.approx(1.9925, abs=5e-5)
    assert result["vergence_theory_added_power"] == "+1.9925 DS"
    assert result["pupil_diameter_mm"] == 3.6 and result["wavelength_nm"] == 587.5618
    assert result["lenses"][0]["back_vertex_z_mm"] == 10.0
    assert result["written"] == []  # --json's shared shape: the files written (none here)


def test_readable_output_prints_the_table(capsys):
    assert main(["bench", "wavefront", "--cylinder", "2", "--axis", "30", "--field-deg", "-0.9,1.1"]) == 0
    out = capsys.readouterr().out
    assert "zernike_um" in out and "2,-2" in out and "rms:" in out
    assert "equivalent added power:  +1.99" in out and "x 120.00" in out  # minus cylinder: x 30 in plus form


def test_scene_file_and_overrides(capsys):
    scene = run_json(capsys, "--scene", str(ROOT / "scenes/dslr_bench.toml"))  # +2 D in its holder
    assert scene["effective_sphere_diopters"] == pytest.approx(1.9925, abs=5e-5)
    wide = run_json(capsys, "--scene", str(ROOT / "scenes/dslr_bench.toml"), "--f-number", "2.5")
    assert wide["pupil_diameter_mm"] == 7.2
    blue = run_json(capsys, "--sphere", "2", "--wavelength-nm", "486.1327")
    assert blue["effective_sphere_diopters"] > scene["effective_sphere_diopters"]  # n_F > n_d


@pytest.mark.parametrize("args, fragment", [
    (["--field-deg", "1"], "--field-deg"),
    (["--field-deg", "1,nan"], "--field-deg"),
    (["--cylinder", "1"], "--axis"),
    (["--wavelength-nm", "0"], "--wavelength-nm"),
    (["--wavelength-nm", "nan"], "--wavelength-nm"),
    (["--wavelength-nm", "100"], "wavelength"),
    (["--f-number", "-1"], "--f-number"),
    (["--max-order", "0"], "order"),
    (["--sphere", "1e300"], "--sphere"),
    (["--field-deg", "30,0"], "clear aperture"),
    (["--scene", "/no/such/scene.toml"], "scene"),
])
def test_bad_input_is_one_error_line(capsys, args, fragment):
    assert main(["bench", "wavefront", "--sphere", "2", *args]) == 2
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("vissim: error: ") and fragment in lines[0], lines
    assert captured.out == ""
