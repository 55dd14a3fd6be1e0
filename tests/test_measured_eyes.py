"""Measured human eyes (Jaeken & Artal 2012, Polans et al. 2015) as eyes.

Oracles: the raw package files read here with numpy (the field rule x = -data horizontal, y = +data vertical
written again in this file), Zernike polynomials written here from OSA's definition (Thibos et al. 2002, JOSA A
19:2329; ANSI Z80.28), an independent least-squares refit on a Cartesian grid, the optic disc's place in the
visual field (the blind spot lies about 15 deg temporal of fixation: Rohrschneider 2004, IOVS 45:3257) and the base
eye's own traced coma and chromatic defocus.
"""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.measured import datasets
from vissim.optics.eyes.measured.datasets import load_dataset
from vissim.optics.eyes.measured.measured_eye import BASE_EYE_MODEL, DEFOCUS_WAVELENGTH_NM, parse_measured_eye
from vissim.optics.eyes.psf_wavefront import eye_wavefront

RAW = {name: dict(np.load(datasets.DATA_DIR / f"{name}.npz")) for name in datasets.DATASET_NAMES}


def osa_nm(j: int) -> tuple[int, int]:
    n = math.ceil((-3 + math.sqrt(9 + 8 * j)) / 2)
    return n, 2 * j - n * (n + 2)


def raw_um(name: str, subject: int, eye: str, x_deg: float, y_deg: float = 0.0) -> dict:
    """{(n, m): µm} of the raw file at vissim field (x, y), j >= 3, by the field rule written here."""
    raw = RAW[name]
    row = list(raw["subject"]).index(subject)
    if name == "jaeken-artal-2012":
        values = raw["zernike_um"][row, list(raw["eye"]).index(eye), list(raw["field_deg"]).index(-x_deg)]
    else:
        values = raw["zernike_um"][row, list(raw["vertical_deg"]).index(y_deg), list(raw["horizontal_deg"]).index(-x_deg)]
    return {osa_nm(int(j)): float(v) for j, v in zip(raw["osa_j"], values) if j >= 3}


def eye_json(capsys, name: str, *args: str) -> dict:
    assert main(["eye", "--eye-model", name, "--json", *args]) == 0
    return json.loads(capsys.readouterr().out)


def terms(record: dict) -> dict:
    return {tuple(int(v) for v in key.split(",")): value for key, value in record["zernike_um"].items()}


# -- the files ---------------------------------------------------------------------------------------


def test_the_shipped_files_load_with_their_shapes():
    jaeken, polans = load_dataset("jaeken-artal-2012"), load_dataset("polans-2015")
    assert jaeken.zernike_um.shape == (130, 2, 1, 81, 21) and jaeken.pupil_mm == 4.0
    assert polans.zernike_um.shape == (10, 1, 11, 81, 21) and polans.pupil_mm == 4.0
    assert jaeken.measured_j == tuple(range(15)) and polans.measured_j == tuple(range(3, 21))
    assert (datasets.DATA_DIR / "LICENSE-isetbio.txt").read_text(encoding="utf-8").startswith("MIT")


def test_a_changed_file_is_refused(tmp_path, monkeypatch):
    for name in datasets.DATASET_NAMES:
        shutil.copy(datasets.DATA_DIR / f"{name}.npz", tmp_path)
    damaged = bytearray((tmp_path / "polans-2015.npz").read_bytes())
    damaged[-100] ^= 1
    (tmp_path / "polans-2015.npz").write_bytes(bytes(damaged))
    monkeypatch.setattr(datasets, "DATA_DIR", tmp_path)
    with pytest.raises(VissimInputError, match="sha256 .* is not the shipped file's"):
        datasets._verified_arrays("polans-2015")
    assert datasets._verified_arrays("jaeken-artal-2012")["zernike_um"].shape == (130, 2, 81, 15)


# -- the field rule -------------------------------------------------------------------------------


