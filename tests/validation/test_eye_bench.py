"""The eye bench (kind "eye"): its campaign file, its ray PSF, and a toy campaign through `validate`.

Oracles: the ray PSF of an eye defocused by a trial lens is a blur disc of angular diameter
pupil x vergence error (geometric optics of a thin defocus, the reduced eye's first-order
law; the schematic eye's spherical aberration and the lens's thickness move it by a few %);
the campaign's geometric self-check is an independent trace of the rendered scene and must land
at the render's noise floor (+3 dB for a noise-free match, >= +2 dB required).  An ametropic eye (``rx``, its
spectacle prescription at the vertex distance) corrected by that very lens at that distance has no defocus
left: a thin lens P at d sends light from infinity to the far point P / (1 - dP) at the cornea, the vergence
the eye focuses (the eye's refraction at the cornea, by the same arithmetic).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.validation.engine.validate import validate
from vissim.optics.rx.prescription import Prescription
from vissim.optics.eyes.retina_map import ray_psf
from vissim.validation.eye.report import configuration_label
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
pupil_diameter_mm = 3.0

[[sweep]]
name = "lens"
lens = [1.0]
field_deg = 0.0
"""


def test_the_campaign_file_is_checked():
    doc = {"item": [{"name": "a", "lens": 1.0, "field_deg": 10.0}]}
    with pytest.raises(VissimInputError, match=r"item\[0\].*lens"):
        read_campaign(doc, {"kind": "eye"}, "eye.toml")
    with pytest.raises(VissimInputError, match="pupil"):
        read_campaign({"item": [{"pupil_diameter_mm": 10.5}]}, {"kind": "eye"}, "eye.toml")  # an eye's pupil: 1-10 mm
    with pytest.raises(VissimInputError, match=r"item\[0\].*accommodation"):  # Arizona's range is 0-6 D
        read_campaign({"item": [{"eye_model": "arizona", "accommodation_diopters": 7.0}]}, {"kind": "eye"}, "eye.toml")
    with pytest.raises(VissimInputError, match="colour"):
        read_campaign({"item": [{"colour": 1}]}, {"kind": "eye"}, "eye.toml")
    settings, configurations = read_campaign({"sweep": [{"name": "p", "pupil_diameter_mm": [3.0, 6.0], "spectrum": "photopic"}]},
                                             {"kind": "eye", "spp": 8}, "eye.toml")
    assert settings.spp == 8 and [c.pupil_mm for c in configurations] == [3.0, 6.0]
    assert {c.spectrum for c in configurations} == {"photopic"}


def test_an_item_s_rx_is_checked_and_kept_as_its_prescription():
    settings, configurations = read_campaign(
        {"item": [{"name": "a", "prescription": -3}, {"name": "b", "prescription": "-2 -1 x 90"}, {"name": "c"}],
         "sweep": [{"name": "s", "prescription": ["-1.00", 2.5]}]}, {"kind": "eye", "vertex_distance_mm": 14.0}, "eye.toml")
    assert [c.rx for c in configurations] == [Prescription(-3.0, 0.0, 180.0), Prescription(-2.0, -1.0, 90.0), None,
                                              Prescription(-1.0, 0.0, 180.0), Prescription(2.5, 0.0, 180.0)]
    assert configurations[0].vertex_mm == 14.0 and "rx" not in configurations[2].key_inputs()
    assert configurations[0].key_inputs() != configurations[2].key_inputs()
    # not a prescription; not text; +90 D: beyond the trial lenses' range (the eye's own check)
    for bad, words in (("abc", "'abc'"), (True, "True"), ("+90", r"\+90\.00 DS an eye is made to need must be within -30 to 30 dioptres")):
        with pytest.raises(VissimInputError, match=rf"eye\.toml: item\[0\]\S*: .*{words}") as caught:
            read_campaign({"item": [{"prescription": bad}]}, {"kind": "eye", "vertex_distance_mm": 14.0}, "eye.toml")
        assert "\n" not in str(caught.value)


def test_an_item_s_rx_is_the_number_given_not_its_text():
    """0.125 D and an axis of 90.5 deg (off the clinical 0.01 D / whole-degree grid) are the eye's prescription exactly;
    the item's key and record hold the numbers, and the report's label writes them in full."""
    _, (eighth, half_degree) = read_campaign({"item": [{"name": "a", "prescription": 0.125}, {"name": "b", "prescription": "-2 -1 x 90.5"}]},
                                             {"kind": "eye"}, "eye.toml")
    assert eighth.eye().rx == Prescription(0.125, 0.0, 180.0) and half_degree.eye().rx.axis_deg == 90.5
    assert eighth.key_inputs()["rx"] == {"sphere_diopters": 0.125, "cylinder_diopters": 0.0, "axis_deg": 180.0}
    assert "eye Rx +0.125 DS (at a 12 mm spectacle plane)" in configuration_label(eighth.as_json())
    assert "x 90.5" in configuration_label(half_degree.as_json())


