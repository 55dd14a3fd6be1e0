"""Layered depth blur (vissim.optics.depth.layered): the pupil-ray composite of layers rendered alone.

Expected values and where they come from:

* one layer alone: the convolution with its pixel-integrated geometric PSF (``compute_psf``,
  ``mode="geometric"``), since the histogram of the rays' rounded offsets is that PSF; to
  float32 round-off (abs 1e-5);
* an in-focus near layer over a blurred far one: ``C_near + (1 - A_near) (C_far * G_far)``,
  the thin-lens image when the occluder's parallax is zero (every ray meets it where the
  pixel looks); abs 1e-5;
* a blurred opaque black near layer over a uniform far layer of 1: ``1 - A_near * G_near``
  (every ray that misses the occluder sees 1); abs 1e-5;
* a far layer's thin bright line just behind a blurred opaque near edge, the line in focus:
  the pixel on the line sees it through the part of the pupil whose rays pass beside the
  edge, the circular segment ``(acos(t) - t sqrt(1 - t^2)) / pi`` of the blur disc (t = the
  line's distance from the edge over the disc radius, in pixels); 2 % (whole-pixel rounding
  of ~11 px offsets);
* wave optics: layers that do not overlap get exactly their own wave blur; a layer hidden
  by an opaque in-focus layer contributes nothing in the occluder's interior.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.depth.depth_map import blur_depth
from vissim.optics.depth.layered import SceneLayer, composite_layers
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront

PUPIL_MM = 4.0
STEP = 1.0
EYE = Prescription(-2.0)  # focuses 0.5 m (2 D)
ATOL = 1e-5
SHAPE = (72, 96)


def psf_at(proximity_diopters, mode="geometric", eye=EYE):
    front = Wavefront.from_prescription(eye, PUPIL_MM).with_defocus_diopters(proximity_diopters)
    size = suggested_size_px(front, STEP, pupil_diameter_mm=PUPIL_MM)
    return compute_psf(front, pupil_diameter_mm=PUPIL_MM, arcmin_per_px=STEP, size_px=size, mode=mode)


def blur(image, psf):
    return blur_image(image, psf, arcmin_per_px=STEP, padding="constant", background=0.0)


def composite(layers, **kwargs):
    kwargs = {"rx": EYE, "pupil_diameter_mm": PUPIL_MM, "arcmin_per_px": STEP} | kwargs
    return composite_layers(layers, **kwargs)


def texture(seed=0):
    return np.random.default_rng(seed).random(SHAPE).astype(np.float32)


def test_one_layer_is_its_geometric_psf_blur():
    image = texture()
    out = composite([SceneLayer(image, np.ones(SHAPE, np.float32), 0.5)]).image
    np.testing.assert_allclose(out, blur(image, psf_at(0.5)), atol=ATOL)


def test_in_focus_near_layer_over_a_blurred_far_layer():
    far, near = texture(1), texture(2)
    cover = np.zeros(SHAPE, np.float32)
    cover[:, :40] = 1.0
    cover[:, 40] = 0.5  # a pixel the edge crosses
    result = composite([SceneLayer(far, np.ones(SHAPE, np.float32), 0.2), SceneLayer(near * cover, cover, 2.0)])
    expected = near * cover + (1.0 - cover) * blur(far, psf_at(0.2))
    np.testing.assert_allclose(result.image, expected, atol=ATOL)
    assert result.n_layers == 2 and result.overlapping_layers == 1


def test_blurred_black_occluder_over_a_uniform_far_layer_of_one():
    cover = np.zeros(SHAPE, np.float32)
    cover[20:50, 30:60] = 1.0
    ones = np.ones(SHAPE, np.float32)
    out = composite([SceneLayer(np.zeros(SHAPE, np.float32), cover, 3.0), SceneLayer(ones, ones, 2.0)]).image
    expected = 1.0 - blur(cover, psf_at(3.0))
    np.testing.assert_allclose(out[10:-10, 10:-10], expected[10:-10, 10:-10], atol=ATOL)  # far blur of 1 is 1 there


@pytest.mark.parametrize("gap_px", [1, 3, 5])
def test_a_line_behind_a_blurred_edge_shows_through_a_circular_segment_of_the_pupil(gap_px):
    near_d = 3.0  # 1 D from the 2 D focus: a disc of 4 mm x 1 D = 13.75 arcmin
    radius_px = 0.5 * PUPIL_MM * 1.0 * 180 * 60 / math.pi / 1000.0 / STEP
    edge = 48
    cover = np.zeros(SHAPE, np.float32)
    cover[:, :edge] = 1.0
    line = np.zeros(SHAPE, np.float32)
    line[:, edge + gap_px] = 1.0
    ones = np.ones(SHAPE, np.float32)
    out = composite([SceneLayer(np.zeros(SHAPE, np.float32), cover, near_d), SceneLayer(line, ones, 2.0)]).image
    t = (gap_px + 0.5) / radius_px  # the line's centre from the edge (between pixels edge - 1 and edge)
    hidden = (math.acos(t) - t * math.sqrt(1 - t * t)) / math.pi
    assert out[SHAPE[0] // 2, edge + gap_px] == pytest.approx(1.0 - hidden, abs=0.02)


def test_a_slanted_layer_alone_is_blur_depth_of_its_depth_map():
    """No occluder: its slices add, each with its own blur, as blur_depth's layers do on a gentle slope."""
    image = texture(3)
    proximity = np.broadcast_to(np.linspace(1.5, 2.5, SHAPE[1]), SHAPE)
    ones = np.ones(SHAPE, np.float32)
    out = composite([SceneLayer(image, ones, proximity)]).image
    reference = blur_depth(image, 1.0 / proximity, rx=EYE, pupil_diameter_mm=PUPIL_MM,
                           arcmin_per_px=STEP, mode="geometric", occlusion_threshold_px=100.0).image
    inner = (slice(12, -12), slice(12, -12))  # away from the grids' borders (zero vs edge padding)
    np.testing.assert_allclose(out[inner], reference[inner], atol=1e-4)


