"""The eye bench (kind "eye"): its campaign file, its ray PSF, and a toy campaign through `validate`.

Oracles: the ray PSF of an eye defocused by a trial lens is a blur disc of angular diameter
pupil x vergence error (geometric optics of a thin defocus, the reduced eye's first-order
law; the schematic eye's spherical aberration and the lens's thickness move it by a few %);
the campaign's geometric self-check is an independent trace of the rendered scene and must land
at the render's noise floor (+3 dB for a noise-free match, >= +2 dB required).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.validation.engine.validate import validate
from vissim.validation.eye.rays import ray_psf
from vissim.validation.eye.schema import read_campaign

TOY = """
[campaign]
kind = "eye"
name = "eye toy"
spp = 64
size_px = [24, 24]
arcmin_per_px = 1.0
oversample = 2
rays_across = 61

[[item]]
name = "plain"
pupil_mm = 3.0

[[sweep]]
name = "lens"
lens = [1.0]
field = 0.0
"""


def test_the_campaign_file_is_checked():
    doc = {"item": [{"name": "a", "lens": 1.0, "field": 10.0}]}
    with pytest.raises(VissimInputError, match=r"item\[0\].*lens"):
        read_campaign(doc, {"kind": "eye"}, "eye.toml")
    with pytest.raises(VissimInputError, match="pupil"):
        read_campaign({"item": [{"pupil_mm": 10.5}]}, {"kind": "eye"}, "eye.toml")  # an eye's pupil: 1-10 mm
    with pytest.raises(VissimInputError, match=r"item\[0\].*accommodation"):  # Arizona's range is 0-6 D
        read_campaign({"item": [{"model": "arizona", "accommodation": 7.0}]}, {"kind": "eye"}, "eye.toml")
    with pytest.raises(VissimInputError, match="colour"):
        read_campaign({"item": [{"colour": 1}]}, {"kind": "eye"}, "eye.toml")
    settings, configurations = read_campaign({"sweep": [{"name": "p", "pupil_mm": [3.0, 6.0], "light": "photopic"}]},
                                             {"kind": "eye", "spp": 8}, "eye.toml")
    assert settings.spp == 8 and [c.pupil_mm for c in configurations] == [3.0, 6.0]
    assert {c.spectrum for c in configurations} == {"photopic"}


def test_a_defocused_eye_s_ray_psf_is_the_blur_disc():
    """+2 D before a relaxed Navarro eye at 6 m, 550 nm: the vergence error at the eye P / (1 - dP) - 1/6 m plus the
    eye's own myopia at 550 nm (`paraxial.refraction_diopters`: -0.175 D) ~ 2.06 D: a blur disc of 3 mm x 2.06 D =
    6.2 mrad = 21.2 arcmin, its RMS radius R / sqrt 2.  The plus lens enlarges the beam the eye's pupil takes (~4 %)
    and the eye's spherical aberration spreads the disc: within 12 %.  The traced spectacle magnification is the
    vergence-matrix one (`trial_lens_effect`) with the lens 12 mm + the eye's paraxial entrance-pupil depth in
    front of the pupil: measured 1.035153 against 1.035149, held to 1e-4."""
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, refraction_diopters
    from vissim.optics.trial_lens import TrialLens, TrialLensSetup, trial_lens_effect

    lens = TrialLens(2.0, 0.0, 180.0, refractive_index=1.523, center_thickness_mm=3.0)
    ray = ray_psf(model="navarro-1985", accommodation_diopters=0.0, pupil_mm=3.0, field_deg=(0.0, 0.0),
                  chart_distance_m=6.0, lens=lens, arcmin_per_px=1.0, oversample=4, rays_across=61)
    rows, cols = np.indices(ray.psf.shape)
    centre = (ray.psf.shape[0] - 1) / 2.0
    rms_arcmin = math.sqrt(float((ray.psf * ((rows - centre) ** 2 + (cols - centre) ** 2)).sum())) * ray.step_arcmin
    eye = eye_model("navarro-1985")
    vergence = 2.0 / (1.0 - 0.012 * 2.0) - 1.0 / 6.0 - refraction_diopters(eye, 550.0)
    expected = math.degrees(3e-3 * vergence) * 60.0
    assert 2.0 * math.sqrt(2.0) * rms_arcmin == pytest.approx(expected, rel=0.12)
    assert ray.magnification[0, 0] == pytest.approx(ray.magnification[1, 1], rel=1e-3)
    span_mm = 12.0 + entrance_pupil_position_mm(eye, 550.0)
    expected_magnification = trial_lens_effect(TrialLensSetup((lens,), span_mm, 6.0)).magnification_matrix[0][0]
    assert ray.magnification[0, 0] == pytest.approx(expected_magnification, rel=1e-4)


@pytest.mark.slow
def test_a_toy_eye_campaign_runs_through_the_engine(tmp_path):
    path = tmp_path / "eye.toml"
    path.write_text(TOY)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.kind == "eye" and done.summary.items_total == 2 and done.summary.renders_made == 4
    tables = (tmp_path / "run" / "tables.md").read_text()
    for words in ("Geometric self-check", "reduced eye, ray optics", "thesis setup", "schematic eye, wave optics",
                  "spherical aberration", "spectacle magnification", "| plain |"):
        assert words in tables
    import json

    rows = json.loads((tmp_path / "run" / "metrics.json").read_text())["rows"]
    checks = [r for r in rows if r["simulation"] == "traced_rays"]
    assert len(checks) == 2
    for row in checks:
        assert 2.0 <= row["over_floor_db"] <= 4.0, row  # the independent trace sits at the render's noise floor
    again = validate(path, tmp_path / "run", show_progress=False)
    assert again.summary.items_reused == 2 and again.summary.renders_made == 0
