"""Depth scenes rendered with Mitsuba: the eye sensor, the depth pass, blur against theory, the CLI.

Small CPU renders with fixed seeds.  Theory: blur diameter = pupil (mm) x |defocus| (D) in
mrad (docs/conventions.md), defocus = K - 1/z with K = A - Rx for an eye and 1/focus for the
DSLR (vissim.bench.depth.scene).  Estimator: the edge-spread function of a panel's straight
edge against the black sky, averaged along the edge and fitted with a uniform disc's ESF
integrated over the pixel (as tests/render/test_dslr_render.py); its noise at 64 spp is
~0.3 % (measured when written), so 3 % is 10x the noise.  For vissim.optics.depth.depth_map.blur_depth, whose
layered compositing reshapes edges against the sky (reported by the depth campaign, not
hidden), the blur is measured instead on the panel's interior: the defocus whose single-plane
geometric blur of the all-in-focus render best matches it there.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest
from scipy.optimize import least_squares, minimize_scalar

from tests.bench.depth_scenes import default_panels_scene, default_tilted_scene
from vissim.bench.depth.scene import (
    ChartPanel,
    DepthScene,
    PanelChart,
    axial_depth_map,
    panel_geometries,
    pixel_tangents,
)
from vissim.bench.depth.viewers import CameraViewer, EyeViewer, viewing_setup
from vissim.bench.depth.scene_dict import depth_scene_dict
from vissim.bench.depth.textures import panel_texture
from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.depth.depth_map import blur_depth
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront
from vissim.render.backend import choose_variant, mitsuba
from vissim.render.depth_render import render_aov_depth, render_depth
from vissim.render.eye_sensor import register_eye_sensor
from vissim.render.run import render_scene

if choose_variant("mono").variant.startswith("scalar"):  # pragma: no cover - machine without LLVM/CUDA
    pytest.skip("no JIT Mitsuba variant: renders would take hours on scalar_rgb", allow_module_level=True)

SPP = 64
SEED = 11
CHART = PanelChart("Z", 0.5, padding_arcmin=14.0)


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


def two_panels(near_m: float, far_m: float) -> DepthScene:
    """``far_m`` on the right, ``near_m`` on the left, both edges toward the frame free against the sky."""
    return DepthScene((ChartPanel(far_m, (50.0, 0.0), CHART), ChartPanel(near_m, (-50.0, 0.0), CHART)),
                      size_px=(96, 224))


_SUB = (np.arange(16) + 0.5) / 16 - 0.5


def _disc_esf(x, radius, x0, amplitude, offset):
    u = np.clip((x[:, None] + _SUB[None, :] - x0) / radius, -1.0, 1.0)
    return offset + amplitude * (0.5 + (u * np.sqrt(1.0 - u * u) + np.arcsin(u)) / np.pi).mean(axis=1)


def edge_blur_px(image, scene: DepthScene, index: int, side: str, expected_px: float) -> float:
    """Blur diameter (px) across one edge of panel ``index`` against the sky (module doc)."""
    g = panel_geometries(scene)[index]
    left, right, bottom, top = g.box_tan
    rows, cols = scene.size_px
    pitch = scene.tan_pitch
    reach = 0.5 * expected_px + 8.0
    if side in ("left", "right"):
        edge = (left if side == "left" else right) / pitch + 0.5 * cols  # in pixel-edge coordinates
        lo, hi = bottom / pitch + 0.5 * expected_px + 3, top / pitch - 0.5 * expected_px - 3
        centres = 0.5 * rows - np.arange(rows) - 0.5
        along = np.arange(rows)[(centres > lo) & (centres < hi)]
        across = np.arange(math.floor(edge - reach), math.ceil(edge + reach))
        profile = np.asarray(image)[np.ix_(along, across)].mean(axis=0)
        x = across + 0.5 - edge
    else:
        edge = 0.5 * rows - (top if side == "top" else bottom) / pitch
        lo, hi = left / pitch + 0.5 * expected_px + 3, right / pitch - 0.5 * expected_px - 3
        centres = np.arange(cols) + 0.5 - 0.5 * cols
        along = np.arange(cols)[(centres > lo) & (centres < hi)]
        across = np.arange(math.floor(edge - reach), math.ceil(edge + reach))
        profile = np.asarray(image)[np.ix_(across, along)].mean(axis=1)
        x = across + 0.5 - edge
    if side in ("right", "bottom"):
        x = -x  # the panel on the positive side
    order = np.argsort(x)
    x, profile = x[order], profile[order]
    fit = least_squares(lambda p: _disc_esf(x, *p) - profile, [max(expected_px, 1.0) / 2, 0.0, np.ptp(profile), 0.0],
                        bounds=([1e-3, -3.0, 0.0, -0.1], [np.inf, 3.0, 2.0, 0.5]))
    return 2.0 * fit.x[0]


def interior_defocus_d(target, all_in_focus, scene: DepthScene, index: int, pupil_mm: float, radius_px: float) -> float:
    """Defocus (D) whose geometric blur of ``all_in_focus`` best matches ``target`` inside panel ``index``."""
    g = panel_geometries(scene)[index]
    tx, ty = pixel_tangents(scene)
    margin = (radius_px + 2.0) * scene.tan_pitch
    left, right, bottom, top = g.box_tan
    region = (((ty > bottom + margin) & (ty < top - margin))[:, None]
              & ((tx > left + margin) & (tx < right - margin))[None])

    def misfit(defocus_d):
        front = Wavefront.from_prescription(Prescription(-defocus_d), pupil_mm)
        psf = compute_psf(front, arcmin_per_px=scene.arcmin_per_px, size_px=2 * int(radius_px) + 15, mode="geometric")
        model = blur_image(all_in_focus, psf, arcmin_per_px=scene.arcmin_per_px, padding="edge")
        return float(np.mean((model[region] - target[region]) ** 2))

    return float(minimize_scalar(misfit, bounds=(0.5, 3.0), method="bounded", options={"xatol": 1e-4}).x)


def test_eye_sensor_is_thinlens_ray_for_ray_and_a_pinhole_without_aperture():
    scene = DepthScene((ChartPanel(0.8, (0.0, 0.0), PanelChart("R", 0.7)),), size_px=(32, 48))
    eye = depth_scene_dict(scene, EyeViewer(Prescription(-2.0), 4.0, 0.0))  # K = 2 D: focused at 500 mm
    thin = depth_scene_dict(scene, EyeViewer(Prescription(-2.0), 4.0, 0.0))
    camera = {k: v for k, v in thin["camera"].items() if not k.startswith("power_")}
    thin["camera"] = dict(camera, type="thinlens", fov_axis="x", focus_distance=500.0)
    register_eye_sensor(mitsuba("mono"))  # render_depth does this; render_scene alone does not
    a, b = (render_scene(s, spp=16, seed=SEED).pixels for s in (eye, thin))
    assert np.abs(a - b).max() < 1e-5 and a.std() > 0.05
    pinhole = depth_scene_dict(scene, EyeViewer(Prescription(-2.0), 4.0, 0.0), view="all_in_focus")
    zero = dict(eye, camera=dict(eye["camera"], aperture_radius=0.0))
    c, d = (render_scene(s, spp=16, seed=SEED).pixels for s in (pinhole, zero))
    assert np.abs(c - d).max() < 1e-5


@pytest.mark.parametrize("scene", [default_panels_scene(), default_tilted_scene()], ids=["panels", "tilted"])
def test_depth_pass_and_aov_give_the_axial_distance_of_the_panels(scene):
    viewer = EyeViewer()
    rendered = render_depth(scene, viewer, spp=4, seed=SEED, blurred=False, depth=True).depth_m
    aov = render_aov_depth(scene, viewer, spp=4, seed=SEED)
    truth, label = axial_depth_map(scene)
    padded = np.pad(label, 1, constant_values=-2)  # pixels on the frame may be partly outside the panel
    windows = np.lib.stride_tricks.sliding_window_view(padded, (3, 3))
    clean = (windows.min(axis=(2, 3)) == windows.max(axis=(2, 3))) & (label >= 0)
    assert clean.sum() > 0.3 * label.size
    for depth in (rendered, aov):
        assert np.abs(depth[clean] / truth[clean] - 1.0).max() < 0.005  # the 0.5 %
    assert np.all(np.isinf(rendered[(windows.max(axis=(2, 3)) < 0)]))  # sky is inf


@pytest.mark.parametrize("scene", [
    DepthScene((ChartPanel(1.0, (0.0, 0.0), PanelChart("R", 1.0)),), size_px=(96, 96)),
    DepthScene((default_tilted_scene().panels[0],), size_px=(96, 192)),
], ids=["panel", "tilted"])
def test_all_in_focus_image_is_the_chart_neither_mirrored_nor_upside_down(scene):
    """The pinhole render is the panel's texture integrated over each pixel (here: 4 x 4 point samples)."""
    image = render_depth(scene, EyeViewer(), spp=4, aux_spp=64, seed=SEED, blurred=False,
                         all_in_focus=True).all_in_focus
    (g,) = panel_geometries(scene)
    texture = panel_texture(g)
    tx, ty = pixel_tangents(scene)
    left, right, bottom, top = g.box_tan
    sub = ((np.arange(4) + 0.5) / 4 - 0.5) * scene.tan_pitch
    cols = np.floor((tx[None, :] + sub[:, None] - left) / (right - left) * texture.shape[1]).astype(int)
    rows = np.floor((top - ty[None, :] - sub[:, None]) / (top - bottom) * texture.shape[0]).astype(int)
    inside = np.all((rows >= 0) & (rows < texture.shape[0]), axis=0)[:, None] & np.all(
        (cols >= 0) & (cols < texture.shape[1]), axis=0)[None]
    rows, cols = np.clip(rows, 0, texture.shape[0] - 1), np.clip(cols, 0, texture.shape[1] - 1)
    correlations = []
    for flipped in (texture, texture[:, ::-1], texture[::-1]):
        expected = np.mean([flipped[r][:, c] for r in rows for c in cols], axis=0)
        correlations.append(np.corrcoef(image[inside], expected[inside])[0, 1])
    assert correlations[0] > 0.99 and max(correlations[1:]) < 0.8
    assert inside.sum() > 0.9 * image.size


