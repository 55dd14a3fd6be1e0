"""A new schematic model is one file and a registration (`vissim.optics.eyes.models.register_eye_model`).

The model here is Emsley's reduced eye, written in this file only: one refracting surface of radius 50/9 mm
into water-like 4/3, the retina 22.22 mm behind (Emsley 1952, Visual Optics; Atchison & Smith 2000, Optics of
the Human Eye, sec. 5.2): power (n' - 1) / r = (1/3) / 5.555... mm = 60 D, image focal length n'/F = 22.22 mm,
so it is emmetropic. Once registered it is an eye everywhere an eye's name is taken: `build_eye`, the traced
wavefront, the eye campaign's ``eye_model`` and ``vissim eye --eye-model``.
"""

from __future__ import annotations

import json
import math

import pytest

from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.optics.eyes import models
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.dispersion import Medium
from vissim.optics.eyes.models import EyeSurface, SchematicEye, register_eye_model
from vissim.optics.eyes.paraxial import equivalent_power_diopters, refraction_diopters
from vissim.optics.eyes.psf_wavefront import eye_wavefront
from vissim.optics.eyes.refraction import paraxial_prescription
from vissim.validation.eye.schema import read_campaign

NAME = "emsley-reduced"
WATER = Medium("reduced eye", "constant", (4.0 / 3.0,), "Emsley 1952")


def emsley_reduced(accommodation_diopters: float = 0.0) -> SchematicEye:
    if accommodation_diopters != 0.0:
        raise VissimInputError(f"{NAME} accommodation must be 0 D only, got {accommodation_diopters:g} D")
    surfaces = (EyeSurface("cornea", 50.0 / 9.0, 0.0, 0.5, WATER),
                EyeSurface("iris", math.inf, 0.0, 200.0 / 9.0 - 0.5, WATER, "stop"),
                EyeSurface("retina", -12.0, 0.0, 0.0, WATER, "retina"))
    return SchematicEye(NAME, surfaces, 1, 589.3, "Emsley 1952 (reduced eye)")


@pytest.fixture()
def registered(monkeypatch):
    monkeypatch.setattr(models, "EYE_MODELS", dict(models.EYE_MODELS))
    register_eye_model(NAME, emsley_reduced)
    return NAME


def test_the_registered_model_is_the_reduced_eye_of_the_textbooks(registered):
    eye = build_eye(registered, pupil_diameter_mm=3.0)
    assert equivalent_power_diopters(eye.optics, 589.3) == pytest.approx(60.0, abs=1e-9)
    assert refraction_diopters(eye.optics, 589.3) == pytest.approx(0.0, abs=1e-9)
    front = eye_wavefront(eye.with_pupil(pupil_diameter_mm=1.0))  # traced: paraxially emmetropic, as the paraxial numbers say
    assert paraxial_prescription(front.coefficients_um, 1.0).sphere_diopters == pytest.approx(0.0, abs=0.01)


def test_the_registered_model_is_taken_by_a_campaign_and_the_command_line(registered, capsys):
    _, (item,) = read_campaign({"item": [{"eye_model": registered, "pupil_diameter_mm": 3.0}]}, {"kind": "eye"}, "eye.toml")
    assert item.eye().model == registered
    assert main(["eye", "--eye-model", registered, "--pupil-mm", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == registered


def test_a_name_taken_is_refused(registered):
    with pytest.raises(VissimInputError, match="registered already"):
        register_eye_model(registered, emsley_reduced)
