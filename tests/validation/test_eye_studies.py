"""The eye studies on renders (scripts/eye_studies, outside the package): their measuring tools against
analytic answers (fast), and each study's must-show threshold on real renders (slow, ``-m slow``)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from vissim.validation.engine.summary import PERFECT_MARGIN_DB
from scipy.special import ndtr

from vissim.optics.eyes.models import eye_model
from vissim.render.backend import find_libllvm

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # the studies are scripts, imported as the package ``scripts.eye_studies``
    sys.path.insert(0, str(ROOT))

from scripts.eye_studies.edge import BIN_PX, edge_mtf, traced_rays_deg  # noqa: E402
from scripts.eye_studies.focus import (denoised_gradient_energy, gaussian_peak, gradient_energy,  # noqa: E402
                                       predicted_best_sphere_diopters, sphere_lattice)
from scripts.eye_studies.scenes import ChartRaster, ideal_image, pixel_directions  # noqa: E402

needs_llvm = pytest.mark.skipif(find_libllvm() is None, reason="no usable libLLVM: llvm variants unavailable")


def test_gaussian_peak_finds_a_gaussian_between_samples():
    spheres = sphere_lattice([-0.4], 0.375, 0.0625)
    scores = 3.0 * np.exp(-0.5 * ((spheres + 0.4137) / 0.09) ** 2)  # log is a parabola: exact
    assert gaussian_peak(spheres, scores) == pytest.approx(-0.4137, abs=1e-9)
    assert np.allclose(np.diff(spheres), 0.0625) and spheres[0] <= -0.775 and spheres[-1] >= -0.025


def test_gaussian_peak_refuses_a_sweep_whose_best_is_at_its_end():
    with pytest.raises(Exception, match="sweep's end"):
        gaussian_peak([0.0, 0.1, 0.2, 0.3, 0.4], [1.0, 2.0, 3.0, 4.0, 5.0])


def test_denoised_gradient_energy_removes_the_noise_share():
    rng = np.random.default_rng(3)
    clean = np.zeros((64, 64))
    clean[:, 32:] = 1.0  # gradient energy: one unit step per row -> 64
    a = clean + rng.normal(0.0, 0.05, clean.shape)
    b = clean + rng.normal(0.0, 0.05, clean.shape)
    assert gradient_energy(clean, 1.0) == pytest.approx(64.0)
    assert gradient_energy(a, 1.0) > 64.0 + 15.0  # the noise's share: 2 x 2 x 0.05^2 x 4032 ~ 40
    assert denoised_gradient_energy(a, b, 1.0) == pytest.approx(64.0, abs=3.0)


def test_predicted_best_sphere_at_550_nm_is_the_thin_lens_vergence_rule():
    """Oracle: a thin lens at 12 mm, the eye's paraxial refraction K at the cornea (y-nu matrices)
    and the chart's vergence V at the lens: S = V_far - V with V_far = K / (1 + 0.012 K)."""
    from vissim.optics.eyes.paraxial import refraction_diopters

    k = refraction_diopters(eye_model("navarro-1985"), 550.0)
    far_point = k / (1.0 + 0.012 * k)
    thin = far_point - (-1.0 / (6.0 - 0.012))
    assert predicted_best_sphere_diopters("navarro-1985", 550.0, 6.0) == pytest.approx(thin, abs=0.001)  # 4e-5


def _slanted_edge_image(sigma_px: float, angle_deg: float, size: int = 96, sub: int = 8) -> np.ndarray:
    """A dark-to-bright edge through the centre, Gaussian LSF of ``sigma_px``, each pixel the mean of sub² points."""
    rows, cols = (np.indices((size * sub, size * sub), dtype=float) + 0.5) / sub
    y, x = rows - 0.5 * size, cols - 0.5 * size
    s = x * math.cos(math.radians(angle_deg)) + y * math.sin(math.radians(angle_deg))
    return ndtr(s / sigma_px).reshape(size, sub, size, sub).mean(axis=(1, 3))


def test_edge_mtf_of_a_gaussian_edge_is_the_gaussian_times_the_pixel():
    """Oracle: MTF = exp(-2 pi^2 sigma^2 f^2) x the box pixel's (sinc along the normal's two components)
    x the quarter-pixel bins' two sincs (averaging and differencing), f in cycles per pixel."""
    sigma_px, angle = 1.5, 5.0
    result = edge_mtf(_slanted_edge_image(sigma_px, angle), arcmin_per_px=1.0)
    f = result.frequencies_cyc_per_deg / 60.0  # cycles per pixel at 1 arcmin/px
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    expected = np.exp(-2.0 * (math.pi * sigma_px * f) ** 2) * np.sinc(f * c) * np.sinc(f * s) * np.sinc(f * BIN_PX) ** 2
    band = f <= 0.3
    assert abs(abs(result.edge_angle_deg) - angle) < 0.05
    assert np.max(np.abs(result.mtf[band] - expected[band])) < 0.005  # 0.003; 0.012 without the pixel's terms