def test_myopic_eye_sees_the_half_metre_panel_sharp_and_6m_blurred_by_pupil_times_1_83_d():
    scene = two_panels(0.5, 6.0)
    eye = EyeViewer(Prescription(-2.0), 4.0, 0.0)
    result = render_depth(scene, eye, spp=SPP, seed=SEED, all_in_focus=True, depth=True)
    # 4 mm x 1.833 D = 25.21'
    theory_px = float(viewing_setup(eye).blur_diameter_at_arcmin(6.0)) / scene.arcmin_per_px
    assert theory_px == pytest.approx(25.21, abs=0.01)
    assert edge_blur_px(result.blurred, scene, 0, "right", theory_px) == pytest.approx(theory_px, rel=0.03)
    assert edge_blur_px(result.blurred, scene, 1, "left", 0.0) < 1.0
    # The Fourier side: blur_depth of the all-in-focus render and depth blurs the 6 m panel by the same defocus.
    simulated = blur_depth(result.all_in_focus, result.depth_m, rx=eye.prescription,
                           pupil_diameter_mm=4.0, arcmin_per_px=scene.arcmin_per_px, mode="geometric").image
    radius = 0.5 * theory_px
    for target in (result.blurred, simulated):
        defocus = interior_defocus_d(target, result.all_in_focus, scene, 0, 4.0, radius)
        assert defocus == pytest.approx(2.0 - 1.0 / 6.0, rel=0.03)


