"""The virtual DSLR bench against paraxial theory: small CPU renders, fixed seeds.

Theory: :meth:`vissim.bench.dslr.bench.DslrBench.viewing_setup` -- added power and spectacle magnification by
4 x 4 ray transfer through the same thick lenses that are rendered
(:func:`vissim.optics.rx.trial_lens.trial_lens_effect`), blur diameter = entrance pupil (3.6 mm) x
defocus (conventions: dioptres x mm = mrad).  Prototype reference: +2 D at 10 mm, chart at
914.4 mm, 3.6 mm pupil -> a 24.7 arcmin blur disc.

Estimators (chosen because they are robust at 64 spp):

* blur: the edge-spread function of a checkerboard of four quadrants meeting on the axis,
  averaged along the edge, fitted with the ESF of a uniform disc (semicircle law) integrated
  over the pixel; the fitted support is the blur diameter along that image axis.  Noise
  measured when written: <= 0.25 % at 64 spp, so the 1 % tolerance is 4x the noise.
* magnification: a camera stopped down to f/1000 (no blur; the chief-ray magnification of
  the theory) looking at an 80 x 80 arcmin bright square; the square's width in pixels
  (row and column sums) with the lens over without.  Error measured when written <= 0.02 %.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from vissim.bench.dslr.bench import DslrBench, chart_mm_per_texel, dslr_scene
from vissim.charts import optotype_tile, single_letter_spec
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.backend import choose_variant
from vissim.render.run import render_bench, render_scene

if choose_variant("mono").variant.startswith("scalar"):  # pragma: no cover - machine without LLVM/CUDA
    pytest.skip("no JIT Mitsuba variant: bench renders would take hours on scalar_rgb", allow_module_level=True)

SPP = 64
SEED = 7
EXTENT_ARCMIN = 260.0  # chart rasters cover the 113 x 133 arcmin field with margins


def raster(bench: DslrBench, paint) -> tuple[np.ndarray, float]:
    """A chart raster centred on the axis; ``paint(x_arcmin, y_arcmin)`` -> reflectance at texel centres."""
    mm = chart_mm_per_texel(bench)
    n = 2 * math.ceil(0.5 * EXTENT_ARCMIN * bench.pitch_mm / bench.arcmin_per_px / mm)
    centres_mm = (np.arange(n) + 0.5 - n / 2) * mm
    x = np.degrees(np.arctan(centres_mm / bench.chart_distance_mm)) * 60.0
    xx, yy = np.meshgrid(x, -x)  # row 0 is the top (+y), columns to the camera's right
    return paint(xx, yy).astype(np.float32), mm


def quadrants(x, y):
    return ((x < 0) == (y > 0)).astype(float)  # bright top-left and bottom-right


def render(bench: DslrBench, paint, *, spp: int = SPP, seed: int = SEED) -> np.ndarray:
    pixels, mm = raster(bench, paint)
    return render_scene(dslr_scene(bench, pixels, mm), spp=spp, seed=seed).pixels.astype(np.float64)


_SUB = (np.arange(16) + 0.5) / 16 - 0.5


def _disc_esf(x, radius, x0, amplitude, offset):
    u = np.clip((x[:, None] + _SUB[None, :] - x0) / radius, -1.0, 1.0)
    return offset + amplitude * (0.5 + (u * np.sqrt(1.0 - u * u) + np.arcsin(u)) / np.pi).mean(axis=1)


def _fit_diameter(profile, x) -> float:
    start = [5.0, 0.0, np.ptp(profile), profile.min()]
    fit = least_squares(lambda p: _disc_esf(x, *p) - profile, start,
                        bounds=([1e-3, -5.0, 0.0, -1.0], [np.inf, 5.0, 2.0, 1.0]))
    return 2.0 * fit.x[0]


def blur_diameters_arcmin(image: np.ndarray, arcmin_per_px: float, margin_px: float = 26.0) -> tuple[float, float]:
    """(along x, along y) blur diameters from the checkerboard's vertical and horizontal edges.

    A blur narrower than a pixel is not resolved: the fit then returns <= 1 px."""
    rows, cols = image.shape
    y = -(np.arange(rows) - (rows - 1) / 2)
    x = np.arange(cols) - (cols - 1) / 2
    top, bottom = image[y > margin_px].mean(axis=0), image[y < -margin_px].mean(axis=0)
    left, right = image[:, x < -margin_px].mean(axis=1), image[:, x > margin_px].mean(axis=1)
    along_x = 0.5 * (bottom + (1.0 - top))  # rising with x
    along_y = 0.5 * (left + (1.0 - right))  # rising with y (left half is bright on top)
    return (_fit_diameter(along_x, x) * arcmin_per_px, _fit_diameter(along_y[::-1], y[::-1]) * arcmin_per_px)


def square_widths_px(image: np.ndarray, half_px: float = 25.0) -> tuple[float, float]:
    rows, cols = image.shape
    y, x = np.abs(np.arange(rows) - (rows - 1) / 2), np.abs(np.arange(cols) - (cols - 1) / 2)
    return image[y < half_px].sum(axis=1).mean(), image[:, x < half_px].sum(axis=0).mean()


def square(x, y):
    return ((np.abs(x) < 40.0) & (np.abs(y) < 40.0)).astype(float)


def theory_blur_xy(bench: DslrBench) -> tuple[float, float]:
    by_meridian = {meridian: diameter for diameter, meridian in bench.viewing_setup().blur_diameter_arcmin}
    return by_meridian[180.0], by_meridian[90.0]


# ------------------------------------------------------------------ no lens


def test_letters_are_neither_mirrored_nor_upside_down():
    """With no lens the render is the angular tile of vissim.charts (same letter, same place)."""
    bench = DslrBench(spp=SPP, seed=SEED)
    tile = optotype_tile("R", 1.0, snap_to_pixels=False).pixels.astype(np.float64)
    image = render_bench(bench, single_letter_spec("R", 1.0)).pixels.astype(np.float64)
    ink, ink_tile = 0.9 - image, 0.9 - tile
    rows, cols = np.mgrid[: image.shape[0], : image.shape[1]]
    for weight in (rows, cols):  # the R's bowl is top-left of centre: flips move the ink centroid by pixels
        assert (ink * weight).sum() / ink.sum() == pytest.approx((ink_tile * weight).sum() / ink_tile.sum(), abs=0.02)
    assert np.corrcoef(image.ravel(), tile.ravel())[0, 1] > 0.999
    assert np.corrcoef(image.ravel(), tile[:, ::-1].ravel())[0, 1] < 0.9
    assert np.corrcoef(image.ravel(), tile[::-1].ravel())[0, 1] < 0.9
    assert image.mean() == pytest.approx(tile.mean(), rel=1e-4)  # radiance in = radiance out


def test_without_trial_lens_the_chart_is_sharp_and_unmagnified():
    bench = DslrBench(spp=SPP, seed=SEED)
    assert max(blur_diameters_arcmin(render(bench, quadrants), bench.arcmin_per_px)) <= 1.1  # < 1 px
    widths = square_widths_px(render(dataclasses.replace(bench, f_number=1000.0), square))
    # the square is 80 arcmin wide (|x|, |y| < 40 arcmin on the chart): 80 px at 1 arcmin/px;
    # 0.02 px is 0.025 %, well inside the 0.2 % magnification tolerance of issue 4
    assert widths == pytest.approx((80.0, 80.0), abs=0.02)


# ------------------------------------------------------------------ trial lenses


@pytest.mark.parametrize("sphere", [-4.0, -2.0, 2.0, 4.0])
def test_blur_diameter_matches_pupil_times_defocus(sphere):
    bench = DslrBench(lenses=(TrialLens(sphere),), spp=SPP, seed=SEED)
    measured = blur_diameters_arcmin(render(bench, quadrants), bench.arcmin_per_px)
    assert measured == pytest.approx(theory_blur_xy(bench), rel=0.01)


@pytest.mark.parametrize("sphere", [-4.0, -2.0, 2.0, 4.0])
def test_magnification_matches_ray_transfer_theory(sphere):
    bare = DslrBench(f_number=1000.0, spp=16, seed=SEED)
    bench = dataclasses.replace(bare, lenses=(TrialLens(sphere),))
    ratio = np.divide(square_widths_px(render(bench, square, spp=16)), square_widths_px(render(bare, square, spp=16)))
    expected = dict((m, mag) for mag, m in bench.viewing_setup().magnification_principal)
    assert ratio == pytest.approx((expected[180.0], expected[90.0]), rel=0.002)


def test_prototype_reference_plus_two_at_ten_mm():
    """Prototype: +2 D at 10 mm, 914.4 mm, 3.6 mm pupil -> 24.68' (thin-lens theory 1.9946 D); ours is thick."""
    bench = DslrBench(lenses=(TrialLens(2.0),))
    assert theory_blur_xy(bench)[0] == pytest.approx(24.68, rel=0.002)


