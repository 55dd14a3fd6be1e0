"""The reports speak a vision scientist's words: configuration names without repeated words or code keys, every
power in minus cylinder, every term the page uses defined on it, scores read with their arithmetic, and a verdict.

Oracles: the campaign files (validation/*.toml), the committed reports (validation/reports/), the scoring
arithmetic (two renders' noise against one render's, checked by simulated noise), and hand-made rows.
"""

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from vissim.optics.rx.prescription import Prescription
from vissim.validation.dslr.report import summary_lines
from vissim.validation.engine.fields import LensSpec
from vissim.validation.engine.reading import (GLOSSARY, ONE_GREY_LEVEL_PSNR_DB, how_to_read, own_error_fraction,
                                              perfect_score_db, terms_used)
from vissim.validation.engine.tiles import LABEL_PX, tile_strip
from vissim.validation.eye.report import self_check_passes
from vissim.validation.eye.schema import read_campaign, sweep_name

ROOT = Path(__file__).resolve().parents[2]
REPORTS = ROOT / "validation" / "reports"
#: A power written in plus cylinder: a sphere, then a positive cylinder before its axis.
PLUS_CYLINDER = re.compile(r"(?:[+-]\d+\.\d+|plano) \+\d+\.\d+ x \d")
#: Code identifiers a reader should never meet in a configuration's name.
CODE_WORDS = re.compile(r"\b(pupil_mm|field_deg|chart_distance_m|eye_model|wavelength_nm)\b")


def eye_names(campaign: str) -> list[str]:
    doc = tomllib.loads((ROOT / "validation" / campaign).read_text())
    _, configurations = read_campaign(doc, doc["campaign"], campaign)
    return [c.name for c in configurations]


@pytest.mark.parametrize("campaign", ["eye.toml", "eye_measured.toml"])
def test_eye_configuration_names_repeat_no_word_and_show_no_code_key(campaign):
    for name in eye_names(campaign):
        words = name.replace(",", " ").split()
        assert not any(a.lower() == b.lower() for a, b in zip(words, words[1:])), name  # "field field 10,0"
        assert not CODE_WORDS.search(name), name
        assert not PLUS_CYLINDER.search(name), name


def test_the_eye_campaign_s_sweeps_are_named_in_words():
    names = set(eye_names("eye.toml"))
    for expected in ("10° field", "3 mm pupil", "photopic light, 4 mm pupil", "trial lens +1.00 DS",
                     "trial lens +1.00 -1.00 x 180", "2 D accommodation, trial lens -2.00 DS, 3 mm pupil"):
        assert expected in names


def test_a_sweep_keeps_its_name_where_its_settings_do_not_say_it():
    assert sweep_name("baseline", {"pupil_diameter_mm": 3.0}) == "baseline, 3 mm pupil"
    assert sweep_name("pupil", {"pupil_diameter_mm": 3.0}) == "3 mm pupil"
    assert sweep_name("field", {"field_deg": [10.0, 5.0]}) == "field 10°, 5° (x, y)"
    assert sweep_name("light", {"spectrum": "photopic"}) == "photopic light"
    assert sweep_name("light", {"wavelength_nm": 450.0}) == "450 nm light"
    assert sweep_name("myope", {"prescription": -3.0}) == "myope, eye Rx -3.00 DS"
    # a +1.00 cylinder at 90 is +1.00 -1.00 x 180: the same power in minus cylinder
    assert sweep_name("lens", {"lens": {"cylinder_diopters": 1.0, "axis_deg": 90}}) == "trial lens +1.00 -1.00 x 180"
    assert np.allclose(Prescription.parse("+1.00 -1.00 x 180").power_matrix(), Prescription(0.0, 1.0, 90.0).power_matrix())


@pytest.mark.parametrize("lens, written", [((0.0, 2.0, 90.0), "+2.00 -2.00 x 180"), ((2.0, 0.0, 180.0), "+2.00 DS"),
                                           ((0.0, -1.0, 30.0), "plano -1.00 x 30"), ((-1.0, 0.5, 10.0), "-0.50 -0.50 x 100")])
def test_a_trial_lens_is_labelled_in_minus_cylinder_with_its_sphere_s_sign(lens, written):
    assert LensSpec(*lens).label() == written


@pytest.mark.parametrize("report", ["eye", "thesis", "eye_measured"])
def test_no_committed_report_writes_a_power_in_plus_cylinder(report):
    text = (REPORTS / report / "tables.md").read_text()
    assert not PLUS_CYLINDER.search(text), PLUS_CYLINDER.search(text).group(0)
    assert " DC x " not in text


def section(text: str, heading: str) -> str:
    return text.split(f"### {heading}")[1].split("\n### ")[0]


@pytest.mark.parametrize("report", ["eye", "thesis"])
def test_every_term_a_committed_report_uses_is_defined_on_it(report):
    text = (REPORTS / report / "tables.md").read_text()
    defined = section(text, "How to read this page")
    rest = text.replace(defined, "")
    used = terms_used(rest)
    assert {"noise floor", "dB over the floor", "self-check", "ray optics", "wave optics", "SSIM"} <= set(used)
    for term in used:
        assert f"* **{term}**: " in defined, term
    assert "as printed" not in text and "thesis setup" not in text  # terms once used and never defined
    assert "provenance in metrics.json" not in text  # cites only what is committed beside it
    assert "### How this page was built" in text


