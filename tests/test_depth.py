"""Depth-dependent blur: defocus per depth, layers, occlusion, and the blur-depth command.

Expected values and where they come from:

* defocus per depth: effective prescription = Rx + 1/d - A (``vissim.optics.depth.depth_map`` docstring);
  a -2 D myope sees 0.5 m with zero defocus and 6 m with 2 - 1/6 = 1.8333 D;
* geometric blur-disc diameter = pupil (mm) x defocus (D) mrad (``docs/conventions.md``); the
  disc's radius r follows from the pixel-integrated second moment <x^2 + y^2> = r^2/2 + 2/12 px^2;
  the tolerance is the 2 % of the brief (ray sampling noise is ~0.1 %);
* "sharp" = equal, to FFT round-off (abs 1e-5 on [0, 1] float32 images), to the diffraction-only
  blur of the same image;
* occlusion: with uniform layers the over-compositing has closed forms (near panel alone over a
  black background: B_near(c mask); a black near panel over a uniform background of 1:
  1 - B_near(mask)); again abs 1e-5.
"""

import json
import math

import numpy as np
import OpenEXR
import pytest

from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.imageio import read_image, write_image
from vissim.optics.rx.accommodation import accommodation_for_target
from vissim.optics.blur.convolve import blur_image
from vissim.optics.depth.depth_map import (
    matte_indices,
    blur_depth,
    layer_spacing_diopters,
    plan_layers,
)
from vissim.optics.depth.windows import extended_layer, occlusion_weight
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.rx.viewing_setup import DepthViewer
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import rad_to_arcmin


def effective_prescription(rx, distance_m, accommodation_diopters=0.0):
    """Oracle, written out (not vissim's code): Rx + 1/d - A on the sphere (docs/conventions.md, Depth)."""
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    return Prescription(rx.sphere_diopters + proximity - accommodation_diopters, rx.cylinder_diopters, rx.axis_deg)

PUPIL_MM = 4.0
STEP = 1.0  # arcmin per pixel
ATOL = 1e-5


def texture(shape, seed=0):
    return np.random.default_rng(seed).random(shape).astype(np.float32)


def single_psf_blur(image, rx: Prescription, mode="wave", pupil=PUPIL_MM, step=STEP, padding="edge"):
    """Reference: the whole image blurred with one PSF (edge padding: blur_depth's default)."""
    front = Wavefront.from_prescription(rx, pupil)
    size = suggested_size_px(front, step, pupil_diameter_mm=pupil)
    psf = compute_psf(front, pupil_diameter_mm=pupil, arcmin_per_px=step, size_px=size, mode=mode)
    return blur_image(image, psf, arcmin_per_px=step, padding=padding)


def margin_px(result):
    return max(layer.psf_size_px for layer in result.layers) // 2 + 2


def disc_diameter_px(patch):
    """Diameter of a uniform disc from the pixel-integrated PSF's second moment."""
    rows, cols = np.indices(patch.shape)
    total = patch.sum(dtype=np.float64)
    r0, c0 = (patch * rows).sum() / total, (patch * cols).sum() / total
    second = (patch * ((rows - r0) ** 2 + (cols - c0) ** 2)).sum() / total
    return 2.0 * math.sqrt(2.0 * (second - 2.0 / 12.0))


# -- the sign of defocus with depth ---------------------------------------------------------
def test_effective_prescription_is_rx_plus_proximity_minus_accommodation():
    myope = Prescription(-2.0, -1.0, 30.0)
    assert effective_prescription(myope, 0.5).sphere_diopters == pytest.approx(0.0, abs=1e-12)
    assert effective_prescription(myope, 6.0).sphere_diopters == pytest.approx(-2.0 + 1 / 6, abs=1e-12)
    assert effective_prescription(myope, math.inf).sphere_diopters == pytest.approx(-2.0, abs=1e-12)
    assert effective_prescription(myope, 0.25, 1.0).sphere_diopters == pytest.approx(1.0, abs=1e-12)
    shifted = effective_prescription(myope, 6.0)
    assert (shifted.cylinder_diopters, shifted.axis_deg) == (-1.0, 30.0)  # the oracle keeps them exactly