def _myope_scenes(chart_distance_m: float):
    """The -3 D myope (spectacle Rx at 12 mm) without and with its -3 D spectacles, and the emmetrope, as
    `EyeScene`s (the lens as the render meshes it; the chart at ``chart_distance_m``)."""
    import dataclasses

    from vissim.validation.eye.renders import build_bench
    from vissim.validation.eye.simulate import EyeScene

    settings, configurations = read_campaign(
        {"item": [{"name": "m", "prescription": -3.0}, {"name": "ms", "prescription": -3.0, "lens": -3.0}, {"name": "e"}]},
        {"kind": "eye", "vertex_distance_mm": 12.0}, "eye.toml")
    moved = [dataclasses.replace(c, chart_distance_m=chart_distance_m) for c in configurations]
    return [EyeScene(build_bench(c, settings).bench, settings.oversample, settings.rays_across) for c in moved]


def test_a_myope_in_its_spectacles_has_no_defocus_left():
    """Chart at 1000 km (1e-6 D): the reduced eye's defocus (`ViewingSetup.eye`: D = -Rx + A + V, myopic > 0).
    Oracle by hand: the -3 D myope's refraction at the cornea is P / (1 - dP) = -3 / 1.036 = -2.895753 D, so
    uncorrected D = +2.895753; its -3 D lens 12 mm in front brings light from infinity to the same vergence at the
    cornea, D = 0.  The thick lens (1 mm, its back vertex at 12 mm, back-vertex power -3 D) does it exactly; the
    chart's 1e-6 D is left.  The thesis setup (the lens's P / (1 - dP), the chart at infinity) likewise, at 6 m."""
    myope, corrected, emmetrope = _myope_scenes(1e6)
    at_cornea = -3.0 / (1.0 - 0.012 * -3.0)
    assert np.asarray(myope.view.reduced_setup(myope.light.focus_nm)[0].defocus_matrix_diopters) == pytest.approx(
        -at_cornea * np.eye(2) - 1e-6 * np.eye(2), abs=1e-9)
    assert np.asarray(corrected.view.reduced_setup(corrected.light.focus_nm)[0].defocus_matrix_diopters) == pytest.approx(np.zeros((2, 2)), abs=2e-6)
    assert np.asarray(emmetrope.view.reduced_setup(emmetrope.light.focus_nm)[0].defocus_matrix_diopters) == pytest.approx(np.zeros((2, 2)), abs=2e-6)
    myope, corrected, _ = _myope_scenes(6.0)
    assert np.asarray(corrected.view.thesis_setup(corrected.light.focus_nm).defocus_matrix_diopters) == pytest.approx(np.zeros((2, 2)), abs=1e-12)
    assert np.asarray(myope.view.thesis_setup(myope.light.focus_nm).defocus_matrix_diopters) == pytest.approx(-at_cornea * np.eye(2), abs=1e-12)


def test_the_schematic_eye_is_the_myopes_own_long_eye_seeing_the_lights_vergence_at_its_entrance_pupil():
    """The schematic simulations trace the item's one `Eye` (the -3 D myope's longer eye) and add only the light's
    vergence at its entrance pupil, ``depth`` behind the cornea (thin-lens arithmetic): the chart at 6 m gives
    -1 / (6 m + depth) with or without the myopia; in its -3 D spectacles the chart's vergence through the lens,
    -1 / (6 m - 12 mm) - 3 D, carried 12 mm + depth on (1 mm thick as meshed: within 1e-3 D). The eye's own
    refraction is in the eye: its traced paraxial refraction at the entrance pupil (1 mm pupil, Thibos et al. 2004;
    at the model's reference wavelength, where its Rx is written) is the spectacle Rx carried there, -3 / (1 + 3 (0.012 m + depth)), to 0.01 D."""
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye
    from vissim.optics.eyes.psf_wavefront import eye_wavefront
    from vissim.optics.eyes.refraction import paraxial_prescription

    myope, corrected, emmetrope = _myope_scenes(6.0)
    depth_m = 1e-3 * entrance_pupil_position_mm(mean_meridian_eye(myope.view.eye.optics), myope.light.focus_nm)
    chart = -1.0 / (6.0 + depth_m)
    assert myope.view.vergence_at_pupil(myope.light.focus_nm)[0] == pytest.approx(chart * np.eye(2), abs=1e-9)
    assert emmetrope.view.vergence_at_pupil(emmetrope.light.focus_nm)[0] == pytest.approx(chart * np.eye(2), abs=1e-9)
    gap_m = 0.012 + depth_m
    through_lens = -1.0 / (6.0 - 0.012) - 3.0
    at_pupil = through_lens / (1.0 - gap_m * through_lens)
    assert corrected.view.vergence_at_pupil(corrected.light.focus_nm)[0] == pytest.approx(at_pupil * np.eye(2), abs=1e-3)
    assert myope.view.eye is corrected.view.eye and str(myope.view.eye.rx) == "-3.00 DS"
    front = eye_wavefront(myope.view.eye.with_pupil(pupil_diameter_mm=1.0))  # at its reference wavelength, as its Rx is
    traced = paraxial_prescription(front.coefficients_um, 1.0).sphere_diopters
    assert traced == pytest.approx(-3.0 / (1.0 + 3.0 * gap_m), abs=0.01)


