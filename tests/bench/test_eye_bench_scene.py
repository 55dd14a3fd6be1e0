"""The eye bench (`vissim.bench.eye`): its own scene dict, built directly, and nothing of the DSLR bench.

Expected values: the holder's rule (`vissim.bench.lenses.holder.lens_clear_aperture_mm`) for a beam
1.2 x the eye's pupil; the lens's back vertex at the spectacle vertex; the chart at its distance.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from vissim.bench.eye.bench import EyeBench
from vissim.bench.eye.scene import eye_scene
from vissim.bench.eye.sensor_eyes import sensor_eye
from vissim.bench.lenses.holder import LENS_GAP_MM, lens_clear_aperture_mm
from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import DEFAULT_EYE_LIGHT_NM
from vissim.optics.eyes.eye import build_eye
from vissim.optics.rx.trial_lens import TrialLens

PACKAGE = Path(__file__).resolve().parents[2] / "vissim"


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


def bench(**changes) -> EyeBench:
    values = dict(eye=build_eye("navarro-1985", pupil_diameter_mm=3.0), lenses=(TrialLens(2.0),), size_px=(16, 24))
    return EyeBench(**{**values, **changes})


def test_the_scene_holds_the_eye_sensor_handed_the_eye_the_chart_and_the_lens():
    b = bench(field_deg=(5.0, 0.0))
    scene = eye_scene(b, spp=4, seed=3)
    sensor = scene["camera"]
    assert sensor["type"] == "vissim_schematic_eye" and sensor_eye(sensor["eye_key"]) is b.eye
    assert sensor["sampler"] == {"type": "independent", "sample_count": 4, "seed": 3}
    assert (sensor["film"]["height"], sensor["film"]["width"]) == (16, 24)
    assert sensor["field_x_deg"] == 5.0 and sensor["wavelength_nm"] == DEFAULT_EYE_LIGHT_NM  # the one default light
    assert scene["chart"]["to_world"][2][3] == 6000.0
    assert scene["lens_0"]["to_world"][2][3] == b.vertex_mm
    assert scene["lens_0"]["bsdf"]["wavelength_nm"] == DEFAULT_EYE_LIGHT_NM  # the glass in the same light
    assert "thinlens" not in repr(scene)


def test_photopic_light_makes_the_lens_dispersive_at_each_paths_hero_wavelength():
    lens = eye_scene(bench(spectrum="photopic"), spp=1, seed=0)["lens_0"]["bsdf"]
    assert lens["dispersion"] == "crown" and lens["sensor_terminates_secondary"] and "wavelength_nm" not in lens


def test_the_lens_is_sized_by_the_holders_rule_for_the_eyes_beam_and_the_widest_direction():
    b = bench(field_deg=(10.0, 0.0), arcmin_per_px=2.0)
    half_deg = math.hypot(10.0 + 0.5 * 24 * 2.0 / 60.0, 0.5 * 16 * 2.0 / 60.0)
    assert b.clear_aperture_mm == lens_clear_aperture_mm(1.2 * 3.0, math.radians(half_deg), b.vertex_mm, LENS_GAP_MM)
    assert bench(field_deg=(20.0, 0.0)).clear_aperture_mm > b.clear_aperture_mm


def test_the_chart_texture_covers_the_image_and_the_lens_blur():
    plain, blurred = bench(lenses=()), bench(lenses=(TrialLens(4.0),))
    rows, cols = plain.chart_half_arcmin
    step = plain.arcmin_per_px
    assert rows >= 0.5 * 16 * step and cols >= 0.5 * 24 * step  # the field, in arcmin
    assert blurred.chart_half_arcmin[0] > rows  # + 4 D over a 3 mm pupil: about 41 arcmin of blur


@pytest.mark.parametrize("changes, words", [
    ({"spectrum": "photopic", "wavelength_nm": 550.0}, "not both"),
    ({"lenses": (TrialLens(1.0),) * 4}, "holder takes up to"),
    ({"field_deg": (80.0, 0.0)}, "field angle"),
    ({"eye": "navarro-1985"}, "Eye"),
])
def test_a_bad_bench_is_refused_naming_what_is_wrong(changes, words):
    with pytest.raises((VissimInputError, TypeError), match=words):
        bench(**changes)


def test_the_eye_bench_borrows_nothing_from_the_dslr_bench():
    """Neither the bench, its render nor its campaign imports the DSLR bench: a change there leaves eye renders."""
    paths = [*sorted((PACKAGE / "bench" / "eye").glob("*.py")), PACKAGE / "render" / "eye_render.py",
             *sorted((PACKAGE / "validation" / "eye").glob("*.py"))]
    found = []
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text())):
            names = [node.module or ""] if isinstance(node, ast.ImportFrom) else \
                [a.name for a in node.names] if isinstance(node, ast.Import) else []
            found += [f"{path.name}: {n}" for n in names if n.startswith("vissim.bench.dslr")]
    assert found == []
