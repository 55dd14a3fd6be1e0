"""The ATV tube rendered by light tracing (and, slowly, from the camera side) against first-order optics.

Expected values and where they come from:

* blur-disc diameter = pupil x vergence at the pupil (mm x D = mrad); a trial lens marked with
  its back vertex power P, d = 15 mm in front of the pupil, gives the collimated light the
  vergence P / (1 - dP) exactly (paraxially);
* a disc much wider than the pixel has a flat plateau at flux / (pi D^2 / 4);
* in focus, the image is the pixel's square: 25.4 / 326 mm at 125 mm = 2.1428';
* flux into the pupil = radiance x etendue = L x pixel area x pupil area / f^2 x M^2, with M the
  trial lens's spectacle magnification (the pixel looks M times larger, radiance is conserved),
  so it changes with trial power only through M^2 (Fresnel losses off);
* the eye's thin lens adds its excess power E and accommodation A to the vergence.

Tolerances: against 2^24-ray references the light tracer's smoothed peak is within 0.1-0.2 %
at 2^18-2^19 rays, its spot diameter within 0.1 % and its flux within 0.01 %; the 2 % geometric
tolerances leave room for the paraxial model's own approximations (real rays, meshed lenses).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

from vissim.atv.predict import predicted_spot
from vissim.bench.atv.tube import (
    AtvConfig,
    AtvEye,
    AtvTube,
    atv_trial_lens,
)
from vissim.bench.atv.paraxial import atv_paraxial
from vissim.bench.atv.scene import LENS_BSDF
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.units import mrad_to_arcmin

mitsuba_backend = pytest.importorskip("vissim.render.backend")
if mitsuba_backend.choose_variant("mono").variant.startswith("scalar"):  # pragma: no cover
    pytest.skip("the ATV light tracer needs a vectorised Mitsuba variant (LLVM >= 16)", allow_module_level=True)

from vissim.render import atv_trace  # noqa: E402
from vissim.render.atv_trace import render_atv_camera, trace_atv  # noqa: E402

D_M = 0.015  # trial lens back vertex to pupil
PUPIL_MM = 4.0
PITCH_MM = 25.4 / 326.0
PIXEL_ARCMIN = float(mrad_to_arcmin(1000.0 * PITCH_MM / 125.0))
RAYS = 1 << 19


def vergence(power: float) -> float:
    return power / (1.0 - D_M * power)


def trial_for_vergence(vergence_diopters: float) -> float:
    """The back vertex power giving this vergence at the pupil: V / (1 + dV)."""
    return vergence_diopters / (1.0 + D_M * vergence_diopters)


def blur_arcmin(vergence_diopters: float, pupil_mm: float = PUPIL_MM) -> float:
    return float(mrad_to_arcmin(pupil_mm * abs(vergence_diopters)))


def config_with(power: float | None, **eye) -> AtvConfig:
    return AtvConfig(eye=AtvEye(**eye), trial_lens=None if power is None else atv_trial_lens(power))


@pytest.fixture(scope="module")
def scan():
    """Traces shared by several tests: trial powers -4, -2, 0 (no lens), +2, +4 D at 0.5'/px."""
    return {p: trace_atv(config_with(p or None), n_rays=RAYS, seed=7, arcmin_per_px=0.5) for p in (-4, -2, 0, 2, 4)}


@pytest.mark.parametrize("power", [-4, -2, 2, 4])
def test_spot_diameter_is_pupil_times_vergence(scan, power):
    assert scan[power].spot_diameter_arcmin == pytest.approx(blur_arcmin(vergence(power)), rel=0.02)


@pytest.mark.parametrize("power", [-4, -2, 2, 4])
def test_peak_is_the_flux_spread_over_the_blur_disc(scan, power):
    result = scan[power]
    disc_area = math.pi / 4.0 * blur_arcmin(vergence(power)) ** 2
    # Discs of 26-58' against a 2.1' pixel: the plateau is flat; 2 % covers noise (~0.5 %) and the edge.
    assert result.peak == pytest.approx(result.total_flux / disc_area, rel=0.02)
    assert result.peak_relative_std < 0.01


def test_peak_falls_with_the_square_of_the_trial_vergence(scan):
    ratio = scan[2].peak / scan[4].peak
    expected = (vergence(4) / vergence(2)) ** 2 * scan[2].total_flux / scan[4].total_flux
    assert ratio == pytest.approx(expected, rel=0.02)
    assert scan[0].peak > 50 * scan[2].peak  # in focus: all the flux in one pixel's square


