"""The ATV tube without rendering: dimensions, focal placement, paraxial theory, validation.

Sources of the expected values: thesis section 5.4 (125 mm tube, 8 D lens, iPhone 5 at
326 ppi); the pixel pitch 25.4 mm / 326 = 77.9 µm; a thick lens marked with its back vertex
power P focuses collimated light 1/P behind its back vertex, so at d behind it the vergence is
P / (1 - dP) exactly (paraxially); spectacle magnification from :func:`trial_lens_effect`
(an independent code path); etendue = pixel area x pupil area / f^2 for collimated light;
sRGB decoding per IEC 61966-2-1 (0.5 -> 0.2140).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from vissim.atv.predict import fresnel_transmittance, predicted_spot
from vissim.bench.atv.spot import spot_metrics
from vissim.bench.atv.tube import (
    AtvConfig,
    AtvEye,
    AtvTube,
    atv_trial_lens,
    display_code_to_linear,
    pixel_pitch_mm,
)
from vissim.bench.atv.paraxial import atv_paraxial
from vissim.bench.atv.scene import LENS_BSDF, atv_scene
from vissim.bench.lenses.mesh import rim_thickness_mm
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import LensPower, Prescription, RefractiveError
from vissim.optics.rx.trial_lens import TrialLens, TrialLensSetup, trial_lens_effect
from vissim.units import mrad_to_arcmin

PITCH_MM = 25.4 / 326.0
PIXEL_ARCMIN = float(mrad_to_arcmin(1000.0 * PITCH_MM / 125.0))  # 2.1428'


def test_iphone5_pixel_is_77_9_um_and_subtends_2_14_arcmin_at_the_focus():
    assert pixel_pitch_mm(326) == pytest.approx(0.0779141, abs=1e-7)
    assert AtvTube().pixel_pitch_mm == pytest.approx(PITCH_MM, rel=1e-12)
    assert atv_paraxial(AtvConfig()).pixel_angle_arcmin == pytest.approx(PIXEL_ARCMIN, rel=1e-9)
    assert PIXEL_ARCMIN == pytest.approx(2.1428, abs=1e-4)


@pytest.mark.parametrize("side", ["eye", "phone"])
def test_phone_sits_in_the_focal_plane_of_the_8d_lens(side):
    config = AtvConfig(tube=AtvTube(lens_convex_side=side))
    lens = config.tube.collimator_lens()
    assert -lens.ray_transfer_matrix()[2, 0] == pytest.approx(8.0, rel=1e-12)  # equivalent power
    layout = config.layout()
    assert layout.phone_z_mm - layout.collimator_front_principal_z_mm == pytest.approx(125.0, abs=1e-9)
    np.testing.assert_allclose(atv_paraxial(config).vergence_matrix_diopters, 0.0, atol=1e-9)
    # Plano-convex: the front principal plane is t/n inside a plano front, at a convex front's vertex.
    inside = 3.0 / 1.523 if side == "eye" else 0.0
    assert layout.collimator_front_vertex_z_mm - layout.collimator_front_principal_z_mm == pytest.approx(inside)


def test_a_longer_tube_makes_the_light_converge():
    config = AtvConfig(tube=AtvTube(tube_length_mm=130.0))
    # 8 D - 1/0.130 m at the back principal point (the back vertex for a plano front), 25 mm to the pupil.
    at_lens = 8.0 - 1000.0 / 130.0
    expected = at_lens / (1.0 - 0.025 * at_lens)
    np.testing.assert_allclose(atv_paraxial(config).vergence_matrix_diopters, expected * np.eye(2), atol=1e-9)


@pytest.mark.parametrize("power", [-5.0, -2.0, 2.0, 4.0, 5.0])
def test_trial_lens_vergence_at_the_pupil_is_p_over_1_minus_dp(power):
    config = AtvConfig(trial_lens=atv_trial_lens(power))
    par = atv_paraxial(config)
    expected = power / (1.0 - 0.015 * power)
    np.testing.assert_allclose(par.vergence_matrix_diopters, expected * np.eye(2), atol=1e-9)
    assert par.blur_diameter_arcmin == pytest.approx(float(mrad_to_arcmin(4.0 * abs(expected))), rel=1e-9)
    # The pixel is magnified like any object at infinity behind the trial lens (spectacle magnification).
    effect = trial_lens_effect(TrialLensSetup(lenses=(config.trial_lens,), vertex_distance_mm=15.0))
    assert par.pixel_angle_arcmin == pytest.approx(PIXEL_ARCMIN * effect.magnification, rel=1e-9)
    # Etendue: flux into the pupil grows as the pixel's apparent solid angle, M^2.
    bare = PITCH_MM**2 * 1e-6 * math.pi / 4 * 0.004**2 / 0.125**2
    assert par.etendue_m2_sr == pytest.approx(bare * effect.magnification**2, rel=1e-9)


def test_eye_error_and_accommodation_add_to_the_defocus():
    eye = AtvEye(pupil_diameter_mm=6.0, refractive_error=Prescription(-1.5), accommodation_diopters=0.5)
    assert eye.refractive_error == RefractiveError(1.5)
    par = atv_paraxial(AtvConfig(eye=eye, trial_lens=atv_trial_lens(-2.0)))
    expected = -2.0 / (1.0 + 0.03) + 1.5 + 0.5
    np.testing.assert_allclose(par.defocus_matrix_diopters, expected * np.eye(2), atol=1e-9)


def test_scene_dict_places_the_lenses_the_pixel_and_the_eye():
    config = AtvConfig(eye=AtvEye(pupil_diameter_mm=5.0), trial_lens=atv_trial_lens(3.0), fresnel_loss=True)
    layout = config.layout()
    scene = atv_scene(config, arcmin_per_px=0.5, size_px=101, spp=16, seed=3)
    assert {"collimator", "trial_lens", "tube", "pixel", "eye", "integrator"} <= set(scene)
    assert scene["collimator"]["to_world"][2][3] == pytest.approx(25.0)
    assert scene["trial_lens"]["to_world"][2][3] == pytest.approx(15.0)
    for key in ("collimator", "trial_lens"):
        assert scene[key]["bsdf"] == {"type": LENS_BSDF, "int_ior": 1.523, "fresnel_loss": True}
        assert scene[key]["face_normals"] is False
    pixel = scene["pixel"]["to_world"]
    assert pixel[0][0] == pytest.approx(PITCH_MM / 2) and pixel[1][1] == pytest.approx(PITCH_MM / 2)
    assert pixel[2][3] == pytest.approx(layout.phone_z_mm)
    assert scene["pixel"]["flip_normals"] is True  # emits toward the eye, -z
    assert scene["tube"]["p1"][2] == pytest.approx(layout.phone_z_mm)
    assert scene["tube"]["radius"] >= 11.0
    eye = scene["eye"]
    assert eye["type"] == "thinlens" and eye["aperture_radius"] == pytest.approx(2.5)
    assert eye["focus_distance"] >= 1e8  # relaxed emmetrope: infinity
    assert eye["fov"] == pytest.approx(101 * 0.5 / 60.0, rel=1e-4)
    assert eye["sampler"] == {"type": "independent", "sample_count": 16, "seed": 3}
    assert set(atv_scene(config, camera=False)) == {"type", "collimator", "trial_lens", "tube", "pixel"}


def test_camera_focuses_where_a_myopic_or_accommodating_eye_does():
    eye = AtvEye(refractive_error=RefractiveError(1.5), accommodation_diopters=0.5)
    assert atv_scene(AtvConfig(eye=eye))["eye"]["focus_distance"] == pytest.approx(500.0)
    with pytest.raises(VissimInputError, match="beyond infinity"):
        atv_scene(AtvConfig(eye=AtvEye(refractive_error=RefractiveError(-1.0))))
    with pytest.raises(VissimInputError, match="spherical eye"):
        atv_scene(AtvConfig(eye=AtvEye(refractive_error=Prescription(0.0, -1.0, 90.0))))
    assert "eye" not in atv_scene(AtvConfig(eye=AtvEye(refractive_error=RefractiveError(-1.0))), camera=False)


def test_realistic_trial_lenses_fit_the_slot():
    for power in (-5.0, -0.25, 0.0, 0.25, 5.0):
        lens = atv_trial_lens(power)
        thinnest, _ = rim_thickness_mm(lens, 22.0)
        assert lens.center_thickness_mm >= 1.0 - 1e-9 and thinnest >= 1.0 - 1e-9
        AtvConfig(trial_lens=lens)  # fits between the pupil and the collimator


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: AtvEye(pupil_diameter_mm=0.5), "pupil diameter must be within 1-10 mm (a human eye's pupil), got 0.5 mm"),
        (lambda: AtvEye(pupil_diameter_mm=11), "pupil diameter must be within 1-10 mm (a human eye's pupil), got 11 mm"),
        (lambda: AtvEye(accommodation_diopters=-1), "accommodation must be >= 0 dioptres, got -1 dioptres"),
        (lambda: AtvEye(refractive_error=LensPower(2.0)), "Prescription or a RefractiveError"),
        (lambda: AtvTube(pixel_radiance=-1), "pixel radiance must be >= 0"),
        (lambda: AtvTube(pixels_per_inch=0), "display resolution must be >= 1 pixels per inch"),
        (lambda: AtvTube(pixels_per_inch=2e4), "display resolution must be <= 10000 pixels per inch"),
        (lambda: AtvTube(tube_length_mm=float("nan")), "tube length must be finite"),
        (lambda: AtvTube(lens_convex_side="left"), "lens_convex_side"),
        (lambda: AtvTube(lens_center_thickness_mm=0.5), "no edge"),
        (lambda: AtvTube(pixel_offset_mm=(9.0, 0.0)), "pixel offset"),
        (lambda: AtvConfig(trial_lens=TrialLens(2.0)), "needs a refractive index"),
        (lambda: AtvConfig(trial_lens=atv_trial_lens(2.0), trial_lens_distance_mm=24.0), "must fit between"),
        (lambda: AtvConfig(trial_lens=atv_trial_lens(2.0), trial_lens_distance_mm=0.2), "must fit between"),
    ],
)
def test_bad_input_is_one_line_naming_the_value(make, message):
    with pytest.raises(VissimInputError, match=re.escape(message)) as info:
        make()
    assert "\n" not in str(info.value)


def test_display_codes_decode_to_linear_radiance():
    assert display_code_to_linear(0.5, "srgb") == pytest.approx(0.21404, abs=1e-5)  # IEC 61966-2-1
    assert display_code_to_linear(0.5) == display_code_to_linear(0.5, "gamma2.2")  # the ATV default
    assert display_code_to_linear(0.5, "gamma2.2") == pytest.approx(0.5**2.2, rel=1e-12)
    codes = np.linspace(0.0, 1.0, 11)
    for transfer in ("srgb", "gamma2.2"):
        linear = display_code_to_linear(codes, transfer)
        assert linear[0] == 0.0 and linear[-1] == pytest.approx(1.0) and np.all(np.diff(linear) > 0)
    assert display_code_to_linear(0.04045, "srgb") == pytest.approx(0.04045 / 12.92, rel=1e-6)  # linear segment
    for bad in (1.2, -0.1, float("nan"), "bright"):
        with pytest.raises(VissimInputError, match=r"\[0, 1\]"):
            display_code_to_linear(bad)
    with pytest.raises(VissimInputError, match="transfer"):
        display_code_to_linear(0.5, "pq")


def test_fresnel_transmittance_of_uncoated_crown_surfaces():
    per_surface = 1.0 - (0.523 / 2.523) ** 2  # normal incidence, 0.9570
    assert fresnel_transmittance(AtvConfig()) == 1.0
    assert fresnel_transmittance(AtvConfig(fresnel_loss=True)) == pytest.approx(per_surface**2)
    assert fresnel_transmittance(AtvConfig(trial_lens=atv_trial_lens(1.0), fresnel_loss=True)) == pytest.approx(
        per_surface**4)


def test_predicted_in_focus_spot_is_the_pixel_square():
    config = AtvConfig(tube=AtvTube(pixel_radiance=2.0))
    prediction = predicted_spot(config, arcmin_per_px=0.1, size_px=41)
    flux = 2.0 * PITCH_MM**2 * 1e-6 * math.pi / 4 * 0.004**2 / 0.125**2
    assert prediction.total_flux == pytest.approx(flux, rel=1e-9)
    assert prediction.image.sum() * 0.01 == pytest.approx(flux, rel=1e-5)
    assert prediction.peak == pytest.approx(flux / PIXEL_ARCMIN**2, rel=1e-5)
    # Square of side s: 21 full pixels and two edge pixels covered (s/0.1 - 21)/2 = 0.214 across the centre.
    row = prediction.image[20] / prediction.peak
    np.testing.assert_allclose(row[10:31], 1.0, atol=1e-5)
    assert row[9] == pytest.approx((PIXEL_ARCMIN / 0.1 - 21) / 2, abs=1e-4)
    assert prediction.spot_diameter_arcmin == pytest.approx(PIXEL_ARCMIN / math.cos(math.pi / 8), rel=0.02)


def test_in_focus_spot_diameter_does_not_depend_on_the_sampling():
    # The pixel's square (s / cos 22.5 deg = 2.32') measured at 0.25' and 0.1' per pixel: ring means centred
    # on whole radii agree within 0.5 % (annuli [k, k + 1) gave 2.43' and 2.33', 4 % apart).
    coarse, fine = (predicted_spot(AtvConfig(), arcmin_per_px=step, size_px=size).spot_diameter_arcmin
                    for step, size in ((0.25, 17), (0.1, 41)))
    assert coarse == pytest.approx(fine, rel=0.005)
    assert fine == pytest.approx(PIXEL_ARCMIN / math.cos(math.pi / 8), rel=0.02)


@pytest.mark.parametrize("power", [-4.0, 2.0])
def test_predicted_blur_disc_has_the_pupil_times_vergence_diameter(power):
    prediction = predicted_spot(AtvConfig(trial_lens=atv_trial_lens(power)), arcmin_per_px=0.5)
    blur = float(mrad_to_arcmin(4.0 * abs(power / (1.0 - 0.015 * power))))
    assert prediction.spot_diameter_arcmin == pytest.approx(blur, rel=0.005)
    area = math.pi / 4 * blur**2
    assert prediction.peak == pytest.approx(prediction.total_flux / area, rel=0.01)


def test_offset_pixel_appears_on_the_same_side_to_the_eye():
    # World +x is the subject's left: a pixel moved that way is seen to the left (negative "right").
    prediction = predicted_spot(AtvConfig(tube=AtvTube(pixel_offset_mm=(0.3, 0.2))), arcmin_per_px=0.25)
    right, up = prediction.centroid_arcmin
    assert right == pytest.approx(-float(mrad_to_arcmin(0.3 / 125 * 1000)), abs=0.01)
    assert up == pytest.approx(float(mrad_to_arcmin(0.2 / 125 * 1000)), abs=0.01)


def test_spot_metrics_of_a_disc_and_of_noise():
    step, n = 0.5, 161
    rows, cols = np.indices((n, n)) - n // 2
    disc = (np.hypot(rows, cols) * step <= 30.0).astype(float)  # diameter 60'
    metrics = spot_metrics(disc, step)
    assert metrics.spot_diameter_arcmin == pytest.approx(60.0, rel=0.01)
    assert metrics.peak == pytest.approx(1.0, rel=1e-6) and metrics.peak_pixel == 1.0
    assert metrics.total_flux == pytest.approx(math.pi * 30.0**2, rel=0.01)
    noisy = np.random.default_rng(0).poisson(disc * 200) / 200.0  # 7 % per pixel
    robust = spot_metrics(noisy, step, np.sqrt(disc * 200) / 200.0)
    assert robust.peak == pytest.approx(1.0, abs=0.02)
    assert robust.peak_pixel > 1.15  # the largest raw pixel is biased up by the noise
    assert robust.peak_relative_std < 0.01
    assert spot_metrics(np.zeros((5, 5)), step).total_flux == 0.0
