"""Every campaign-file value, mutated (zero, negative, NaN, inf, huge, wrong type, missing), loads or gets one clean line.

The loaders are the whole of a campaign's input checking (values, physics, memory), so these
tests stop at them and render nothing.
"""

import math

import pytest
from campaign_toml import MISSING, mutate, paths, toml_document
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.validation.engine.loader import load_campaign

SINGLE_PLANE = {
    "campaign": {
        "name": "fuzz", "description": "mutated values", "f_number": 5.0, "spp": 4, "seeds": [1, 2],
        "arcmin_per_px": 1.0, "tile_px": [48, 48], "focal_length_mm": 18.0, "chart_distance_m": 0.9144,
        "vertex_distance_mm": 10.0, "wavelength_nm": 550.0, "refractive_index": 1.523, "data_range": 1.0,
        "simulations": ["wave", "geometric"], "inputs": ["render", "synthetic"], "wave_truth": True,
    },
    "item": [{"name": "plus two", "letter": "K", "logmar": 0.5, "polarity": "black-on-white",
              "lenses": [{"sphere_diopters": 2.0, "cylinder_diopters": -1.0, "axis_deg": 90}], "f_number": 5.0, "capture": "none"}],
    "sweep": [{"name": "sweep", "letter": ["N"], "logmar": [0.5], "polarity": ["white-on-black"],
               "lens": [1.0, {"cylinder_diopters": 1.0, "axis_deg": 180}], "lenses": [[0.5]], "f_number": 4.0}],
}

SCENE = """
[image]
arcmin_per_px = 1.0
size_px = [40, 80]
[eye]
prescription = "-1.00 DS"
pupil_diameter_mm = 3.0
[[panel]]
distance_m = 2.0
letters = "H"
logmar = 0.5
"""

DEPTH = {
    "campaign": {"kind": "depth", "name": "fuzz", "description": "mutated values", "spp": 4, "aux_spp": 4, "seeds": [1, 2],
                       "aux_seed": 3, "oversample": 1, "simulations": ["geometric", "wave"], "wavelength_nm": 550.0,
                       "data_range": 1.0, "margin_px": 1.0, "layer_spacing_fraction": 0.5},
    "config": [{"name": "eye", "scene": "scene.toml", "prescription": "-1.00 DS", "pupil_diameter_mm": 3.0, "accommodation_diopters": 0.5},
               {"name": "camera", "scene": "scene.toml",
                "camera": {"f_number": 5.0, "focus_distance_m": 2.0, "focal_length_mm": 18.0,
                           "vertex_distance_mm": 10.0, "lenses": [1.0]}}],
}

#: Zero, negative, tiny, huge, NaN, inf, wrong types, and names that are right for some keys.
SPECIAL = [0, -1, 1, 2, 16, 0.5, -0.5, 1e-9, 1e9, 1e300, -1e300, 10**12, 2**63 - 1, math.nan, math.inf, -math.inf,
           True, False, "", "x", "K", "wave", "render", "plano", [], [1], [1, 2], [1, 1], ["wave", "wave"], {},
           {"a": 1}, {"sphere": 1.0}, MISSING]
VALUES = st.one_of(
    st.sampled_from(SPECIAL),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.text(alphabet=st.characters(blacklist_categories=("Cs", "Cc")), max_size=4),
)
FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def mutated(data, base: dict) -> dict:
    doc = base
    for _ in range(data.draw(st.integers(1, 2), label="mutations")):
        where = data.draw(st.sampled_from(paths(doc)), label="path")
        doc = mutate(doc, where, data.draw(VALUES, label="value"))
    return doc


def load_or_one_line(load, path):
    """Load ``path``; a refusal must be one VissimInputError line naming the file."""
    try:
        return load(path)
    except VissimInputError as exc:
        message = str(exc)
        assert message.strip() and "\n" not in message, message
        assert str(path) in message, message
        return None


@FUZZ
@given(data=st.data())
def test_mutated_single_plane_campaigns_load_or_give_one_clean_line(tmp_path, data):
    path = tmp_path / "fuzz.toml"
    path.write_text(toml_document(mutated(data, SINGLE_PLANE)))
    campaign = load_or_one_line(load_campaign, path)
    if campaign is not None:
        assert campaign.configurations and all(math.isfinite(c.logmar) for c in campaign.configurations)