def test_the_optic_disc_lies_in_each_eyes_temporal_field():
    # Right eye: temporal field = the observer's right = the examiner's left = vissim x < 0; left eye: x > 0.
    data = load_dataset("jaeken-artal-2012")
    central = np.abs(data.x_deg) <= 20
    for column, eye, sign in ((0, "right", -1), (1, "left", +1)):
        assert data.eyes[column] == eye
        missing = np.isnan(data.zernike_um[:, column, 0, :, 4]).mean(axis=0)  # share of subjects, per field
        gap = data.x_deg[central][np.argmax(missing[central])]
        mirrored = missing[data.x_deg == -gap][0]
        assert sign * gap > 10 and missing[central].max() > 3 * mirrored, (eye, gap, mirrored)
    # Polans's file fills its disc: there the coefficients of most subjects are the roughest of the central
    # horizontal meridian (median over subjects of the second difference along it), read raw.
    raw = RAW["polans-2015"]
    row = raw["zernike_um"][:, list(raw["vertical_deg"]).index(0.0)]  # subject, horizontal (file's order), j
    roughness = np.median(np.abs(row[:, 2:] - 2 * row[:, 1:-1] + row[:, :-2]).sum(axis=2), axis=0)
    h = raw["horizontal_deg"][1:-1]
    rough_x = -h[np.abs(h) <= 25][np.argmax(roughness[np.abs(h) <= 25])]
    assert datasets.OPTIC_DISC_X_DEG[0] <= rough_x <= datasets.OPTIC_DISC_X_DEG[1] < 0


def test_coma_grows_with_field_as_in_the_base_eye():
    # Horizontal coma (3,1) against x, vertical coma (3,-1) against y: the population's slopes have the base
    # eye's signs (Navarro: about -0.012 µm/deg at 4 mm, traced here).
    base = build_eye(BASE_EYE_MODEL, pupil_diameter_mm=4.0)
    slope_x = (eye_wavefront(base, field_deg=(10, 0)).coefficients_um[(3, 1)]
               - eye_wavefront(base, field_deg=(-10, 0)).coefficients_um[(3, 1)]) / 20
    slope_y = (eye_wavefront(base, field_deg=(0, 10)).coefficients_um[(3, -1)]
               - eye_wavefront(base, field_deg=(0, -10)).coefficients_um[(3, -1)]) / 20
    assert slope_x < -0.005 and slope_y < -0.005
    jaeken = load_dataset("jaeken-artal-2012")
    x = jaeken.x_deg
    for column in (0, 1):
        coma = np.nanmedian(jaeken.zernike_um[:, column, 0, :, 8], axis=0)
        near = np.abs(x) <= 25
        assert np.polyfit(x[near & ~np.isnan(coma)], coma[near & ~np.isnan(coma)], 1)[0] < 0
    polans = load_dataset("polans-2015")
    coma = np.median(polans.zernike_um[:, 0, :, int(np.flatnonzero(polans.x_deg == 0.0)[0]), 7], axis=0)
    assert np.polyfit(polans.y_deg, coma, 1)[0] < 0
    coma = np.median(polans.zernike_um[:, 0, int(np.flatnonzero(polans.y_deg == 0.0)[0]), :, 8], axis=0)
    near = (np.abs(polans.x_deg) <= 25) & ~np.isnan(coma)
    assert np.polyfit(polans.x_deg[near], coma[near], 1)[0] < 0


# -- the eye's wavefront is the data's ----------------------------------------------------------------


@pytest.mark.parametrize("name, field", [("jaeken-artal-2012:17:right", (10.0, 0.0)),
                                         ("jaeken-artal-2012:17:left", (-20.0, 0.0)),
                                         ("jaeken-artal-2012:120:left", (0.0, 0.0)),
                                         ("polans-2015:3", (5.0, -10.0))])
def test_the_json_zernikes_are_the_data_at_a_measured_field(capsys, name, field):
    measured = parse_measured_eye(name)
    data = raw_um(measured.dataset, measured.subject, measured.eye, *field)
    field_arg = f"--field-deg={field[0]:g},{field[1]:g}"
    record = eye_json(capsys, name, "--pupil-mm", "4", field_arg)  # the model's reference wavelength
    assert record["model"] == name and record["base_model"] == BASE_EYE_MODEL
    got = terms(record)
    for key, value in data.items():
        if key != (2, 0):
            assert got.get(key, 0.0) == pytest.approx(value, abs=1e-12), key
    assert got[(2, 0)] != pytest.approx(data[(2, 0)], abs=1e-3)  # other light: the chromatic shift
    at_defocus = terms(eye_json(capsys, name, "--pupil-mm", "4", field_arg,
                                "--wavelength-nm", f"{DEFOCUS_WAVELENGTH_NM[measured.dataset]:g}"))
    assert at_defocus[(2, 0)] == pytest.approx(data[(2, 0)], abs=1e-12)