def test_myopic_eye_sees_the_half_metre_panel_sharp():
    # Left half at 0.5 m (the -2 D myope's far point), right half at 6 m.
    image = texture((64, 256))
    depth = np.where(np.arange(256) < 128, 0.5, 6.0)[None, :].repeat(64, axis=0)
    result = blur_depth(image, depth, rx=Prescription(-2.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP)
    diffraction_only = single_psf_blur(image, Prescription(0.0))
    m = margin_px(result)
    np.testing.assert_allclose(result.image[:, : 128 - m], diffraction_only[:, : 128 - m], atol=ATOL)
    # ... and the 6 m half is not: it matches the -1.83 D blur instead.
    far = single_psf_blur(image, Prescription(-2.0 + 1 / 6))
    np.testing.assert_allclose(result.image[:, 128 + m :], far[:, 128 + m :], atol=ATOL)
    assert np.abs(result.image[:, 128 + m :] - diffraction_only[:, 128 + m :]).max() > 0.1


def test_myopic_eye_blurs_a_six_metre_point_into_a_disc_of_pupil_times_1_83_D():
    image = np.zeros((80, 200), np.float32)
    image[40, 50] = image[40, 150] = 1.0
    depth = np.where(np.arange(200) < 100, 0.5, 6.0)[None, :].repeat(80, axis=0)
    result = blur_depth(
        image, depth, rx=Prescription(-2.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, mode="geometric"
    )
    expected_px = rad_to_arcmin(PUPIL_MM * (2.0 - 1 / 6) * 1e-3) / STEP  # 25.21 px
    measured = disc_diameter_px(result.image[10:71, 120:181])
    assert measured == pytest.approx(expected_px, rel=0.02)
    # the 0.5 m point stays a point (ray optics: zero defocus, no diffraction)
    assert result.image[40, 50] == pytest.approx(1.0, abs=ATOL)
    assert np.abs(result.image[:, :90]).sum() == pytest.approx(1.0, abs=1e-4)


def test_emmetrope_accommodating_to_each_panel_in_turn_sees_it_sharp():
    # One accommodation state at a time: for each panel beyond 0.33 m the accommodation
    # found by accommodation_for_target (within the 3 D amplitude) makes *that* panel equal
    # to its diffraction-only blur; the 0.25 m panel cannot be reached (1 D left over).
    distances = [0.25, 0.34, 0.5, 1.0, 6.0]
    width = 96
    image = texture((40, width * len(distances)), seed=1)
    depth = np.repeat(np.array(distances), width)[None, :].repeat(40, axis=0)
    diffraction_only = single_psf_blur(image, Prescription(0.0))
    for i, distance in enumerate(distances):
        exerted = accommodation_for_target(Prescription(0.0), distance, 3.0)
        result = blur_depth(
            image, depth, rx=Prescription(0.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
            accommodation_diopters=exerted,
        )
        m = margin_px(result)
        assert m < width // 2 - 4
        inner = slice(i * width + m, (i + 1) * width - m)
        difference = np.abs(result.image[:, inner] - diffraction_only[:, inner]).max()
        if distance >= 0.34:
            assert difference < ATOL, (distance, difference)
        else:
            assert exerted == 3.0 and difference > 0.05


# -- layers ------------------------------------------------------------------------------
def test_layer_spacing_keeps_neighbouring_blur_discs_within_the_fraction_of_a_pixel():
    spacing = layer_spacing_diopters(STEP, PUPIL_MM, 0.5)
    pixel_rad = math.radians(STEP / 60)
    assert spacing == pytest.approx(0.5 * pixel_rad / (PUPIL_MM * 1e-3), rel=1e-12)  # 0.03636 D
    plan = plan_layers(0.0, 1.0, spacing, anchor_diopters=0.3)
    gaps = np.diff(plan.proximities_diopters)
    assert gaps.min() > 0 and 0.3 in plan.proximities_diopters
    step_px = rad_to_arcmin(gaps.max() * PUPIL_MM * 1e-3) / STEP
    assert step_px <= 0.5 + 1e-12


def test_layer_count_grows_with_the_dioptric_range():
    spacing = layer_spacing_diopters(STEP, PUPIL_MM, 0.5)
    counts = [plan_layers(0.5, 0.5 + span, spacing).n_layers for span in (1.0, 2.0, 4.0)]
    assert counts == [math.ceil(s / spacing) + 1 for s in (1.0, 2.0, 4.0)]  # 29, 56, 111
    assert (counts[1] - 1) / (counts[0] - 1) == pytest.approx(2.0, rel=0.05)
    assert (counts[2] - 1) / (counts[1] - 1) == pytest.approx(2.0, rel=0.05)
    # an in-focus anchor inside the range adds at most one layer
    assert plan_layers(0.5, 1.5, spacing, anchor_diopters=0.77).n_layers <= counts[0] + 1
    # blur_depth reports the same count for a depth ramp over that range (in focus: 0 D, outside)
    proximity = np.linspace(0.5, 1.5, 32)[None, :].repeat(8, axis=0)
    result = blur_depth(
        texture((8, 32)), 1.0 / proximity, rx=Prescription(0.0), pupil_diameter_mm=PUPIL_MM,
        arcmin_per_px=STEP,
    )
    assert result.n_layers == counts[0]


def test_too_many_layers_is_a_clear_error():
    depth = np.where(np.arange(16) < 8, 0.1, 10.0)[None, :].repeat(16, axis=0)
    with pytest.raises(VissimInputError, match=r"needs \d+ layers .*max_layers=20"):
        blur_depth(texture((16, 16)), depth, rx=Prescription(0.0), pupil_diameter_mm=PUPIL_MM,
                   arcmin_per_px=STEP, max_layers=20)
    # refused by default (DEFAULT_MAX_LAYERS = 256), naming the range it found; None lifts the limit
    with pytest.raises(VissimInputError, match=r"0 to 100 D of proximity \(0.01 m to infinity\), which needs 3335 layers"):
        plan_layers(0.0, 100.0, 0.03)
    assert plan_layers(0.0, 100.0, 0.03, None).n_layers == 3335  # ceil(100 / 0.03) + 1


def test_finer_layers_change_the_result_by_less_than_a_percent():
    # A slanted plane from 6 m (top) to 0.4 m (bottom) behind a 1/1.9 m panel, white-noise
    # texture (the hardest case); spacing fraction 0.5 -> 0.25 (26 -> 50 layers at 3 mm,
    # 2 arcmin/px).  Measured when written: max 0.84 % of the range, PSNR 61 dB; halving the
    # spacing again changes the result ~4x less (second-order convergence).
    rows, cols = 96, 96
    image = texture((rows, cols), seed=2)
    proximity = np.linspace(1 / 6, 2.5, rows)[:, None].repeat(cols, axis=1)
    proximity[30:60, 30:60] = 1.9
    kwargs = dict(rx=Prescription(-1.0), pupil_diameter_mm=3.0, arcmin_per_px=2.0)
    coarse = blur_depth(image, 1.0 / proximity, layer_spacing_fraction=0.5, **kwargs)
    fine = blur_depth(image, 1.0 / proximity, layer_spacing_fraction=0.25, **kwargs)
    assert fine.n_layers > 1.9 * coarse.n_layers
    value_range = float(image.max() - image.min())
    difference = np.abs(fine.image - coarse.image)
    psnr_db = 10 * math.log10(value_range**2 / float(np.mean(difference.astype(np.float64) ** 2)))
    assert difference.max() < 0.01 * value_range and psnr_db > 40.0, (difference.max(), psnr_db)


@pytest.mark.parametrize("distance_m, padding", [(6.0, "edge"), (math.inf, "edge"), (6.0, "reflect")])
def test_constant_depth_is_exactly_the_single_psf_blur(distance_m, padding):
    image = texture((48, 64, 3), seed=3)
    depth = np.full((48, 64), distance_m)
    result = blur_depth(image, depth, rx=Prescription(-2.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
                        padding=padding)
    assert result.n_layers == 1 and result.image.shape == image.shape and result.image.dtype == np.float32
    rx = effective_prescription(Prescription(-2.0), distance_m)
    np.testing.assert_allclose(result.image, single_psf_blur(image, rx, padding=padding), atol=ATOL)


@pytest.mark.parametrize("padding", ["constant", "wrap"])
def test_paddings_without_a_meaning_for_depth_are_refused_not_replaced(padding):
    # Outside the image a constant colour would need a depth and a coverage too, and wrapping would
    # put the far side's depths beside the near; blur_depth refuses both rather than padding by "edge".
    image, depth = texture((24, 32)), np.full((24, 32), 2.0)
    with pytest.raises(VissimInputError, match="depth-blur padding must be one of edge, reflect"):
        blur_depth(image, depth, rx=Prescription(-1.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
                   padding=padding)


def test_two_depth_scene_equals_each_single_psf_blur_away_from_the_boundary():
    image = texture((48, 192), seed=4)
    depth = np.where(np.arange(192) < 96, 0.4, 3.0)[None, :].repeat(48, axis=0)
    result = blur_depth(
        image, depth, rx=Prescription(0.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, accommodation_diopters=1.0
    )
    m = margin_px(result)
    near = single_psf_blur(image, Prescription(2.5 - 1.0))
    far = single_psf_blur(image, Prescription(1 / 3 - 1.0))
    np.testing.assert_allclose(result.image[:, : 96 - m], near[:, : 96 - m], atol=ATOL)
    np.testing.assert_allclose(result.image[:, 96 + m :], far[:, 96 + m :], atol=ATOL)


def test_layers_without_blur_give_back_the_input():
    # Matting + extension + compositing with delta PSFs: out = sum P_k T_k / sum A_k T_k with
    # T_k = 1 - (coverage of the layers that occlude k).  A background group of depths and an
    # occluder group, each spread over less than the occlusion threshold, far apart.
    rng = np.random.default_rng(5)
    colour = rng.random((3, 40, 50)).astype(np.float32)
    proximity = rng.random((40, 50)) * 0.15
    proximity[10:20, 10:30] = 2.9 + rng.random((10, 20)) * 0.1
    threshold_diopters = 0.2
    plan = plan_layers(float(proximity.min()), float(proximity.max()), 0.05)
    layer_diopters = np.array(plan.proximities_diopters)
    lower, frac = matte_indices(proximity, layer_diopters)
    upper, frac = np.minimum(lower + 1, plan.n_layers - 1), frac.astype(np.float32)
    numerator, denominator = np.zeros_like(colour), np.zeros((40, 50), np.float32)
    layers = [extended_layer(colour, lower, upper, frac, layer_diopters, k, threshold_diopters) for k in range(plan.n_layers)]
    for k, planes in enumerate(layers):
        weights = occlusion_weight(layer_diopters - layer_diopters[k], threshold_diopters)
        transmitted = np.clip(1.0 - sum(w * other[-1] for w, other in zip(weights, layers)), 0, 1)
        numerator += planes[:-1] * transmitted
        denominator += planes[-1] * transmitted
    np.testing.assert_allclose(numerator / denominator, colour, atol=1e-5)


# -- occlusion -----------------------------------------------------------------------------
OCCLUSION_CASES = {
    # eye, accommodation: which of near (0.5 m) / far (6 m) is sharp
    "near blurred, far sharp": (Prescription(0.0), 1 / 6),
    "near sharp, far blurred": (Prescription(-2.0), 0.0),
}


def panel_scene(size=96):
    mask = np.zeros((size, size), np.float32)
    mask[size // 3 : 2 * size // 3, size // 3 : 2 * size // 3] = 1.0
    return mask, np.where(mask > 0, 0.5, 6.0)


@pytest.mark.parametrize("case", OCCLUSION_CASES)
def test_bright_near_panel_leaks_no_light_beyond_its_own_blur(case):
    eye, accommodation = OCCLUSION_CASES[case]
    mask, depth = panel_scene()
    result = blur_depth(mask, depth, rx=eye, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
                        accommodation_diopters=accommodation)
    own_blur = single_psf_blur(mask, effective_prescription(eye, 0.5, accommodation))
    np.testing.assert_allclose(result.image, own_blur, atol=ATOL)


@pytest.mark.parametrize("case", OCCLUSION_CASES)
def test_dark_near_panel_over_a_bright_background_shows_no_halo(case):
    eye, accommodation = OCCLUSION_CASES[case]
    mask, depth = panel_scene()
    result = blur_depth(1.0 - mask, depth, rx=eye, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP,
                        accommodation_diopters=accommodation)
    assert result.image.max() <= 1.0 + ATOL  # no glow
    # The near panel's blurred edge attenuates the background by its own blurred coverage,
    # on both sides of the edge; the far blur does not reach into it.
    coverage = single_psf_blur(mask, effective_prescription(eye, 0.5, accommodation))
    np.testing.assert_allclose(result.image, 1.0 - coverage, atol=ATOL)


def test_astigmatism_rides_along_at_every_depth():
    # Eye Rx -1.00 -2.00 x 90: excess power in the horizontal meridian, so points become
    # horizontal streaks (docs/conventions.md) at 1 m (plano -2.00 x 90 left) and at 6 m.
    image = np.zeros((80, 160), np.float32)
    image[40, 40] = image[40, 120] = 1.0
    depth = np.where(np.arange(160) < 80, 1.0, 6.0)[None, :].repeat(80, axis=0)
    result = blur_depth(image, depth, rx=Prescription(-1.0, -2.0, 90.0), pupil_diameter_mm=PUPIL_MM,
                        arcmin_per_px=STEP, mode="geometric")
    for centre in (40, 120):
        patch = result.image[10:71, centre - 30 : centre + 31].astype(np.float64)
        rows, cols = np.indices(patch.shape)
        var_row = (patch * (rows - 30) ** 2).sum() / patch.sum()
        var_col = (patch * (cols - 30) ** 2).sum() / patch.sum()
        assert var_col > 3.0 * var_row, (centre, var_col, var_row)


# -- input checks --------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_depth_must_be_positive_metres_or_inf(bad):
    depth = np.full((8, 8), 2.0)
    depth[3, 3] = bad
    with pytest.raises(VissimInputError, match="depth map has 1 pixels that are not positive metres"):
        blur_depth(texture((8, 8)), depth, rx=Prescription(0.0), pupil_diameter_mm=3.0, arcmin_per_px=1.0)


def test_other_bad_inputs():
    kwargs = dict(rx=Prescription(0.0), pupil_diameter_mm=3.0, arcmin_per_px=1.0)
    with pytest.raises(VissimInputError, match=r"the depth map is 9 × 8 px \(width × height\) but the image 8 × 8 px"):
        blur_depth(texture((8, 8)), np.ones((8, 9)), **kwargs)
    with pytest.raises(VissimInputError, match="accommodation exerted must be >= 0 dioptres"):
        blur_depth(texture((8, 8)), np.ones((8, 8)), accommodation_diopters=-1.0, **kwargs)
    with pytest.raises(TypeError, match="RefractiveError"):
        blur_depth(texture((8, 8)), np.ones((8, 8)), rx=Prescription(-1.0).refractive_error(),
                   pupil_diameter_mm=3.0, arcmin_per_px=1.0)
    with pytest.raises(VissimInputError, match="not both .also given: pupil_diameter_mm"):
        blur_depth(texture((8, 8)), np.ones((8, 8)), eye=DepthViewer(Prescription(0.0), 3.0), pupil_diameter_mm=3.0,
                   arcmin_per_px=1.0)
    with pytest.raises(TypeError, match="the eye is needed"):
        blur_depth(texture((8, 8)), np.ones((8, 8)), arcmin_per_px=1.0)


def test_an_eye_object_blurs_as_its_keywords_do():
    rx, extra = Prescription(-1.0, -0.5, 20.0), Wavefront({(3, 1): 0.05}, 4.0)
    image, depth = texture((24, 24)), np.where(np.arange(24) < 12, 0.5, 2.0)[None, :].repeat(24, axis=0)
    kwargs = dict(arcmin_per_px=1.0, mode="geometric")
    by_keywords = blur_depth(image, depth, rx=rx, pupil_diameter_mm=3.0, accommodation_diopters=0.5,
                             extra_wavefront=extra, **kwargs)
    by_eye = blur_depth(image, depth, eye=DepthViewer(rx, 3.0, 0.5, extra), **kwargs)
    np.testing.assert_array_equal(by_eye.image, by_keywords.image)
    assert by_eye.as_json() == by_keywords.as_json()


# -- the command ---------------------------------------------------------------------------
def test_blur_depth_command_reads_sampling_from_provenance_and_a_z_channel_exr(tmp_path, capsys):
    image_path, depth_path, out_path = tmp_path / "in.exr", tmp_path / "depth.exr", tmp_path / "out.exr"
    write_image(image_path, texture((32, 48, 3)), provenance={"arcmin_per_px": 1.0})
    depth = np.where(np.arange(48) < 24, 0.5, 6.0)[None, :].repeat(32, axis=0).astype(np.float32)
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {"Z": OpenEXR.Channel(np.ascontiguousarray(depth))}).write(str(depth_path))
    code = main(["blur-depth", str(image_path), str(depth_path), "-o", str(out_path), "--rx", "-2.00 DS",
                 "--pupil-mm", "4", "--age", "30", "--focus-distance-m", "0.25", "--mode", "geometric"])
    out, err = capsys.readouterr()
    assert code == 0 and "wrote" in out, err
    written = read_image(out_path)
    assert written.pixels.shape == (32, 48, 3)
    focus = written.provenance["inputs"]["focus"]
    assert focus["accommodation_diopters"] == pytest.approx(2.0) and focus["amplitude_diopters"] == pytest.approx(9.5)
    assert written.provenance["inputs"]["depth_blur"]["n_layers"] > 2
    json.dumps(written.provenance)


def test_blur_depth_command_refuses_conflicting_focus_options(tmp_path, capsys):
    image_path, depth_path = tmp_path / "in.exr", tmp_path / "depth.npy"
    write_image(image_path, texture((8, 8)))
    np.save(depth_path, np.ones((8, 8)))
    code = main(["blur-depth", str(image_path), str(depth_path), "-o", str(tmp_path / "o.exr"), "--rx", "plano",
                 "--pupil-mm", "3", "--arcmin-per-px", "1", "--accommodation-diopters", "1", "--age", "30"])
    _, err = capsys.readouterr()
    assert code == 2 and err.startswith("vissim: error:") and err.count("\n") == 1


def test_crop_px_cuts_the_margin_from_the_result():
    image = texture((40, 50))
    depth = np.full((40, 50), 2.0)
    depth[:, 25:] = 0.5
    kwargs = dict(rx=Prescription(-1.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, mode="geometric")
    whole = blur_depth(image, depth, **kwargs).image
    np.testing.assert_array_equal(blur_depth(image, depth, crop_px=6, **kwargs).image, whole[6:-6, 6:-6])
    with pytest.raises(VissimInputError, match="crop_px"):
        blur_depth(image, depth, crop_px=20, **kwargs)


def test_coarse_grid_for_wide_blurs_stays_within_its_stated_db():
    """White noise (the hardest input: all its energy above any grid's Nyquist) at one depth whose blur
    is vissim.optics.depth.depth_map.COARSE_BLUR_PX (14 px) wide: coarse vs fine >= COARSE_MIN_DB (44 dB); wider
    blurs come closer (20 px: >= 48 dB).  Measured when written: 44.6 dB and 49.3 dB."""
    from vissim.optics.depth.depth_map import COARSE_BLUR_PX, COARSE_MIN_DB

    image = texture((96, 128), seed=7)
    for blur_px, floor_db in ((COARSE_BLUR_PX, COARSE_MIN_DB), (20.0, 48.0)):
        defocus = blur_px * STEP / rad_to_arcmin(PUPIL_MM * 1e-3)  # dioptres that blur this wide
        depth = np.full(image.shape, 1.0 / (2.0 + defocus))
        kwargs = dict(rx=Prescription(-2.0), pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP)
        fine = blur_depth(image, depth, **kwargs)
        coarse = blur_depth(image, depth, coarse_blur_px=COARSE_BLUR_PX - 1e-6, **kwargs)
        assert coarse.layers[0].blur_diameter_arcmin == pytest.approx(blur_px * STEP, rel=1e-9)
        error = (coarse.image - fine.image)[16:-16, 16:-16].astype(np.float64)
        assert 10 * math.log10(1.0 / np.mean(error**2)) >= floor_db


@pytest.mark.parametrize("mode", ["wave", "geometric"])
def test_a_layer_of_opposite_defocus_reuses_the_reflected_psf(mode):
    """|F(P e^{-ikW})(x)|^2 = |F(P e^{ikW})(-x)|^2 and rays land at -grad W: the PSF of -W is that of W
    turned through 180 degrees, so the symmetric plan's mirrored layers need not compute it again."""
    from vissim.optics.depth.psfs import LayerOptics

    base = Wavefront.from_prescription(Prescription(-1.5), PUPIL_MM)
    front = base.with_defocus_diopters(1.5 - 0.6)
    optics = LayerOptics({0: base.with_defocus_diopters(1.5 + 0.6), 1: front}, {0: 1, 1: 1}, PUPIL_MM, 550.0, STEP,
                         mode)
    assert optics.source == {0: None, 1: 0}  # the second layer reflects the first's PSF
    plus, minus = optics.psf(0), optics.psf(1)
    computed = compute_psf(front, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, mode=mode,
                           size_px=suggested_size_px(front, STEP, pupil_diameter_mm=PUPIL_MM))
    assert minus.data.shape[0] % 2 == 1 and minus is not plus
    assert minus.wavefront.coefficients_um == pytest.approx(front.coefficients_um, abs=1e-12)
    # float32 PSFs (the default): the same PSF to its round-off, < 2e-6 of the peak
    np.testing.assert_allclose(minus.data, computed.data, rtol=0, atol=2e-6 * computed.data.max())
    np.testing.assert_array_equal(minus.data, plus.data[::-1, ::-1])


@pytest.mark.parametrize("wavelength_nm", [5.0, -550.0, 3000.0])
def test_blur_depth_refuses_a_wavelength_outside_the_checks_range(wavelength_nm):
    from vissim.checks import WAVELENGTH_RANGE_NM

    image, depth = np.ones((16, 16), np.float32), np.full((16, 16), 2.0)
    with pytest.raises(VissimInputError, match=f"{WAVELENGTH_RANGE_NM[0]:g}.*{WAVELENGTH_RANGE_NM[1]:g}"):
        blur_depth(image, depth, rx=Prescription(-1.0), pupil_diameter_mm=3.0, arcmin_per_px=1.0,
                   wavelength_nm=wavelength_nm)