def test_a_defocused_eye_s_ray_psf_is_the_blur_disc():
    """+2 D before a relaxed Navarro eye at 6 m, 550 nm: the vergence error at the eye P / (1 - dP) - 1/6 m plus the
    eye's own myopia at 550 nm (`paraxial.refraction_diopters`: -0.175 D) ~ 2.06 D: a blur disc of 3 mm x 2.06 D =
    6.2 mrad = 21.2 arcmin, its RMS radius R / sqrt 2.  The plus lens enlarges the beam the eye's pupil takes (~4 %)
    and the eye's spherical aberration spreads the disc: within 12 %.  The traced spectacle magnification is the
    vergence-matrix one (`trial_lens_effect`) with the lens 12 mm + the eye's paraxial entrance-pupil depth in
    front of the pupil: measured 1.035153 against 1.035149, held to 1e-4."""
    from vissim.optics.eyes.eye import build_eye
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, refraction_diopters
    from vissim.optics.rx.trial_lens import TrialLens, TrialLensSetup, trial_lens_effect

    lens = TrialLens(2.0, 0.0, 180.0, refractive_index=1.523, center_thickness_mm=3.0)
    ray = ray_psf(build_eye("navarro-1985", pupil_diameter_mm=3.0), field_deg=(0.0, 0.0), chart_distance_m=6.0, lens=lens,
                  arcmin_per_px=1.0, oversample=4, rays_across=61)
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
    for words in ("Geometric self-check", "reduced eye, ray optics", "thesis method", "the eye's wavefront, wave optics",
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


MYOPE_TOY = TOY.split("[[item]]")[0].replace('name = "eye toy"', 'name = "myope toy"') + """
[[item]]
name = "myope"
pupil_diameter_mm = 3.0
prescription = -3.0

[[item]]
name = "myope in spectacles"
pupil_diameter_mm = 3.0
prescription = -3.0
lens = -3.0
"""


@pytest.mark.slow
def test_the_myope_with_and_without_its_spectacles_passes_the_self_check(tmp_path):
    """The render traces the ametropic eye (the sensor's `sensor_eye`), the self-check the same eye
    (its `Eye`), each film mapped through that eye's chief rays: the self-check sits at the noise floor."""
    import json

    path = tmp_path / "eye.toml"
    path.write_text(MYOPE_TOY)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.summary.items_total == 2 and done.summary.renders_made == 4
    assert "eye Rx -3.00 DS (at a 12 mm spectacle plane)" in (tmp_path / "run" / "tables.md").read_text()
    rows = json.loads((tmp_path / "run" / "metrics.json").read_text())["rows"]
    checks = {r["configuration"]: r["over_floor_db"] for r in rows if r["simulation"] == "traced_rays"}
    assert set(checks) == {"myope", "myope in spectacles"}
    for name, over_floor_db in checks.items():
        assert 2.0 <= over_floor_db <= 4.0, (name, over_floor_db)


ALTERED_TOY = TOY.split("[[item]]")[0].replace('name = "eye toy"', 'name = "altered toy"') + """
[[item]]
name = "spherical cornea"
pupil_diameter_mm = 4.0
surfaces."cornea front".conic = 0.0
"""


@pytest.mark.slow
def test_an_eye_with_an_altered_cornea_described_in_toml_passes_the_self_check(tmp_path):
    """A model plus overrides in the campaign file (Navarro with a spherical cornea): the render's sensor is handed
    that eye, the self-check traces it, and lands at the render's noise floor (>= +2 dB)."""
    import json

    path = tmp_path / "eye.toml"
    path.write_text(ALTERED_TOY)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.summary.items_total == 1
    rows = json.loads((tmp_path / "run" / "metrics.json").read_text())["rows"]
    check = next(r for r in rows if r["simulation"] == "traced_rays")
    assert 2.0 <= check["over_floor_db"] <= 4.0, check


MEASURED_TOY = TOY.split("[[item]]")[0].replace('name = "eye toy"', 'name = "measured toy"') + """
[[item]]
name = "subject 92 at -20 deg"
eye_model = "jaeken-artal-2012:92:right"
pupil_diameter_mm = 4.0
chart_distance_m = 0.33
field_deg = [-20.0, 0.0]
"""


@pytest.mark.slow
def test_a_measured_eye_renders_through_its_phase_plane_at_the_noise_floor(tmp_path):
    """The most aberrated Jaeken & Artal eye at -20 deg: the render's rays cross its phase plane on the way out,
    the self-check's on the way in (the numpy trace), and the two land at the render's noise floor (>= +2 dB)."""
    import json

    path = tmp_path / "eye.toml"
    path.write_text(MEASURED_TOY)
    validate(path, tmp_path / "run", show_progress=False)
    result = json.loads(next((tmp_path / "run" / "items").glob("*/result.json")).read_text())
    assert result["configuration"]["model"] == "jaeken-artal-2012:92:right"
    rows = {r["simulation"]: r["over_floor_db"] for r in result["rows"]}
    assert 2.0 <= rows["traced_rays"] <= 4.0, rows


def test_one_bench_and_one_model_eye_are_built_per_eye_campaign_item(tmp_path, monkeypatch):
    """Reading the item, building its bench and computing it (renders stood in by noise) build the bench once and
    the model eye once: the item's one `Eye` is what the simulations, the self-check and the rendered bench use."""
    import dataclasses

    from vissim.bench.eye import bench as eye_bench
    from vissim.optics.eyes import eye as eye_module
    from vissim.optics.eyes import models
    from vissim.validation.eye.item import compute_eye_item
    from vissim.validation.eye.kind import BENCH

    counts = {"model": 0, "bench": 0}
    builders = dict(models.EYE_MODELS)

    def counted(builder):
        def build(*args, **kwargs):
            counts["model"] += 1
            return builder(*args, **kwargs)
        return build

    monkeypatch.setattr(models, "EYE_MODELS", {name: counted(b) for name, b in builders.items()})
    eye_module.eye_from_fields.cache_clear()
    original_init = eye_bench.EyeBench.__post_init__

    def counted_init(self):
        counts["bench"] += 1
        original_init(self)

    monkeypatch.setattr(eye_bench.EyeBench, "__post_init__", counted_init)
    doc = {"item": [{"name": "myope in spectacles", "pupil_diameter_mm": 3.0, "prescription": -1.0, "lens": -1.0,
                     "eye_model": "escudero-sanz-1999"}]}
    settings, (configuration,) = read_campaign(doc, {"kind": "eye", "size_px": [16, 16], "rays_across": 41,
                                                     "oversample": 1}, "eye.toml")
    built = BENCH.build(configuration, settings)
    noise = np.random.default_rng(0)
    images = {f"truth_{i}": 0.5 + 0.01 * noise.standard_normal((16, 16)) for i in range(2)}
    compute_eye_item("k", configuration, settings, built, images, tmp_path, {})
    assert counts == {"model": 1, "bench": 1}
    assert dataclasses.is_dataclass(configuration) and configuration.eye() is configuration.eye()


def test_each_seeds_render_spec_carries_the_one_built_bench_with_its_chart(monkeypatch):
    """The item's renders carry the configuration's bench, built once; a seed's worker (the spec pickled, as
    a process pool sends it) prints no chart again and hands its sensor the item's `Eye`."""
    import pickle

    import vissim.charts as charts
    from vissim.bench.eye.scene import eye_scene
    from vissim.bench.eye.sensor_eyes import sensor_eye
    from vissim.validation.engine.protocol import Campaign
    from vissim.validation.eye.kind import BENCH

    settings, (configuration,) = read_campaign({"item": [{"name": "lens", "lens": 1.0, "pupil_diameter_mm": 3.0}]},
                                               {"kind": "eye", "size_px": [16, 16]}, "eye.toml")
    built = BENCH.build(configuration, settings)
    campaign = Campaign(kind="eye", name="one", description="", settings=settings, configurations=(configuration,),
                        built=(built,))
    plans, _ = BENCH.plan_items(campaign, [("k", 0)])
    specs = list(plans["k"].renders.values())
    assert [s.seed for s in specs] == list(settings.seeds) and all(s.bench is built.bench for s in specs)
    assert built.bench.eye is configuration.eye()

    def refuse(*args, **kwargs):
        raise AssertionError("a worker printed the chart again")

    sent = pickle.loads(pickle.dumps(specs[1]))
    monkeypatch.setattr(charts, "render_chart_print", refuse)
    scene = eye_scene(sent.bench, sent.spp, sent.seed)
    assert sensor_eye(scene["camera"]["eye_key"]).optics == configuration.eye().optics
    assert sent.as_json() == specs[1].as_json()
