"""Depth scenes (charts at several distances, a tilted chart) as plain dicts, without rendering.

Expected values: letter heights from vissim.acuity.letter_height_mm (LogMAR 0.5 = 15.81 arcmin:
27.6 mm at 6 m, 1.84 mm at 0.4 m); the eye focuses proximity K = A - Rx (docs/conventions.md:
an eye corrected by Rx with accommodation A is blurred like Rx + 1/d - A); blur diameter =
pupil (mm) x defocus (D) in mrad.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from vissim.acuity import letter_height_mm
from tests.bench.depth_scenes import default_panels_scene, default_tilted_scene
from vissim.bench.depth.scene import (
    ChartPanel,
    DepthScene,
    PanelChart,
    TiltedChart,
    axial_depth_map,
    panel_geometries,
    pixel_tangents,
)
from vissim.bench.depth.scene_dict import depth_scene_dict, tilted_mesh
from vissim.bench.depth.scene_files import load_depth_scene_toml
from vissim.bench.depth.textures import panel_texture
from vissim.bench.depth.viewers import CameraViewer, EyeViewer, equivalent_eye, viewing_setup
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import TrialLens
from vissim.units import rad_to_arcmin


def effective_prescription(rx, distance_m, accommodation_diopters=0.0):
    """Oracle, written out (not vissim's code): Rx + 1/d - A on the sphere (docs/conventions.md, Depth)."""
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    return Prescription(rx.sphere_diopters + proximity - accommodation_diopters, rx.cylinder_diopters, rx.axis_deg)

SCENES = Path(__file__).resolve().parents[2] / "scenes"


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


def test_each_panel_is_printed_for_its_own_distance():
    scene = default_panels_scene()
    geometries = panel_geometries(scene)
    assert sorted(g.distance_left_m for g in geometries) == [0.4, 0.9144, 2.0, 6.0]
    for g in geometries:
        assert g.letter_height_mm == pytest.approx(letter_height_mm(0.5, g.distance_left_m), rel=1e-9)
        texel = 1000.0 * g.distance_left_m * scene.tan_pitch / scene.texels_per_px
        assert g.size_mm == pytest.approx((g.texture_shape[0] * texel, g.texture_shape[1] * texel))
        assert panel_texture(g).shape == g.texture_shape
    # One LogMAR everywhere: the panels subtend the same angle (to a texel), whatever their distance.
    widths = [g.box_arcmin[1] - g.box_arcmin[0] for g in geometries]
    assert max(widths) - min(widths) < 1.0 / scene.texels_per_px
    assert geometries[0].letter_height_mm == pytest.approx(27.6, abs=0.05)  # 6 m


def test_nearer_panels_hide_the_farther_ones_where_they_overlap():
    scene = default_panels_scene()
    depth, label = axial_depth_map(scene)
    geometries = sorted(panel_geometries(scene), key=lambda g: g.distance_left_m)  # near to far
    for near, far in zip(geometries, geometries[1:]):
        nl, nr, nb, nt = near.box_tan
        fl, fr, fb, ft = far.box_tan
        assert nl < fr and fl < nr and nb < ft and fb < nt  # the boxes overlap ...
        tx, ty = pixel_tangents(scene)
        overlap = ((ty > max(nb, fb)) & (ty <= min(nt, ft)))[:, None] & ((tx >= max(nl, fl)) & (tx < min(nr, fr)))[None]
        assert overlap.sum() > 50 and np.all(label[overlap] == near.index)  # ... and the nearer one shows there
    for g in geometries:
        visible = label == g.index
        assert visible.sum() > 1000 and np.all(depth[visible] == g.distance_left_m)
    assert np.all(np.isinf(depth[label < 0]))


def test_tilted_chart_spans_its_depths_continuously_across_the_image():
    scene = default_tilted_scene()
    (g,) = panel_geometries(scene)
    left, right = g.box_tan[:2]
    assert g.axial_distance_m(left) == pytest.approx(0.5) and g.axial_distance_m(right) == pytest.approx(3.0)
    depth, label = axial_depth_map(scene)
    row = depth[scene.size_px[0] // 2]
    inside = np.isfinite(row)
    assert inside.sum() >= 185 and np.all(np.diff(row[inside]) > 0)  # farther to the right
    assert row[inside][0] < 0.51 and row[inside][-1] > 2.9
    assert np.allclose(np.diff(1.0 / row[inside], 2), 0.0, atol=1e-9)  # a plane: 1/z linear in the tangent
    vertices, normals, uv, faces = tilted_mesh(g, 64)
    x, y, z = vertices.T
    (a, b), *_ = np.linalg.lstsq(np.stack([z, -x], 1), np.ones(len(z)), rcond=None)
    assert np.allclose(a * z - b * x, 1.0, atol=1e-9)  # one plane, turned about the vertical axis
    assert np.allclose(uv[:, 0], (-x / z - left) / (right - left), atol=1e-6)  # u = image tangent (right)
    assert np.allclose(uv[:, 1], (g.box_tan[3] - y / z) / (g.box_tan[3] - g.box_tan[2]), atol=1e-6)  # v: top = 0
    assert np.all(np.einsum("ij,ij->i", normals, -vertices) > 0)  # faces the observer at the origin
    v = vertices[faces]
    assert np.all(np.einsum("ij,ij->i", np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), normals[faces[:, 0]]) > 0)
    assert math.degrees(math.atan2(b, a)) == pytest.approx(-87.0, abs=1.0)  # nearly along the line of sight


def test_eye_focuses_accommodation_minus_prescription():
    """Sign: a -2 D myope focuses 0.5 m; +3 D accommodation focuses 1/3 m; a relaxed +1 D hyperope focuses
    'beyond infinity' (K = -1 D), so its blur at 6 m is pupil x (1 + 1/6) D, not x (1 - 1/6)."""
    myope = viewing_setup(EyeViewer(Prescription(-2.0), 4.0, 0.0))
    assert np.allclose(myope.focus_matrix_diopters, 2.0 * np.eye(2))
    assert myope.blur_diameter_at_arcmin(0.5) == pytest.approx(0.0, abs=1e-12)
    assert myope.blur_diameter_at_arcmin(6.0) == pytest.approx(rad_to_arcmin(4e-3 * (2.0 - 1.0 / 6.0)))  # 25.21'
    assert float(myope.blur_diameter_at_arcmin(6.0)) == pytest.approx(25.21, abs=0.01)
    accommodating = viewing_setup(EyeViewer(Prescription(0.0), 4.0, 3.0))
    assert accommodating.blur_diameter_at_arcmin(1.0 / 3.0) == pytest.approx(0.0, abs=1e-12)
    hyperope = viewing_setup(EyeViewer(Prescription(1.0), 3.0, 0.0))
    assert np.allclose(hyperope.focus_matrix_diopters, -np.eye(2))
    assert hyperope.blur_diameter_at_arcmin(6.0) == pytest.approx(rad_to_arcmin(3e-3 * (1.0 + 1.0 / 6.0)))
    assert hyperope.blur_diameter_at_arcmin(math.inf) == pytest.approx(rad_to_arcmin(3e-3))
    # plano -2.00 x 90 corrects excess power in the horizontal (x) meridian only.
    astigmat = viewing_setup(EyeViewer(Prescription(0.0, -2.0, 90.0)))
    assert np.allclose(astigmat.focus_matrix_diopters, [[2.0, 0.0], [0.0, 0.0]])
    # The eye sensor's K agrees with the written-out Rx + 1/d - A: that defocus vanishes where 1/d = K.
    rx = Prescription(-1.0, -1.0, 30.0)
    eye = EyeViewer(rx, 3.0, 0.5)
    for k in np.linalg.eigvalsh(viewing_setup(eye).focus_matrix_diopters):
        effective = effective_prescription(rx, 1.0 / k, 0.5)
        assert min(abs(effective.meridian_power(m)) for m in np.arange(0.0, 180.0, 0.5)) < 1e-3


def test_dslr_is_simulated_as_the_eye_of_minus_its_focus_vergence():
    camera = CameraViewer(f_number=5.0, focus_distance_m=2.0)
    eye = equivalent_eye(camera)
    assert eye.pupil_diameter_mm == pytest.approx(3.6) and eye.accommodation_diopters == 0.0
    assert eye.prescription.sphere_diopters == pytest.approx(-0.5) and eye.prescription.cylinder_diopters == 0.0
    assert effective_prescription(eye.prescription, 2.0).spherical_equivalent_diopters == pytest.approx(0.0)
    plus = CameraViewer(focus_distance_m=2.0, lenses=(TrialLens(1.0),))
    assert viewing_setup(plus).focus_matrix_diopters[0, 0] == pytest.approx(1.5, abs=0.02)  # a plus lens: myopic


def test_scene_dicts_for_the_eye_and_the_dslr():
    scene = default_panels_scene()
    eye = depth_scene_dict(scene, EyeViewer(Prescription(-1.0, -0.5, 180.0), 5.0, 0.25))
    camera = eye["camera"]
    assert camera["type"] == "vissim_eye" and camera["aperture_radius"] == 2.5
    assert (camera["power_xx_diopters"], camera["power_xy_diopters"], camera["power_yy_diopters"]) == pytest.approx(
        (1.25, 0.0, 1.75))  # A - Rx: -0.5 cyl x 180 corrects the vertical meridian
    pinhole = depth_scene_dict(scene, EyeViewer(), view="all_in_focus")["camera"]
    assert pinhole["type"] == "perspective" and pinhole["fov"] == camera["fov"] and pinhole["film"] == camera["film"]
    assert math.tan(math.radians(pinhole["fov"] / 2)) == pytest.approx(96 * math.tan(math.radians(1 / 60)))
    assert (pinhole["film"]["height"], pinhole["film"]["width"]) == (128, 192)
    dslr = depth_scene_dict(scene, CameraViewer(lenses=(TrialLens(1.0),)))
    assert dslr["camera"]["type"] == "thinlens" and dslr["camera"]["aperture_radius"] == pytest.approx(1.8)
    assert dslr["camera"]["focus_distance"] == pytest.approx(914.4) and "lens_0" in dslr and "chart" not in dslr
    assert "lens_0" in depth_scene_dict(scene, CameraViewer(lenses=(TrialLens(1.0),)), view="all_in_focus")
    proximity = depth_scene_dict(scene, EyeViewer(), view="all_in_focus", content="proximity")
    for g in panel_geometries(scene):
        assert proximity[f"panel_{g.index}"]["emitter"]["radiance"] == pytest.approx(1.0 / g.distance_left_m)
        assert eye[f"panel_{g.index}"]["to_world"][2][3] == pytest.approx(1000.0 * g.distance_left_m)
    tilted = depth_scene_dict(default_tilted_scene(), EyeViewer(), content="proximity")["panel_0"]
    ramp = tilted["emitter"]["radiance"]["data"][0, :, 0]
    assert Path(tilted["filename"]).is_file() and ramp[0] == pytest.approx(2.0, abs=2e-3)
    assert ramp[-1] == pytest.approx(1.0 / 3.0, abs=2e-3)


@pytest.mark.parametrize("make, message", [
    (lambda: ChartPanel(-1.0), "panel distance"),
    (lambda: PanelChart(""), "at least one Sloan letter"),
    (lambda: PanelChart("E"), "Sloan"),
    (lambda: PanelChart(padding_arcmin=-1.0), "arcmin"),
    (lambda: TiltedChart(0.5, 0.0), "distance right m"),
    (lambda: DepthScene((ChartPanel(1.0),), size_px=(0, 5)), "size_px"),
    (lambda: EyeViewer(Prescription(0.0), 4.0, -1.0), "accommodation"),
    (lambda: EyeViewer(Prescription(0.0), 0.0), "pupil"),
    (lambda: depth_scene_dict(default_panels_scene(), EyeViewer(), view="sideways"), "view"),
])
def test_bad_input_names_the_value_and_its_unit(make, message):
    with pytest.raises(VissimInputError, match=message) as info:
        make()
    assert "\n" not in str(info.value)


def test_scene_files_are_the_default_scenes():
    panels = load_depth_scene_toml(SCENES / "depth_panels.toml")
    assert panels.scene == default_panels_scene()
    assert panels.viewer == EyeViewer(Prescription(-2.0), 4.0, 0.0) and panels.spp == 64
    tilted = load_depth_scene_toml(SCENES / "depth_tilted.toml", spp=8)
    assert tilted.scene == default_tilted_scene() and tilted.spp == 8
    assert tilted.viewer == EyeViewer(Prescription(0.0), 4.0, 1.0)


@pytest.mark.parametrize("text, message", [
    ("[[panel]]\ndistance_m = 1.0\ncolour = 'red'\n", "unknown key 'colour'"),
    ("[[panel]]\ndistance_m = 'far'\n", "distance_m must be a number in m"),
    ("[eye]\n[camera]\n[[panel]]\ndistance_m = 1.0\n", "not both"),
    ("[image]\nsize_px = [10]\n[[panel]]\ndistance_m = 1.0\n", "size_px"),
    ("[eye]\n", "no panels"),
])
def test_bad_scene_files_name_file_key_and_unit(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=message) as info:
        load_depth_scene_toml(path)
    assert str(path) in str(info.value)


def test_a_camera_scene_file_with_a_trial_lens(tmp_path):
    path = tmp_path / "camera.toml"
    path.write_text("[camera]\nf_number = 4.0\nfocus_distance_m = 2.0\n[[camera.lenses]]\nsphere_diopters = 1.0\n"
                    "[[tilted]]\ndistance_left_m = 1.0\ndistance_right_m = 2.0\nletters = 'CKNOR'\n")
    loaded = load_depth_scene_toml(path)
    assert loaded.viewer == CameraViewer(f_number=4.0, focus_distance_m=2.0, lenses=(TrialLens(1.0),))
    assert dataclasses.replace(loaded.scene.panels[0]).chart.letters == "CKNOR"


def test_a_margin_adds_pixels_around_the_same_frame():
    from vissim.bench.depth.scene import pixel_tangents

    scene = default_panels_scene()
    wide = scene.with_margin(7)
    assert wide.size_px == (scene.size_px[0] + 14, scene.size_px[1] + 14) and scene.with_margin(0) is scene
    (tx, ty), (wx, wy) = pixel_tangents(scene), pixel_tangents(wide)
    np.testing.assert_allclose(wx[7:-7], tx, rtol=0, atol=1e-15)
    np.testing.assert_allclose(wy[7:-7], ty, rtol=0, atol=1e-15)
    with pytest.raises(VissimInputError, match="whole number of pixels"):
        scene.with_margin(-1)


def test_frame_margin_holds_the_largest_blur_radius():
    """-2 D myope, 4 mm: the 0.4 m panel is |2 - 2.5| D, the 6 m one |2 - 1/6| D = 1.833 D:
    4 mm x 1.833 D = 7.33 mrad = 25.2 arcmin, radius 12.6 px -> 13 + 2."""
    from vissim.bench.depth.viewers import frame_margin_px

    scene = default_panels_scene()
    assert frame_margin_px(EyeViewer(Prescription(-2.0), 4.0, 0.0), scene) == 13 + 2
    # tilted 0.5-3 m, emmetrope accommodating 2.5 D: |2.5 - 1/3| D = 2.167 D -> 29.8 arcmin, radius 14.9 px
    assert frame_margin_px(EyeViewer(Prescription(0.0), 4.0, 2.5), default_tilted_scene(0.5, 3.0)) == 15 + 2


def test_a_layer_is_one_panel_and_its_coverage_glows_with_one():
    scene = default_panels_scene()
    layer = depth_scene_dict(scene, EyeViewer(), view="all_in_focus", content="coverage", panels=(2,))
    assert [k for k in layer if k.startswith("panel_")] == ["panel_2"]
    assert layer["panel_2"]["emitter"] == {"type": "area", "radiance": 1.0}
    with pytest.raises(VissimInputError, match="not indices"):
        depth_scene_dict(scene, EyeViewer(), panels=(7,))