def test_how_to_read_defines_exactly_the_terms_the_page_uses():
    page = "The noise floor, and its SSIM."
    text = how_to_read(page)
    # render and spp always: How this page was built, written after the rest, uses them
    assert [line.split("**")[1] for line in text.splitlines() if line.startswith("* **")] == [
        "render", "spp", "noise floor", "SSIM"]
    assert "Strehl" not in text
    for term, (patterns, definition) in GLOSSARY.items():
        assert patterns and len(definition) > 30, term


def test_a_perfect_simulation_scores_ten_log_two_and_more_against_a_blurred_reference():
    """Simulated noise: two renders (truth + independent noise), a perfect simulation (the truth). Against one
    render it scores 10 log10 2 over the floor; against the render convolved with a PSF h (noise kept: sum h^2),
    10 log10(2 / sum h^2), as the eye report's 'a perfect wave simulation' column says."""
    from scipy.signal import fftconvolve

    rng = np.random.default_rng(1)
    truth = np.zeros((400, 400))
    a, b = (truth + 0.05 * rng.standard_normal(truth.shape) for _ in range(2))
    mse = lambda x, y: float(((x - y)[8:-8, 8:-8] ** 2).mean())  # noqa: E731
    floor = mse(a, b)
    assert 10 * math.log10(floor / mse(truth, a)) == pytest.approx(perfect_score_db(1.0), abs=0.05)
    h = np.outer([1, 2, 1], [1, 2, 1]) / 16.0
    blurred = fftconvolve(a, h, mode="same")
    assert 10 * math.log10(floor / mse(truth, blurred)) == pytest.approx(perfect_score_db(float((h ** 2).sum())), abs=0.1)
    assert perfect_score_db(float((h ** 2).sum())) > 8.0
    # +2 dB over the floor leaves the simulation an error of its own of 26 % of one render's noise power
    assert own_error_fraction(2.0) == pytest.approx(2 * 10 ** -0.2 - 1) and own_error_fraction(perfect_score_db()) == pytest.approx(0.0)


def _result(over_floor_db: float, ssim: float, floor_ssim: float) -> dict:
    return {"rows": [{"simulation": "traced_rays", "over_floor_db": over_floor_db, "ssim": ssim}],
            "noise_floor": {"psnr_db": 30.0, "ssim": floor_ssim}}


def test_the_self_check_needs_its_db_and_an_ssim_at_least_the_renders_own():
    assert self_check_passes(_result(2.9, 0.60, 0.41))  # photopic: SSIM 0.6, above the renders' 0.41
    assert not self_check_passes(_result(2.9, 0.60, 0.65))  # less like the render than a second render is
    assert not self_check_passes(_result(1.9, 0.99, 0.41))


def _row(configuration, simulation, psnr, floor, lenses="+2.00 DS", input_kind="render", reference="render"):
    return {"configuration": configuration, "simulation": simulation, "input": input_kind, "lenses": lenses,
            "reference": reference, "psnr_db": psnr, "noise_floor_psnr_db": floor, "ssim": 0.99}


def test_the_verdict_names_the_worst_and_judges_the_no_lens_configuration_by_one_grey_level():
    rows = [_row("a", "wave", 44.9, 45.6), _row("a", "geometric", 47.0, 44.0), _row("b", "wave", 46.0, 45.0),
            _row("b", "thesis", 29.0, 45.6),
            # no lens: a 65 dB floor would make this fine 51.6 dB simulation read -13.5 dB
            _row("bare", "wave", 51.6, 65.1, lenses="no lens", input_kind="synthetic"),
            _row("bare", "geometric", 64.5, 63.5, lenses="no lens")]
    lines = summary_lines(rows)
    assert lines[0].startswith("verdict: all 3 wave- and ray-optics simulations of the 2 configurations with a lens "
                               "within 0.7 dB of the render's noise floor (2 at or above it); worst: a, wave optics")
    assert "-0.70 dB" in lines[0]
    bare = next(line for line in lines if line.startswith("no lens"))
    assert f"PSNR >= {ONE_GREY_LEVEL_PSNR_DB:.1f} dB" in bare and "2 of 2" in bare and "-13.5" not in bare
    assert any(line.startswith("thesis method") and "not judged" in line for line in lines)
    assert len(lines) <= 8 and all(len(line) < 300 for line in lines)
    failing = summary_lines(rows[:4] + [_row("bare", "wave", 46.0, 65.1, lenses="no lens")])
    assert "1 of 2" not in failing[-1] and any("0 of 1" in line for line in failing)


def test_a_tile_strip_is_its_images_side_by_side_under_their_labels():
    from io import BytesIO

    from PIL import Image

    grey = np.full((10, 12), 0.5)
    png = tile_strip([grey, grey, grey - 0.5], ["grey", "grey", "difference"], ["render", "simulation", "difference"],
                     zoom=2)
    image = np.asarray(Image.open(BytesIO(png)).convert("L"))
    assert image.shape == (20 + LABEL_PX, 3 * 24 + 2 * 6)
    assert image[LABEL_PX + 5, -5] == 128  # no difference: mid-grey


def test_a_measured_eye_is_named_by_its_study_subject_and_eye():
    name = sweep_name("subject 92", {"eye_model": "jaeken-artal-2012:92:right", "field_deg": [-20.0, 0.0]})
    assert name == "Jaeken & Artal 2012 subject 92, right eye, -20° field"
    assert sweep_name("x", {"eye_model": "polans-2015:3:right"}) == "x, Polans et al. 2015 subject 3, right eye"
    assert sweep_name("model", {"eye_model": "navarro-1985"}) == "model, navarro-1985"
