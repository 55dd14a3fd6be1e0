"""One vocabulary across commands (docs/conventions.md, "Defaults and words"): each word and default
decided once, and every command reading it from there."""

from __future__ import annotations

import argparse
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from vissim.atv.virtual import AtvApparatus, VirtualSubject
from vissim.bench.atv.tube import AtvConfig, AtvEye
from vissim.checks import (DEFAULT_WAVELENGTH_NM, EYE_PUPIL_RANGE_MM, eye_pupil_diameter_mm, pupil_diameter_mm,
                           size_text)
from vissim.cli import build_parser, main
from vissim.errors import VissimInputError
from vissim.imageio import write_image
from vissim.optics.eyes.defaults import PHOTOPIC_FOCUS_NM
from vissim.optics.rx.glass import D_LINE_NM
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import EYE_VERTEX_DISTANCE_MM
from vissim.provenance import make_provenance
from vissim.thesis import THESIS_VERTEX_DISTANCE_MM

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def subcommands(parser=None, path=()):
    """(command path, parser) of every leaf sub-command."""
    parser = parser or build_parser()
    children = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not children:
        yield path, parser
        return
    for name, child in children[0].choices.items():
        yield from subcommands(child, (*path, name))


def option(parser, flag):
    return next((a for a in parser._actions if flag in a.option_strings), None)


# -- sizes --------------------------------------------------------------------------------------


def test_a_size_reads_width_by_height_from_an_array_shape():
    assert size_text((480, 640)) == "640 × 480 px (width × height)"
    assert size_text((480, 640, 3)) == "640 × 480 px (width × height)"  # channels are not a dimension of size
    assert size_text((64, 64)) == "64 × 64 px"
    assert size_text((297.0, 210.0), "mm") == "210 × 297 mm (width × height)"
    assert size_text((8.25, 29.2), "mm") == "29.2 × 8.25 mm (width × height)"


SIZE_LIKE = re.compile(r"\{[^{}]*\}\s*(?:x|×)\s*\{[^{}]*\}\s*(?:px|mm|texel)|shape[^{}]*\}\s*px")


def test_no_message_formats_a_size_but_the_helper():
    # An f-string that writes '{a} x {b} px' or '{shape} px' is a size formatted by hand, in
    # whichever order its author chose; every one goes through size_text.
    hand_made = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
                 for path in sorted((ROOT / "vissim").rglob("*.py")) if path.name != "checks.py"
                 for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
                 if SIZE_LIKE.search(line)]
    assert hand_made == []


def test_success_lines_and_errors_say_sizes_the_same_way(capsys, tmp_path):
    code, out, _ = run(capsys, "chart", "--logmar", "1", "-o", tmp_path / "c.exr")
    assert code == 0 and "chart 550 × 150 px (width × height) at 1 arcmin/px" in out
    image = tmp_path / "wide.exr"
    write_image(image, np.full((20, 40), 0.5, np.float32), provenance=make_provenance(command="test", arcmin_per_px=1.0))
    code, _, err = run(capsys, "blur-depth", image, tmp_path / "missing.npy", "--rx", "-1", "--pupil-mm", "3",
                       "--crop-px", "10", "-o", tmp_path / "o.exr")
    assert code == 2 and "cannot crop 10 px from every side of a 40 × 20 px (width × height) image" in err


# -- defaults -----------------------------------------------------------------------------------


def test_every_wavelength_default_is_the_one_constant():
    # The bench's glass is traced at its d line (render bench --optics wave, bench wavefront), stated in
    # their help; blur's RGB channels have their own wavelengths (mono images take the constant); a
    # schematic eye is reported at its model's reference wavelength (Escudero-Sanz's 543 nm), said in its help;
    # an eye's render is lit at the constant, as the eye campaign is.
    seen = []
    for path, parser in subcommands():
        for flag in ("--wavelength-nm", "--lca-reference-nm"):
            action = option(parser, flag)
            if action is None:
                continue
            seen.append(path)
            if path in (("render", "bench"), ("bench", "wavefront")):
                assert action.default in (None, D_LINE_NM) and "the d line" in action.help
            elif path == ("population",):  # the published human MTFs' light, V(λ)'s peak
                assert action.default is None and f"default {PHOTOPIC_FOCUS_NM:g}: V(λ)'s peak" in action.help
            elif path == ("eye",):
                assert action.default is None and "the model's reference wavelength" in action.help
            elif action.default is None:
                assert path in (("blur",), ("psf",), ("render", "eye")) and f"default {DEFAULT_WAVELENGTH_NM:g}" in action.help
            else:
                assert float(action.default) == DEFAULT_WAVELENGTH_NM, (path, flag)
                assert f"default {DEFAULT_WAVELENGTH_NM:g}" in action.help, (path, flag)
    assert {("psf",), ("blur-depth",), ("fit-rx",), ("atv", "simulate"), ("eye",), ("render", "eye")} <= set(seen)
    assert AtvApparatus().wavelength_nm == DEFAULT_WAVELENGTH_NM  # was 555 nm: no reason recorded