def test_wave_layers_that_do_not_overlap_get_their_own_wave_blur():
    left, right = np.zeros(SHAPE, np.float32), np.zeros(SHAPE, np.float32)
    left[20:50, 5:25], right[20:50, 65:90] = 1.0, 1.0
    c_left, c_right = texture(4) * left, texture(5) * right
    out = composite([SceneLayer(c_left, left, 2.3), SceneLayer(c_right, right, 1.8)], mode="wave")
    expected = blur(c_left, psf_at(2.3, "wave")) + blur(c_right, psf_at(1.8, "wave"))
    np.testing.assert_allclose(out.image, expected, atol=ATOL)
    assert out.overlapping_layers == 0


def test_wave_light_behind_an_opaque_in_focus_layer_stays_hidden():
    cover = np.zeros(SHAPE, np.float32)
    cover[10:62, 10:86] = 1.0
    near = np.full(SHAPE, 0.5, np.float32) * cover
    far = texture(6)
    ones = np.ones(SHAPE, np.float32)
    out = composite([SceneLayer(near, cover, 2.0), SceneLayer(far, ones, 0.2)], mode="wave").image
    inside = blur(near, psf_at(2.0, "wave"))[30:42, 35:60]  # in focus: diffraction only
    np.testing.assert_allclose(out[30:42, 35:60], inside, atol=1e-4)


def test_layers_are_sorted_near_to_far_and_cropped():
    far, near = texture(7), texture(8)
    cover = np.zeros(SHAPE, np.float32)
    cover[:, :40] = 1.0
    ones = np.ones(SHAPE, np.float32)
    a = composite([SceneLayer(far, ones, 0.2), SceneLayer(near * cover, cover, 2.0)]).image
    b = composite([SceneLayer(near * cover, cover, 2.0), SceneLayer(far, ones, 0.2)], crop_px=6).image
    np.testing.assert_array_equal(a[6:-6, 6:-6], b)


def test_rgb_layers_composite_each_channel():
    rgb = np.stack([texture(9), texture(10), texture(11)], axis=-1)
    ones = np.ones(SHAPE, np.float32)
    out = composite([SceneLayer(rgb, ones, 1.0)]).image
    assert out.shape == SHAPE + (3,)
    np.testing.assert_allclose(out[..., 1], blur(rgb[..., 1], psf_at(1.0)), atol=ATOL)


@pytest.mark.parametrize("layers, message", [
    ([], "at least one layer"),
    ([SceneLayer(np.ones((4, 4)), np.ones((4, 5)), 1.0)], "share a grid"),
    ([SceneLayer(np.ones((4, 4)), np.full((4, 4), 2.0), 1.0)], r"coverage must lie in \[0, 1\]"),
    ([SceneLayer(np.ones((4, 4)), np.ones((4, 4)), -1.0)], "dioptres >= 0"),
    ([SceneLayer(np.ones((4, 4)), np.ones((4, 4)), np.ones((3, 3)))], "proximity must be one value"),
    ([SceneLayer(np.ones((4, 4)), np.ones((4, 4)), 1.0), SceneLayer(np.ones((5, 5)), np.ones((5, 5)), 1.0)], "differs"),
])
def test_bad_layers_are_refused_with_the_reason(layers, message):
    with pytest.raises(VissimInputError, match=message):
        composite(layers)