def test_traced_psf_is_centred_and_its_scale_is_the_paraxial_one():
    """On axis a centred eye's ray landing offsets average to ~0; their RMS radius changes with the pupil;
    and the traced mm/deg the offsets are divided by agrees with the paraxial one to 1 %."""
    from vissim.optics.eyes.paraxial import retinal_mm_per_deg

    small = traced_rays_deg("navarro-1985", 2.0, 550.0, rays_across=31)
    large = traced_rays_deg("navarro-1985", 4.0, 550.0, rays_across=31)
    assert np.all(np.abs(large.mean(axis=0)) < 1e-6)
    assert np.sqrt(np.mean(np.sum(large**2, axis=1))) > 1.5 * np.sqrt(np.mean(np.sum(small**2, axis=1)))
    from vissim.optics.eyes.traced_wavefront import trace_to_retina

    eye = eye_model("navarro-1985")
    centre = trace_to_retina(eye, np.array([[0.0, 0.0]]), 550.0, field_deg=(0.0, 0.0))[0].points_mm
    tilted = trace_to_retina(eye, np.array([[0.0, 0.0]]), 550.0, field_deg=(0.5, 0.0))[0].points_mm
    assert abs(tilted[0, 0] - centre[0, 0]) / 0.5 == pytest.approx(retinal_mm_per_deg(eye, 550.0), rel=0.01)


@pytest.mark.parametrize("model, field", [("navarro-1985", (0.0, 0.0)), ("navarro-1985", (10.0, -4.0)),
                                          ("liou-brennan-1997", (-7.0, 3.0))])
def test_pixel_directions_follow_the_trace_field_rule(model, field):
    """The centre of an odd film looks along world +z, and every pixel along eye_to_world @ field_direction."""
    from vissim.optics.eyes.traced_wavefront import field_direction
    from vissim.bench.eye.scene import eye_to_world

    eye = eye_model(model)
    d = pixel_directions(eye, (5, 7), 30.0, field)
    assert np.allclose(d[2, 3], [0.0, 0.0, 1.0], atol=1e-12)
    rotation = np.asarray(eye_to_world(eye, field))[:3, :3]
    row, col = 0, 6  # top right: field x smaller by 3 px, y larger by 2 px (30 arcmin each)
    expected = rotation @ field_direction(eye, (field[0] - 1.5, field[1] + 1.0))
    assert np.allclose(d[row, col], expected, atol=1e-12)


def test_chart_lookup_inverts_the_raster():
    def chart(x, y):
        return (x > 10.0).astype(float) + 0.25 * (y > -5.0)

    raster = ChartRaster.from_function(chart, 100.0, 60.0, 1000.0, 0.5)
    x, y = np.meshgrid(np.linspace(-45.0, 45.0, 37), np.linspace(-25.0, 25.0, 23))
    x, y = x + 0.13, y + 0.07  # off the texel boundaries
    assert np.array_equal(raster.lookup(x, y), chart(x, y).astype(np.float32))
    rolled = ChartRaster(raster.data, 100.0, 60.0, 1000.0, roll_deg=90.0)  # turned a quarter towards +y
    x, y = np.meshgrid(np.linspace(-24.0, 24.0, 17) + 0.13, np.linspace(-24.0, 24.0, 17) + 0.07)
    assert np.array_equal(rolled.lookup(x, y), raster.lookup(y, -x))


def test_ideal_image_of_a_uniform_chart_is_uniform():
    raster = ChartRaster(np.full((4, 4), 0.7, dtype=np.float32), 1e5, 1e5, 1e6)
    image = ideal_image(raster, eye_model("navarro-1985"), (6, 8), 1.0, (5.0, 0.0))
    assert np.allclose(image, 0.7)


@needs_llvm
@pytest.mark.slow
def test_chromatic_focus_on_renders_matches_the_lca_within_0_05_diopters():
    from scripts.eye_studies import chromatic_focus

    result = chromatic_focus()  # measured: 450-550 nm off by 0.019 D, 650-550 nm by 0.004 D
    for wavelength in (450.0, 650.0):
        rendered = result.rendered_difference_diopters(wavelength)
        assert abs(rendered - result.predicted_difference_diopters(wavelength)) <= 0.05
        assert abs(rendered - result.traced_difference_diopters(wavelength)) <= 0.05
    assert result.rendered_difference_diopters(450.0) < -0.5 < 0.2 < result.rendered_difference_diopters(650.0)


@needs_llvm
@pytest.mark.slow
def test_slanted_edge_mtf_matches_the_traced_geometric_mtf_within_the_noise():
    from scripts.eye_studies import slanted_edge

    result = slanted_edge()
    assert abs(abs(result.edge_angle_deg) - 5.0) < 0.1
    # measured (8 seeds, 1024 spp): 0.0040 = 1.16 one-render sigma = 3.3 standard errors of the mean
    assert result.worst_deviation_in(result.seed_sigma, 30.0) <= 2.0
    assert result.worst_deviation_in(result.standard_error, 30.0) <= 4.0
    assert result.worst_deviation(30.0) <= 0.01


@needs_llvm
@pytest.mark.slow
def test_wide_chart_field_dependent_blur_follows_the_render_and_one_psf_does_not():
    from scripts.eye_studies import wide_chart

    # measured: field-dependent 29.2 / 28.8 dB, perfect (floor + 3.01) 29.9 / 29.3, one PSF 28.4 / 12.7
    result = wide_chart()
    perfect = {band: result.noise_floor_db[band] + PERFECT_MARGIN_DB for band in result.noise_floor_db}
    for band in ("on axis", "off axis"):
        assert result.field_dependent_db[band] >= perfect[band] - 1.5
    assert result.single_psf_db["on axis"] >= perfect["on axis"] - 2.5
    assert result.single_psf_db["off axis"] <= result.field_dependent_db["off axis"] - 10.0