def test_total_flux_changes_only_with_spectacle_magnification(scan):
    for power, result in scan.items():
        par = atv_paraxial(config_with(power or None))
        assert result.total_flux == pytest.approx(par.etendue_m2_sr, rel=0.003)  # radiance 1
        magnification = par.pixel_angle_arcmin / PIXEL_ARCMIN
        assert result.total_flux / magnification**2 == pytest.approx(scan[0].total_flux, rel=0.003)


def test_in_focus_spot_is_the_pixel_square():
    result = trace_atv(AtvConfig(), n_rays=1 << 19, seed=3, arcmin_per_px=0.1, size_px=41)
    image = result.image / result.peak
    for profile in (image[20], image[:, 20]):  # across the centre: a box of the pixel's width
        np.testing.assert_allclose(profile[10:31], 1.0, atol=0.03)  # 21 covered pixels
        assert profile.sum() * 0.1 == pytest.approx(PIXEL_ARCMIN, rel=0.02)  # width incl. partial edges
    assert result.spot_diameter_arcmin == pytest.approx(PIXEL_ARCMIN / math.cos(math.pi / 8), rel=0.03)
    assert result.peak == pytest.approx(result.total_flux / PIXEL_ARCMIN**2, rel=0.01)


def test_an_eye_with_refractive_error_sees_like_a_trial_lens_of_that_vergence():
    # A 2 D myope (prescription -2) without a lens blurs like an emmetrope behind a lens of vergence +2 D ...
    myope = trace_atv(config_with(None, refractive_error=Prescription(-2.0)), n_rays=RAYS, seed=5)
    lens = trace_atv(config_with(trial_for_vergence(2.0)), n_rays=RAYS, seed=5)
    assert myope.spot_diameter_arcmin == pytest.approx(blur_arcmin(2.0), rel=0.02)
    assert lens.spot_diameter_arcmin == pytest.approx(myope.spot_diameter_arcmin, rel=0.01)
    # ... and a correcting lens of vergence -2 D brings the pixel back into focus.
    corrected = trace_atv(config_with(trial_for_vergence(-2.0), refractive_error=Prescription(-2.0)),
                          n_rays=1 << 18, seed=5)
    pixel = atv_paraxial(corrected.config).pixel_angle_arcmin
    assert corrected.spot_diameter_arcmin == pytest.approx(pixel / math.cos(math.pi / 8), rel=0.1)
    assert corrected.peak > 100 * myope.peak


def test_accommodation_moves_the_best_trial_lens_by_minus_a():
    # With 1 D of accommodation the sharpest (highest-peak) spot needs a lens of vergence -1 D,
    # where the spot is the pixel; +-0.5 D from there the blur is pupil x 0.5 D.
    peaks = {}
    for v in (-1.5, -1.0, -0.5, 0.0):
        result = trace_atv(config_with(trial_for_vergence(v), accommodation_diopters=1.0), n_rays=1 << 18, seed=2)
        peaks[v] = result.peak
        if v == -0.5:
            assert result.spot_diameter_arcmin == pytest.approx(blur_arcmin(0.5), rel=0.05)
    assert max(peaks, key=peaks.get) == -1.0


def test_pixel_offset_appears_on_the_eye_side_it_should():
    # World +x is the subject's left, so a pixel moved 0.3 mm that way appears 8.25' to the left.
    config = AtvConfig(tube=AtvTube(pixel_offset_mm=(0.3, 0.2)))
    right, up = trace_atv(config, n_rays=1 << 18, seed=1, arcmin_per_px=0.25).centroid_arcmin
    assert right == pytest.approx(-float(mrad_to_arcmin(0.3 / 125 * 1000)), abs=0.03)
    assert up == pytest.approx(float(mrad_to_arcmin(0.2 / 125 * 1000)), abs=0.03)
    camera = render_atv_camera(config, spp=16, seed=1, arcmin_per_px=0.5, size_px=45)
    assert camera.centroid_arcmin == pytest.approx((right, up), abs=0.05)


def test_astigmatic_eye_blurs_across_its_cylinder_axis_like_the_fourier_prediction():
    # plano -2.00 x 90: excess power in the horizontal meridian, a horizontal line (docs/conventions.md).
    config = config_with(None, refractive_error=Prescription(0.0, -2.0, 90.0))
    result = trace_atv(config, n_rays=1 << 19, seed=4, arcmin_per_px=0.5)
    rows, cols = np.indices(result.image.shape)
    weights = result.image / result.image.sum()
    var_x = (weights * (cols - (weights * cols).sum()) ** 2).sum()
    var_y = (weights * (rows - (weights * rows).sum()) ** 2).sum()
    assert var_x > 20 * var_y
    prediction = predicted_spot(config, arcmin_per_px=0.5, size_px=result.image.shape[0])
    assert np.abs(result.image - prediction.image).sum() / prediction.image.sum() < 0.08