@pytest.mark.parametrize("axis_deg, blurred_axis", [(90.0, "x"), (180.0, "y")])
def test_plus_cylinder_blurs_only_across_its_axis(axis_deg, blurred_axis):
    """+2 DC x 90 has its power in the horizontal meridian: it blurs image columns (x) only."""
    bench = DslrBench(lenses=(TrialLens(0.0, 2.0, axis_deg),), spp=SPP, seed=SEED)
    along_x, along_y = blur_diameters_arcmin(render(bench, quadrants), bench.arcmin_per_px)
    blurred, sharp = (along_x, along_y) if blurred_axis == "x" else (along_y, along_x)
    assert blurred == pytest.approx(max(theory_blur_xy(bench)), rel=0.01)
    assert sharp <= 1.1


def test_three_lenses_in_the_holder_add_up_by_ray_transfer():
    lenses = (TrialLens(-2.0), TrialLens(0.0, 1.5, 90.0), TrialLens(+1.0))
    bench = DslrBench(lenses=lenses, spp=SPP, seed=SEED)
    measured = blur_diameters_arcmin(render(bench, quadrants), bench.arcmin_per_px)
    assert measured == pytest.approx(theory_blur_xy(bench), rel=0.01)


# ------------------------------------------------------------------ radiometry and sampling


