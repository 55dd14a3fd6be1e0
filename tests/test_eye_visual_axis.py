"""Field angles from the visual axis (`vissim.optics.eyes.traced_wavefront`): Liou–Brennan's 5° angle alpha.

The rule (written once, in `traced_wavefront.field_direction`): for a model with ``visual_axis_deg``
(Liou & Brennan 1997: the visual axis 5° from the optical axis, fixation nasal of it; the models
are right eyes, +x nasal in OSA's frame), a field angle is measured from the visual axis, so field
(0, 0) is the fixation direction, (+5°, 0) from the optical axis; models without one measure from
the optical axis. Oracles:

* the angle between the fixation direction and the optical axis: 5° (exact rotation, 1e-12°);
* where the fixation ray lands (the fovea): the paraxial y-nu chief ray (`paraxial.matrix_to_surface`,
  no real ray) at slope −tan 5° through the iris centre 0.5 mm nasal, carried to the retina's
  vertex plane: −1.4499 mm (temporal); the exact trace lands at −1.4426 mm on the curved retina.
  Tolerance 2 % (the 5° ray is not paraxial and the retina's sag there is 0.09 mm).
"""

import dataclasses
import json
import math

import pytest

from vissim.cli import main
from vissim.optics.eyes.models import escudero_sanz_1999, liou_brennan_1997
from vissim.optics.eyes.paraxial import matrix_to_surface
from vissim.optics.eyes.traced_wavefront import field_axis, field_from_optical_axis_deg, trace_eye_wavefront

FOVEA_TOL = 0.02


def test_fixation_is_five_degrees_nasal_of_the_optical_axis():
    eye = liou_brennan_1997()
    assert field_axis(eye) == "visual axis"
    x, y = field_from_optical_axis_deg(eye, (0.0, 0.0))
    assert (x, y) == pytest.approx((5.0, 0.0), abs=1e-12)
    x, _ = field_from_optical_axis_deg(eye, (-5.0, 0.0))  # 5° temporal of fixation: on the optical axis
    assert x == pytest.approx(0.0, abs=1e-12)


def test_a_model_without_a_visual_axis_keeps_its_field_angles():
    eye = escudero_sanz_1999()
    assert field_axis(eye) == "optical axis"
    assert field_from_optical_axis_deg(eye, (12.0, -7.0)) == pytest.approx((12.0, -7.0), abs=1e-12)


def test_the_fixation_ray_lands_temporally_where_the_paraxial_chief_ray_does():
    eye = liou_brennan_1997()
    wavefront = trace_eye_wavefront(eye, 555.0, (0.0, 0.0), pupil_mm=1.0, samples=17)
    slope = -math.tan(math.radians(5.0))  # the beam travels towards -x: from a nasal (+x) field point
    to_iris = matrix_to_surface(eye, eye.stop_index, 555.0)
    to_retina = matrix_to_surface(eye, len(eye.surfaces) - 1, 555.0)
    height = (eye.stop_decentre_nasal_mm - to_iris[0, 1] * slope) / to_iris[0, 0]
    expected_x = (to_retina @ [height, slope])[0]
    assert wavefront.field_axis == "visual axis"
    assert wavefront.image_point_mm[0] < -1.0  # temporal retina
    assert wavefront.image_point_mm[0] == pytest.approx(expected_x, rel=FOVEA_TOL)
    assert wavefront.image_point_mm[1] == pytest.approx(0.0, abs=1e-12)


def test_the_same_eye_without_its_visual_axis_is_traced_along_its_optical_axis():
    eye = liou_brennan_1997()
    along_optical = trace_eye_wavefront(dataclasses.replace(eye, visual_axis_deg=0.0), 555.0, (5.0, 0.0),
                                        pupil_mm=1.0, samples=17)
    at_fixation = trace_eye_wavefront(eye, 555.0, (0.0, 0.0), pupil_mm=1.0, samples=17)
    assert at_fixation.image_point_mm == pytest.approx(along_optical.image_point_mm, abs=1e-12)


def test_the_record_names_the_axis_the_field_is_from(capsys):
    assert main(["eye", "--eye-model", "liou-brennan-1997", "--pupil-mm", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["field_axis"] == "visual axis"
    assert main(["eye", "--eye-model", "navarro-1985", "--pupil-mm", "2"]) == 0
    assert "(0, 0) deg from the optical axis" in capsys.readouterr().out