def test_defocus_in_other_light_moves_by_the_base_eyes_traced_difference():
    field = (20.0, 0.0)
    measured = build_eye("jaeken-artal-2012:40:right", pupil_diameter_mm=3.0)
    base = build_eye(BASE_EYE_MODEL, pupil_diameter_mm=3.0)
    for nm in (450.0, 555.0, 650.0):
        shift = (eye_wavefront(measured, wavelength_nm=nm, field_deg=field).coefficients_um[(2, 0)]
                 - eye_wavefront(measured, wavelength_nm=780.0, field_deg=field).coefficients_um[(2, 0)])
        traced = (eye_wavefront(base, wavelength_nm=nm, field_deg=field).coefficients_um[(2, 0)]
                  - eye_wavefront(base, wavelength_nm=780.0, field_deg=field).coefficients_um[(2, 0)])
        assert shift == pytest.approx(traced, abs=1e-9)
        assert shift > 0.1  # shorter light focuses in front: more myopic, positive (2,0)


# -- smaller pupils: an independent refit ------------------------------------------------------------


def zernike_cartesian(n: int, m: int, rho: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """OSA's normalised Zernike polynomial, written from its definition (Thibos et al. 2002)."""
    radial = sum((-1) ** s * math.factorial(n - s)
                 / (math.factorial(s) * math.factorial((n + abs(m)) // 2 - s) * math.factorial((n - abs(m)) // 2 - s))
                 * rho ** (n - 2 * s) for s in range((n - abs(m)) // 2 + 1))
    if m == 0:
        return math.sqrt(n + 1) * radial
    angular = np.cos(m * theta) if m > 0 else np.sin(-m * theta)
    return math.sqrt(2 * (n + 1)) * radial * angular


@pytest.mark.parametrize("name, field, pupil", [("jaeken-artal-2012:17:right", (10.0, 0.0), 3.0),
                                                ("polans-2015:7", (-30.0, 15.0), 2.5)])
def test_a_smaller_pupil_equals_a_least_squares_refit(name, field, pupil):
    measured = parse_measured_eye(name)
    data = raw_um(measured.dataset, measured.subject, measured.eye, *field)
    keys = [osa_nm(j) for j in range(21)]
    axis = np.linspace(-1, 1, 161)
    x, y = np.meshgrid(axis, axis)
    inside = x ** 2 + y ** 2 <= 1
    rho, theta = np.hypot(x, y)[inside], np.arctan2(y, x)[inside]
    scale = pupil / 4.0  # the small pupil's points in the data's unit disc
    opd = sum(v * zernike_cartesian(n, m, rho * scale, theta) for (n, m), v in data.items())
    basis = np.stack([zernike_cartesian(n, m, rho, theta) for n, m in keys], axis=1)
    refit = dict(zip(keys, np.linalg.lstsq(basis, opd, rcond=None)[0]))
    eye = build_eye(name, pupil_diameter_mm=pupil)
    got = eye_wavefront(eye, wavelength_nm=DEFOCUS_WAVELENGTH_NM[measured.dataset], field_deg=field).coefficients_um
    for key in keys[3:]:
        assert got.get(key, 0.0) == pytest.approx(refit[key], abs=1e-6), key


# -- between and outside the measured fields ----------------------------------------------------------


def test_between_measured_fields_the_coefficients_are_interpolated_linearly():
    jaeken = load_dataset("jaeken-artal-2012")
    mid = jaeken.at_field(17, "right", (10.25, 0.0))
    low, high = jaeken.at_field(17, "right", (10.0, 0.0)), jaeken.at_field(17, "right", (11.0, 0.0))
    np.testing.assert_allclose(mid, 0.75 * low + 0.25 * high, rtol=0, atol=1e-15)
    polans = load_dataset("polans-2015")
    corners = [polans.at_field(2, "right", (x, y)) for x in (20.0, 21.0) for y in (5.0, 10.0)]
    np.testing.assert_allclose(polans.at_field(2, "right", (20.5, 7.5)), np.mean(corners, axis=0), atol=1e-15)


@pytest.mark.parametrize("name, kwargs, field, words", [
    ("jaeken-artal-2012:17:right", {}, (-15.0, 0.0), "no measurement at field -15,0 deg"),
    ("jaeken-artal-2012:17:left", {}, (16.0, 0.0), "measured nearby: "),
    ("polans-2015:1", {}, (-14.0, 0.0), "no measurement at field"),
    ("jaeken-artal-2012:17:right", {}, (41.0, 0.0), "measured at field x -40 to 40 deg, got 41 deg"),
    ("jaeken-artal-2012:17:right", {}, (0.0, 1.0), "measured at field y 0 deg only, got 1 deg"),
    ("polans-2015:1", {}, (0.0, 26.0), "measured at field y -25 to 25 deg, got 26 deg"),
])
def test_fields_without_a_measurement_are_refused(name, kwargs, field, words):
    eye = build_eye(name, pupil_diameter_mm=3.0, **kwargs)
    with pytest.raises(VissimInputError, match=words):
        eye_wavefront(eye, field_deg=field)


@pytest.mark.parametrize("name, kwargs, words", [
    ("jaeken-artal-2012:17:right", {"pupil_diameter_mm": 4.5}, "measured over a 4 mm pupil"),
    ("jaeken-artal-2012:17:right", {"pupil_diameter_mm": 3.0, "rx": "-1.00"}, "cannot be given a prescription"),
    ("jaeken-artal-2012:17:right", {"accommodation_diopters": 2.0}, "its accommodation is 0 D only"),
    ("jaeken-artal-2012:17:right", {"surfaces": {"cornea front": {"radius_mm": 7.5}}}, "surfaces cannot change"),
    ("jaeken-artal-2012:131:right", {}, "has subjects 1-130, got 131"),
    ("jaeken-artal-2012:17:middle", {}, "has right and left eyes, got 'middle'"),
    ("jaeken-artal-2012:17", {}, "say which eye"),
    ("polans-2015:11", {}, "has subjects 1-10, got 11"),
    ("polans-2015:x", {}, "subject is a whole number"),
])
def test_measured_eyes_refuse_what_was_not_measured(name, kwargs, words):
    with pytest.raises(VissimInputError, match=words):
        build_eye(name, **kwargs)


def test_the_command_line_refuses_in_one_line(capsys):
    assert main(["eye", "--eye-model", "jaeken-artal-2012:17:right", "--field-deg=-15,0", "--pupil-mm", "4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vissim: error:") and "-14,0 deg" in err[0]
    assert main(["eye", "--eye-model", "polans-2015:99"]) == 2
    assert "has subjects 1-10, got 99" in capsys.readouterr().err


def test_a_plano_prescription_is_the_eye_as_measured(tmp_path):
    assert build_eye("polans-2015:4", pupil_diameter_mm=3.0, rx="plano").rx is None
    from vissim.imageio import write_image
    from vissim.provenance import make_provenance
    image, depth = tmp_path / "in.exr", tmp_path / "depth.exr"
    write_image(image, np.full((32, 32), 0.5, np.float32), provenance=make_provenance(command="t", arcmin_per_px=1.0))
    write_image(depth, np.full((32, 32), 2.0, np.float32), provenance=make_provenance(command="t", arcmin_per_px=1.0))
    assert main(["blur-depth", str(image), str(depth), "-o", str(tmp_path / "out.exr"), "--rx", "0",
                 "--pupil-mm", "3", "--eye-model", "polans-2015:4", "--field-deg", "10,5"]) == 0


def test_the_eye_bench_renders_a_measured_eye_through_its_phase_plane_and_no_lens():
    from vissim.bench.eye.bench import EyeBench
    from vissim.bench.eye.scene import eye_sensor
    from vissim.bench.eye.sensor_eyes import sensor_eye, sensor_phase
    from vissim.optics.rx.trial_lens import TrialLens

    eye = build_eye("polans-2015:1", pupil_diameter_mm=3.0)
    with pytest.raises(VissimInputError, match="measured eye: lenses"):
        EyeBench(eye, lenses=(TrialLens(1.0),))
    bench = EyeBench(eye, field_deg=(10.0, 0.0), wavelength_nm=550.0)
    key = eye_sensor(bench, 4, 1)["eye_key"]
    assert sensor_eye(key) is eye and sensor_phase(key) is bench.phase_plane is bench.measured_phase.plane
    record = bench.as_json()["phase_plane"]
    assert record["field_deg"] == [10.0, 0.0] and record["wavelength_nm"] == 550.0
    assert EyeBench(build_eye("navarro-1985", pupil_diameter_mm=3.0)).phase_plane is None


# -- the data's pupil is normal to the measuring beam -------------------------------------------------------


def test_an_oblique_measured_eyes_refraction_is_the_datas_own(capsys):
    # The data are over the plane normal to the beam, so no oblique stretch applies: J0, J45 and M are the
    # textbook ones of the coefficients (Thibos et al. 2004: M = -4√3 c20 / r², J0 = -2√6 c22 / r²,
    # J45 = -2√6 c2-2 / r²), carried from the pupil to the corneal vertex (3 mm / cos 30°: under 4 % at 4 D
    # and less; a stretch of the pupil would make J0 1/cos² 30° = 1.33 times larger).
    data = raw_um("jaeken-artal-2012", 17, "right", 30.0)
    record = eye_json(capsys, "jaeken-artal-2012:17:right", "--pupil-mm", "4", "--field-deg", "30,0",
                      "--wavelength-nm", "780")
    paraxial_free = record["refraction"]["minimum_rms"]
    r2 = 2.0 ** 2
    expected = {"M": -4 * math.sqrt(3) * data[(2, 0)] / r2, "J0": -2 * math.sqrt(6) * data[(2, 2)] / r2,
                "J45": -2 * math.sqrt(6) * data[(2, -2)] / r2}
    for key, value in expected.items():
        assert paraxial_free[key] == pytest.approx(value, rel=0.04, abs=0.02), key
    assert abs(expected["J0"]) > 1.0


def test_slopes_over_the_beams_plane_go_to_visual_angle_by_the_rotation_they_are():
    # Turning the beam by δ within its own normal plane moves field x by δ and field y by δ / cos θ (vissim's
    # field angles are atan(x/z), atan(y/z)); a horizontal field of θ: diag(1, 1 / cos θ).
    from vissim.optics.eyes.measured.measured_eye import beam_field_map
    from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
    base = build_eye(BASE_EYE_MODEL, pupil_diameter_mm=4.0)
    for theta in (10.0, 30.0):
        trace = trace_eye_wavefront(base.optics, 555.0, (theta, 0.0), pupil_mm=4.0)
        np.testing.assert_allclose(beam_field_map(trace), np.diag([1.0, 1.0 / math.cos(math.radians(theta))]),
                                   atol=1e-9)


def test_the_json_says_which_plane_the_zernikes_are_over(capsys):
    measured = eye_json(capsys, "polans-2015:2", "--pupil-mm", "3", "--field-deg", "20,0")
    schematic = eye_json(capsys, "navarro-1985", "--pupil-mm", "3", "--field-deg", "20,0")
    assert "normal to the chief ray" in measured["zernike_pupil"] and schematic["zernike_pupil"] == "entrance pupil"


@pytest.mark.parametrize("field_deg", [(0.0, 0.0), (-20.0, 0.0), (-30.0, 0.0)])
def test_the_lights_vergence_over_a_measured_eyes_beam_pupil_is_a_sphere(field_deg):
    """A measured front lies in the plane normal to the beam, so an object's vergence V adds a plain sphere
    there, at every field (a traced front, over the entrance pupil's plane, sees it stretched off axis). Oracle:
    the difference is that of an eye whose correcting lens is -V: -V DS, no cylinder (from the second order)."""
    from vissim.optics.eyes.psf_wavefront import eye_wavefront
    from vissim.optics.pupil.wavefront import Wavefront

    eye = build_eye("jaeken-artal-2012:92:right", pupil_diameter_mm=4.0)
    near = eye_wavefront(eye, wavelength_nm=550.0, field_deg=field_deg, vergence_diopters=-3.0).coefficients_um
    far = eye_wavefront(eye, wavelength_nm=550.0, field_deg=field_deg).coefficients_um
    added = Wavefront({k: near.get(k, 0.0) - far.get(k, 0.0) for k in ((2, -2), (2, 0), (2, 2))}, 4.0, 550.0)
    rx = added.to_prescription()
    assert rx.sphere_diopters + 0.5 * rx.cylinder_diopters == pytest.approx(3.0, abs=1e-9)
    assert abs(rx.cylinder_diopters) < 1e-9