def uniform(x, y):
    return np.full_like(x, 0.9)


def test_lenses_without_fresnel_loss_conserve_radiance():
    """A uniform chart stays uniform at its radiance through any lens (radiance invariance)."""
    bench = DslrBench(lenses=(TrialLens(4.0), TrialLens(-2.0, 1.0, 30.0)), spp=16, seed=SEED)
    image = render(bench, uniform, spp=16)
    assert image.mean() == pytest.approx(0.9, rel=1e-5) and np.ptp(image) < 1e-5


def test_fresnel_loss_is_the_product_of_the_surface_transmittances():
    """Uncoated n = 1.523: each of the 4 surfaces passes 1 - ((n-1)/(n+1))^2 at near-normal incidence."""
    bench = DslrBench(lenses=(TrialLens(2.0), TrialLens(-2.0)), spp=16, seed=SEED, fresnel_loss=True)
    transmittance = 1.0 - ((1.523 - 1.0) / (1.523 + 1.0)) ** 2
    assert render(bench, uniform, spp=16).mean() == pytest.approx(0.9 * transmittance**4, rel=1e-3)


def test_same_seed_gives_bit_identical_pixels_and_another_seed_does_not():
    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(41, 37))
    pixels, mm = raster(bench, quadrants)
    scene = dslr_scene(bench, pixels, mm)
    first = render_scene(scene, spp=16, seed=3, pass_spp=8)
    assert first.passes == 2
    assert np.array_equal(first.pixels, render_scene(scene, spp=16, seed=3, pass_spp=8).pixels)
    assert not np.array_equal(first.pixels, render_scene(scene, spp=16, seed=4, pass_spp=8).pixels)


# ------------------------------------------------------------------ against the Fourier-optics half


@pytest.mark.parametrize("lens", [TrialLens(2.0), TrialLens(-2.0, 1.0, 30.0)], ids=["+2DS", "-2+1x30"])
def test_bench_render_matches_vissims_blur_of_the_magnified_letter(lens):
    """Render vs vissim.optics.psf.compute (geometric mode) + vissim.optics.blur.convolve of the tile magnified by the theory.

    Same camera prescription (DslrBench.viewing_setup), 3.6 mm pupil, letter scaled by the spectacle
    magnification (ERRATA item 5).  This pins the oblique-axis mirroring of both halves to each
    other.  Measured when written at 256 spp: PSNR 44.8 dB (+2 DS) and 43.2 dB (-2 +1 x 30) over
    the 0.9 white level (46 and 44 dB at 512 spp); the render's own noise is ~48 dB.  Threshold 40 dB."""
    from vissim.optics.blur.convolve import blur_image
    from vissim.optics.psf.compute import compute_psf

    bench = DslrBench(lenses=(lens,), spp=256, seed=SEED)
    setup = bench.viewing_setup()
    image = render_bench(bench, single_letter_spec("R", 1.0)).pixels.astype(np.float64)
    magnification = math.sqrt(np.linalg.det(np.asarray(setup.magnification_matrix)))
    tile = optotype_tile("R", 1.0 + math.log10(magnification), snap_to_pixels=False).pixels
    wavefront = setup.wavefront
    psf = compute_psf(wavefront, mode="geometric", arcmin_per_px=1.0, size_px=101)
    simulated = blur_image(tile, psf, arcmin_per_px=1.0, background=0.9).astype(np.float64)
    psnr_db = 10.0 * math.log10(0.9**2 / np.mean((simulated - image) ** 2))
    assert psnr_db >= 40.0


def test_provenance_added_power_is_the_lenses_alone_not_the_focus_error():
    # Camera focused at 600 mm, chart at 914.4 mm: the defocus holds 1/0.6 - 1/0.9144 = 0.5730 D
    # of focus error; "added_power" is the +2 D lens's own contribution at the camera (ERRATA
    # item 4: 1.9960 D at 914.4 mm, tests/test_trial_lens.py), unchanged by where the camera focuses.
    bench = DslrBench(lenses=(TrialLens(2.0),), focus_distance_mm=600.0, size_px=(21, 21), spp=4)
    result = render_bench(bench, single_letter_spec("K", 1.0))
    theory = result.provenance["inputs"]["theory"]
    assert theory["added_power"].startswith("+1.99")
    defocus = theory["defocus_matrix_diopters"]
    assert defocus[0][0] - 1.99 == pytest.approx(1 / 0.6 - 1 / 0.9144, abs=0.01)