def test_emmetrope_accommodating_3_d_sees_the_third_of_a_metre_panel_sharp():
    scene = two_panels(1.0 / 3.0, 0.5)
    eye = EyeViewer(Prescription(0.0), 4.0, 3.0)
    image = render_depth(scene, eye, spp=SPP, seed=SEED).blurred
    assert edge_blur_px(image, scene, 1, "left", 0.0) < 1.0
    theory_px = float(viewing_setup(eye).blur_diameter_at_arcmin(0.5))  # 4 mm x 1 D = 13.75'
    assert edge_blur_px(image, scene, 0, "right", theory_px) == pytest.approx(theory_px, rel=0.03)


def test_relaxed_hyperope_focuses_beyond_infinity():
    """+1.00 DS, A = 0: K = -1 D, so 6 m is blurred by 3 mm x (1 + 1/6) D = 12.03', not x (1 - 1/6) = 8.59'."""
    scene = two_panels(0.5, 6.0)
    image = render_depth(scene, EyeViewer(Prescription(1.0), 3.0, 0.0), spp=SPP, seed=SEED).blurred
    assert edge_blur_px(image, scene, 0, "right", 12.03) == pytest.approx(12.03, rel=0.03)


def test_astigmatic_eye_blurs_across_the_cylinder_axis():
    """plano -2.00 x 90: excess power 2 D in the horizontal meridian -> horizontal blur only (conventions)."""
    scene = two_panels(0.5, 6.0)
    image = render_depth(scene, EyeViewer(Prescription(0.0, -2.0, 90.0), 4.0, 0.0), spp=SPP, seed=SEED).blurred
    horizontal = float(viewing_setup(EyeViewer(Prescription(-2.0), 4.0)).blur_diameter_at_arcmin(6.0))  # 4 mm x 1.83
    vertical = float(4.0 / 6.0 * 180 * 60 / math.pi / 1000)  # 4 mm x 1/6 D = 2.29'
    assert edge_blur_px(image, scene, 0, "right", horizontal) == pytest.approx(horizontal, rel=0.03)
    assert edge_blur_px(image, scene, 0, "top", vertical) == pytest.approx(vertical, abs=0.3)