def test_vertex_distances_are_the_camera_and_the_eye_constants():
    parsers = dict(subcommands())
    assert THESIS_VERTEX_DISTANCE_MM == 10.0 and EYE_VERTEX_DISTANCE_MM == 15.0
    assert option(parsers[("trial-lens",)], "--vertex-mm").default == THESIS_VERTEX_DISTANCE_MM
    for path in (("render", "atv"), ("atv", "simulate")):
        assert f"default {EYE_VERTEX_DISTANCE_MM:g}" in option(parsers[path], "--vertex-mm").help
    assert AtvApparatus().trial_lens_vertex_mm == EYE_VERTEX_DISTANCE_MM
    assert AtvConfig().trial_lens_distance_mm == EYE_VERTEX_DISTANCE_MM
    scene = tomllib.loads((ROOT / "scenes" / "atv_tube.toml").read_text(encoding="utf-8"))
    assert scene["trial_lens"]["distance_mm"] == EYE_VERTEX_DISTANCE_MM
    dslr = tomllib.loads((ROOT / "scenes" / "dslr_bench.toml").read_text(encoding="utf-8"))
    assert dslr["holder"]["vertex_distance_mm"] == THESIS_VERTEX_DISTANCE_MM


# -- pupils -------------------------------------------------------------------------------------


def test_an_eye_pupil_and_an_entrance_pupil_are_two_ranges():
    assert EYE_PUPIL_RANGE_MM == (1.0, 10.0)
    assert eye_pupil_diameter_mm(9.0) == 9.0 and pupil_diameter_mm(30.0) == 30.0  # 9 mm eye; a 30 mm lens
    with pytest.raises(VissimInputError, match=r"within 1-10 mm \(a human eye's pupil\), got 30 mm"):
        eye_pupil_diameter_mm(30.0)
    assert AtvEye(pupil_diameter_mm=9.0).pupil_diameter_mm == 9.0  # render atv refused 9 mm
    with pytest.raises(VissimInputError, match="a human eye's pupil"):
        VirtualSubject(Prescription(0.0), 12.0)


@pytest.mark.parametrize("argv", [
    ["atv", "simulate", "--rx", "+1", "--pupil-mm", "12", "-o", "{tmp}/s"],
    ["render", "atv", "--pupil-mm", "12", "-o", "{tmp}/a.exr"],
    ["render", "depth", str(ROOT / "scenes" / "depth_panels.toml"), "--pupil-mm", "12", "-o", "{tmp}/d.exr"],
])
def test_commands_whose_viewer_is_an_eye_refuse_a_pupil_no_eye_has(capsys, tmp_path, argv):
    code, out, err = run(capsys, *[a.format(tmp=tmp_path) for a in argv])
    assert code == 2 and err.count("\n") == 1 and "within 1-10 mm (a human eye's pupil), got 12 mm" in err
    assert not any(tmp_path.iterdir())


# -- words --------------------------------------------------------------------------------------


def test_the_atv_options_say_amplitude_and_the_slopes_variable():
    parsers = dict(subcommands())
    simulate, procedure = parsers[("atv", "simulate")], parsers[("atv", "run")]
    assert option(simulate, "--accommodation-diopters") is None  # there it meant an amplitude
    assert "amplitude" in option(simulate, "--accommodation-amplitude-diopters").help
    assert option(simulate, "--slope") is None and option(procedure, "--slope") is None
    assert "luminance" in option(simulate, "--luminance-slope").help
    assert "code value" in option(procedure, "--code-value-slope").help
    # Everywhere else --accommodation-diopters is the accommodation exerted.
    for path, parser in parsers.items():
        action = option(parser, "--accommodation-diopters")
        if action is not None:
            assert "amplitude" not in action.help and "accommodation" in action.help, path


def test_blur_depth_help_states_one_accommodation_default(capsys):
    assert main(["blur-depth", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert text.count("relaxed, 0 D exerted") == 1 and "default relaxed" not in text
    assert "default the depth at the image centre" not in text


def test_trial_lens_prints_one_cylinder_form(capsys):
    # A plus-cylinder lens: every power the command prints is in minus cylinder.
    code, out, _ = run(capsys, "trial-lens", "--sphere", "1", "--cylinder", "2", "--axis", "30")
    assert code == 0 and "minus-cylinder form" in out.splitlines()[0]
    cylinders = [float(c) for c in re.findall(r"[+-]\d+\.\d+ ([+-]\d+\.\d+) x \d", out)]
    assert len(cylinders) == 3 and all(c < 0 for c in cylinders)  # the lens, the added power, the camera's Rx
    code, out, _ = run(capsys, "trial-lens", "--sphere", "1", "--cylinder", "2", "--axis", "30", "--json")
    record = json.loads(out)
    assert record["cylinder_form"] == "minus"
    for text in (record["lens"]["marked_power"], record["added_power"], record["camera_prescription"]):
        assert Prescription.parse(text).cylinder_diopters < 0, text
    lens = record["lens"]  # +1.00 +2.00 x 30 is +3.00 -2.00 x 120
    assert (lens["sphere_diopters"], lens["cylinder_diopters"], lens["axis_deg"]) == pytest.approx((3.0, -2.0, 120.0))


def test_a_render_without_a_lens_says_so(capsys, tmp_path):
    from vissim.render.backend import choose_variant

    if choose_variant("mono").variant.startswith("scalar"):
        pytest.skip("no JIT Mitsuba variant")
    code, out, _ = run(capsys, "render", "bench", "--letter", "C", "--spp", "4", "--size", "21x21", "-o", tmp_path / "r.exr")
    assert code == 0 and out.rstrip().endswith("no trial lens") and "None" not in out