@FUZZ
@given(data=st.data())
def test_mutated_depth_campaigns_load_or_give_one_clean_line(tmp_path, data):
    (tmp_path / "scene.toml").write_text(SCENE)
    path = tmp_path / "fuzz.toml"
    path.write_text(toml_document(mutated(data, DEPTH)))
    campaign = load_or_one_line(load_campaign, path)
    if campaign is not None:
        assert campaign.configurations


@pytest.mark.parametrize("where", [p for p in paths(SINGLE_PLANE) if len(p) >= 2])
@pytest.mark.parametrize("value", [0, -1, math.nan, math.inf, 1e300, 10**12, "x", [1], MISSING])
def test_every_single_plane_key_at_every_bad_value(tmp_path, where, value):
    """The exhaustive grid the fuzzing samples from: each key, each kind of bad value."""
    path = tmp_path / "bad.toml"
    path.write_text(toml_document(mutate(SINGLE_PLANE, where, value)))
    load_or_one_line(load_campaign, path)


@pytest.mark.parametrize("text, fragments", [
    ('[campaign]\ntile_px = [1000000, 1000000]\n[[item]]\nletter = "K"\n', ["memory", "GiB"]),
    ('[campaign]\narcmin_per_px = 0.05\n[[item]]\nletter = "K"\nlogmar = 0.0\nlenses = [20.0]\n', ["PSF"]),
    ('[campaign]\nspp = 1000000000000\n[[item]]\nletter = "K"\n', ["campaign.spp", "samples per pixel"]),
    ('[[item]]\nletter = "K"\nlogmar = 1e300\n', ["item[0].logmar", "LogMAR"]),
    ('[[item]]\nletter = "K"\nlenses = [1e9]\n', ["item[0].lenses[0]", "dioptres"]),
    ('[campaign]\nf_number = 1e9\n[[item]]\nletter = "K"\n', ["campaign.f_number"]),
])
def test_huge_values_are_refused_before_anything_is_allocated(tmp_path, text, fragments):
    path = tmp_path / "huge.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError) as caught:
        load_campaign(path)
    assert all(f in str(caught.value) for f in fragments), str(caught.value)


@pytest.mark.parametrize("field, value, fragments", [
    ("wavelength_nm", 2200.0, ["campaign.wavelength_nm", "within 200 to 2000 nm"]),
    ("vertex_distance_mm", 201.0, ["campaign.vertex_distance_mm", "within 0 to 200 mm"]),
])
def test_single_plane_campaigns_take_the_ranges_of_checks(tmp_path, field, value, fragments):
    path = tmp_path / "range.toml"
    path.write_text(toml_document(mutate(SINGLE_PLANE, ("campaign", field), value)))
    with pytest.raises(VissimInputError) as caught:
        load_campaign(path)
    assert all(f in str(caught.value) for f in fragments), str(caught.value)


@pytest.mark.parametrize("where, value, fragments", [
    (("campaign", "wavelength_nm"), 2200.0, ["campaign.wavelength_nm", "within 200 to 2000 nm"]),
    (("config", 1, "camera", "vertex_distance_mm"), 201.0, ["vertex_distance_mm", "within 0 to 200 mm"]),
    (("config", 0, "pupil_diameter_mm"), 0.5, ["config[0].pupil_diameter_mm", "within 1 to 10 mm"]),
])
def test_depth_campaigns_take_the_ranges_of_checks(tmp_path, where, value, fragments):
    (tmp_path / "scene.toml").write_text(SCENE)
    path = tmp_path / "range.toml"
    path.write_text(toml_document(mutate(DEPTH, where, value)))
    with pytest.raises(VissimInputError) as caught:
        load_campaign(path)
    assert all(f in str(caught.value) for f in fragments), str(caught.value)


@pytest.mark.parametrize("lens, fragments", [
    ("{sphere_diopters = 1.0, prism = 2.0}", ["item[0].lenses[0]", "unknown lens field ['prism']", "axis_deg"]),
    ("{sphere = 1.0}", ["item[0].lenses[0]", "'sphere' is now 'sphere_diopters'"]),
])
def test_a_lens_table_with_an_unknown_key_is_refused_naming_it(tmp_path, lens, fragments):
    path = tmp_path / "lens.toml"
    path.write_text(f'[[item]]\nletter = "K"\nlenses = [{lens}]\n')
    with pytest.raises(VissimInputError) as caught:
        load_campaign(path)
    assert all(f in str(caught.value) for f in fragments), str(caught.value)