def test_a_plus_cylinder_trial_lens_at_90_also_draws_a_horizontal_line():
    # conventions: a +2.00 DC x 90 trial lens on a perfect eye blurs like the eye corrected by plano -2.00 x 90.
    result = trace_atv(AtvConfig(trial_lens=atv_trial_lens(0.0, 2.0, 90.0)), n_rays=1 << 17, seed=4)
    rows, cols = np.indices(result.image.shape)
    weights = result.image / result.image.sum()
    var_x = (weights * (cols - (weights * cols).sum()) ** 2).sum()
    var_y = (weights * (rows - (weights * rows).sum()) ** 2).sum()
    assert var_x > 20 * var_y


def test_traced_image_matches_the_paraxial_prediction(scan):
    size = scan[2].image.shape[0]  # 73 px
    prediction = predicted_spot(config_with(2), arcmin_per_px=0.5, size_px=size)

    def blocks(image):  # 2' pixels: sums of 4 x 4, which divide the per-pixel noise by 4
        n = size // 4 * 4
        return image[:n, :n].reshape(n // 4, 4, n // 4, 4).sum(axis=(1, 3))

    difference = np.abs(blocks(scan[2].image) - blocks(prediction.image)).sum() / blocks(prediction.image).sum()
    assert difference < 0.03
    assert scan[2].peak == pytest.approx(prediction.peak, rel=0.02)


def test_fresnel_loss_weights_each_surface():
    plain = trace_atv(config_with(3.0), n_rays=1 << 16, seed=1)
    lossy = trace_atv(AtvConfig(trial_lens=atv_trial_lens(3.0), fresnel_loss=True), n_rays=1 << 16, seed=1)
    per_surface = 1.0 - (0.523 / 2.523) ** 2  # near-normal incidence
    assert lossy.total_flux / plain.total_flux == pytest.approx(per_surface**4, rel=0.002)


def test_a_wider_sampling_cone_gives_the_same_flux(monkeypatch):
    config = config_with(-3.0)
    tight = trace_atv(config, n_rays=1 << 18, seed=1)
    monkeypatch.setattr(atv_trace, "_CONE_MARGIN", 2.0)  # 3.6x the rays wasted outside the pupil
    wide = trace_atv(config, n_rays=1 << 18, seed=1)
    assert wide.total_flux == pytest.approx(tight.total_flux, rel=0.004)
    assert wide.spot_diameter_arcmin == pytest.approx(tight.spot_diameter_arcmin, rel=0.01)


def test_a_too_narrow_sampling_cone_widens_itself(monkeypatch, caplog):
    config = config_with(-3.0)
    reference = trace_atv(config, n_rays=1 << 17, seed=1)
    monkeypatch.setattr(atv_trace, "_CONE_MARGIN", 0.7)  # misses the pupil's rim at first
    with caplog.at_level("WARNING", logger="vissim.render.atv_trace"):
        widened = trace_atv(config, n_rays=1 << 17, seed=1)
    assert "widening" in caplog.text
    assert widened.total_flux == pytest.approx(reference.total_flux, rel=0.004)


def test_same_seed_same_image_and_other_seed_other_noise():
    config = config_with(1.0)
    a, b = (trace_atv(config, n_rays=1 << 16, seed=11) for _ in range(2))
    c = trace_atv(config, n_rays=1 << 16, seed=12)
    np.testing.assert_array_equal(a.image, b.image)
    assert not np.array_equal(a.image, c.image)
    assert a.n_rays == 1 << 16 and trace_atv(config, n_rays=1000, seed=1).n_rays == 1024


def test_bad_requests_raise_one_line_errors():
    with pytest.raises(VissimInputError, match="n_rays"):
        trace_atv(AtvConfig(), n_rays=0)
    with pytest.raises(VissimInputError, match="arcmin per pixel"):
        trace_atv(AtvConfig(), arcmin_per_px=-1)
    with pytest.raises(VissimInputError, match="passes"):
        render_atv_camera(AtvConfig(), spp=8, passes=1)


def test_scene_bsdf_is_the_registered_refraction_plugin():
    from vissim.render.plugins import REFRACT_BSDF

    assert LENS_BSDF == REFRACT_BSDF


def _cli(tmp_path, capsys, *argv: str) -> tuple[int, str]:
    from vissim.cli.render_atv import add_atv_parser

    parser = argparse.ArgumentParser(prog="vissim render")
    add_atv_parser(parser.add_subparsers(dest="bench"))
    args = parser.parse_args(["atv", *argv])
    code = args.func(args)
    return code, capsys.readouterr().out


def test_cli_writes_the_spot_and_a_json_summary(tmp_path, capsys):
    from vissim.imageio import read_image

    out = tmp_path / "spot.exr"
    code, text = _cli(tmp_path, capsys, "--sphere", "-2", "--pupil-mm", "5", "--rays", "65536",
                      "--rx=-0.5", "--accommodation-diopters", "0.25", "-o", str(out), "--json")
    assert code == 0
    summary = json.loads(text)
    for key in ("peak_irradiance_per_arcmin2", "spot_diameter_arcmin", "total_flux", "method", "seconds"):
        assert key in summary
    assert summary["method"] == "trace" and summary["n_rays"] == 65536
    expected = blur_arcmin(vergence(-2.0) + 0.5 + 0.25, pupil_mm=5.0)
    assert summary["spot_diameter_arcmin"] == pytest.approx(expected, rel=0.03)
    assert summary["prediction_geometric"]["blur_diameter_arcmin"] == pytest.approx(expected, rel=1e-9)
    image = read_image(out)
    assert image.pixels.dtype == np.float32
    assert image.provenance["inputs"]["command"] == "render atv"
    assert summary["written"] == [str(out)] and summary["provenance"]["inputs"]["command"] == "render atv"
    with pytest.raises(VissimInputError, match="already exists"):
        _cli(tmp_path, capsys, "--sphere", "-2", "-o", str(out))


def test_cli_refuses_mismatched_budgets_and_bad_values(tmp_path, capsys):
    out = str(tmp_path / "spot.exr")
    with pytest.raises(VissimInputError, match="--spp goes with --method camera"):
        _cli(tmp_path, capsys, "--spp", "8", "-o", out)
    with pytest.raises(VissimInputError, match="pupil diameter must be within 1-10 mm"):
        _cli(tmp_path, capsys, "--pupil-mm", "0.5", "-o", out)
    with pytest.raises(VissimInputError, match=r"\.exr"):
        _cli(tmp_path, capsys, "-o", str(tmp_path / "spot.png"))
    with pytest.raises(VissimInputError, match=r"display code must lie in \[0, 1\]"):
        _cli(tmp_path, capsys, "--display-code", "2", "-o", out)


@pytest.mark.slow
def test_camera_side_render_agrees_with_the_tracer_within_its_noise():
    # +2 D trial lens, 4 mm pupil: a 28.4' disc; 1'/px, 8 passes of 1024 spp (about a minute on 2 cores).
    config = config_with(2.0)
    camera = render_atv_camera(config, spp=8192, seed=1, arcmin_per_px=1.0, size_px=37, passes=8)
    trace = trace_atv(config, n_rays=1 << 22, seed=1, arcmin_per_px=1.0, size_px=37)
    assert camera.total_flux == pytest.approx(trace.total_flux, rel=0.03)
    # Annuli 2' wide about the axis: the camera's pass spread sets the tolerance (4 sigma).
    rows, cols = np.indices(camera.image.shape) - 18
    ring = (np.hypot(rows, cols) // 2).astype(int)
    for r in range(int(ring.max()) + 1):
        inside = ring == r
        cam, tr = camera.image[inside].mean(), trace.image[inside].mean()
        sigma = math.sqrt((camera.std_image[inside] ** 2).sum()) / inside.sum() + 1e-3 * trace.peak
        assert abs(cam - tr) < 4.0 * sigma, f"annulus {r}: camera {cam:.4g}, tracer {tr:.4g}, sigma {sigma:.3g}"
    assert camera.spot_diameter_arcmin == pytest.approx(trace.spot_diameter_arcmin, rel=0.03)


@pytest.mark.slow
def test_tracer_peak_converges_to_its_high_ray_reference():
    config = config_with(-4.0)
    reference = trace_atv(config, n_rays=1 << 24, seed=99)
    for seed in (1, 2):
        result = trace_atv(config, n_rays=1 << 22, seed=seed, arcmin_per_px=0.5,
                           size_px=reference.image.shape[0])
        assert result.peak == pytest.approx(reference.peak, rel=0.01)
        assert result.total_flux == pytest.approx(reference.total_flux, rel=0.001)
        assert result.spot_diameter_arcmin == pytest.approx(reference.spot_diameter_arcmin, rel=0.003)