def test_dslr_focused_at_3_ft_blurs_near_and_far_panels_by_its_entrance_pupil():
    scene = two_panels(0.5, 6.0)
    camera = CameraViewer(f_number=5.0, focus_distance_m=0.9144)
    image = render_depth(scene, camera, spp=SPP, seed=SEED).blurred
    for index, side, distance in ((0, "right", 6.0), (1, "left", 0.5)):
        theory = float(viewing_setup(camera, scene).blur_diameter_at_arcmin(distance))  # 3.6 mm x |1.094 - 1/d| D
        assert edge_blur_px(image, scene, index, side, theory) == pytest.approx(theory, rel=0.03)


def _cli(argv):
    from vissim.cli import _protect_negative_values
    from vissim.cli.render_depth import add_depth_parser

    parser = argparse.ArgumentParser(prog="throwaway")
    add_depth_parser(parser.add_subparsers())
    args = parser.parse_args(_protect_negative_values(["depth", *argv]))
    return args.func(args)


def test_render_depth_command_writes_blurred_all_in_focus_and_depth(tmp_path, capsys):
    from pathlib import Path

    from vissim.cli.blur_depth import read_depth_m
    from vissim.imageio import read_image

    scene = Path(__file__).resolve().parents[2] / "scenes" / "depth_panels.toml"
    out, aif, depth = tmp_path / "blur.exr", tmp_path / "aif.exr", tmp_path / "depth.exr"
    argv = [str(scene), "--rx", "-1.00 DS", "--pupil-mm", "3", "--spp", "4", "--aux-spp", "4", "-o", str(out),
            "--all-in-focus", str(aif), "--depth", str(depth)]
    assert _cli(argv) == 0
    printed = capsys.readouterr().out
    assert "wrote" in printed and "panel 6 m: predicted blur diameter 8.6'" in printed  # 3 mm x (1 - 1/6) D
    # The all-in-focus image and the depth extend beyond the frame by the largest blur radius + 2 px:
    # the 0.4 m panel's 3 mm x |1 - 2.5| D = 15.5 arcmin disc, radius 7.7 -> 8 + 2 = 10 px.
    assert "a 10 px margin beyond the frame" in printed
    blurred, sharp = read_image(out), read_image(aif)
    assert blurred.pixels.shape == (128, 192) and sharp.pixels.shape == (148, 212)
    inputs = blurred.provenance["inputs"]
    assert inputs["viewer"]["prescription"]["sphere_diopters"] == -1.0 and inputs["arcmin_per_px"] == 1.0
    assert inputs["margin_px"] == 10 and sharp.provenance["inputs"]["margin_px"] == 10
    distances = read_depth_m(depth)
    assert distances.shape == (148, 212) and np.isinf(distances).any()
    assert distances[np.isfinite(distances)].min() == pytest.approx(0.4, rel=1e-5)
    # blur-depth reads the margin from the input's provenance and crops its output to the frame
    from vissim.cli import main

    simulated = tmp_path / "sim.exr"
    assert main(["blur-depth", str(aif), str(depth), "-o", str(simulated), "--rx", "-1.00 DS", "--pupil-mm", "3",
                 "--mode", "geometric"]) == 0
    assert read_image(simulated).pixels.shape == (128, 192)
    with pytest.raises(VissimInputError, match="already exists"):
        _cli(argv)
    with pytest.raises(VissimInputError, match="not both"):
        _cli([str(scene), "--rx", "plano", "--f-number", "4", "-o", str(tmp_path / "x.exr")])
    with pytest.raises(VissimInputError, match=r"\.exr"):
        _cli([str(scene), "-o", str(tmp_path / "x.png")])


def test_layers_rendered_alone_composite_to_the_all_in_focus_render():
    """Each panel alone (radiance, coverage): over-composited near to far with no blur, they are the pinhole
    render of the whole scene (to its edge sampling noise), and the far panel is there behind the near one."""
    scene = default_panels_scene((3.0, 0.5), size_px=(96, 128))  # overlapping: the 0.5 m panel hides part of the 3 m
    result = render_depth(scene, EyeViewer(pupil_diameter_mm=3.0), spp=SPP, seed=SEED, blurred=False,
                          all_in_focus=True, layers=True, margin_px=4)
    assert result.all_in_focus.shape == (scene.size_px[0] + 8, scene.size_px[1] + 8) and result.margin_px == 4
    (far, near), (far_cover, near_cover) = result.layer_radiance, result.layer_coverage  # scene order: far first
    assert near_cover.max() == pytest.approx(1.0) and far_cover.max() == pytest.approx(1.0)
    hidden = (near_cover > 0.999) & (far_cover > 0.999)
    assert hidden.sum() > 100  # the far panel behind the near one: what an RGB-D image cannot hold
    composite = near + (1.0 - near_cover) * far
    assert np.abs(composite - result.all_in_focus).mean() < 2e-3
