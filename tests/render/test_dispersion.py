"""Dispersion of ``vissim_refract`` in Mitsuba's spectral variants (hero wavelength), and the bench's spectral mode.

Oracles (none shares code with the plugin):

* unbiased: with Fresnel loss off, a lens conserves radiance, so a uniform equal-energy chart seen
  through a dispersive lens has the luminance it has through a non-dispersive one.  Statistical
  test: two-sample z-test on the image means, the standard error from the per-pixel spread
  (pixels are independent renders of the same value); |z| < 4.
* physics: the paraxial lensmaker's scaling ``P(λ) = P_d (n(λ) - 1) / (n_d - 1)`` with
  `crown_index` at each wavelength, the lens at its back vertex (the bench's lenses are made to
  their back vertex power at the d line), vergences carried 10 mm to the camera; the blur
  diameter is the entrance pupil times the defocus.  The render is spectral with a 1 nm sensor
  response around each wavelength, so the hero alone sets the focus.
* variance: termination leaves one wavelength of four per path.  Four independent wavelengths
  would have a quarter of one's variance; Mitsuba's four are rotations of the hero spread over
  the visible range, which does better still, so the ratio must be >= 4 (measured 74x on the
  uniform white here; benchmarks/bench_dispersion.py gives 5.1x on a letter chart).  A broken
  termination (all four carried, or none ended) gives ~1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from vissim.bench.dslr.bench import DslrBench, dslr_scene
from vissim.optics.rx.glass import D_LINE_NM, crown_index
from vissim.optics.rx.trial_lens import TrialLens
from vissim.render.backend import choose_variant
from vissim.render.run import render_scene

if choose_variant("spectral").variant.startswith("scalar"):  # pragma: no cover - machine without LLVM/CUDA
    pytest.skip("no JIT Mitsuba variant: spectral bench renders would be slow on scalar_spectral",
                allow_module_level=True)

WHITE = np.ones((400, 400), dtype=np.float32)
WHITE_MM_PER_TEXEL = 0.5  # 200 mm square: covers a 24 px field at 1 arcmin/px with margin


def white_through(lens_dispersion: bool, *, spp: int = 64, seed: int = 1) -> np.ndarray:
    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(24, 24), spp=spp, seed=seed)
    scene = dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL, kind="spectral")
    if not lens_dispersion:
        del scene["lens_0"]["bsdf"]["dispersion"]
    assert scene["lens_0"]["bsdf"].get("dispersion") == ("crown" if lens_dispersion else None)
    return render_scene(scene, kind="spectral", spp=spp, seed=seed).pixels.astype(np.float64)


def test_hero_termination_is_unbiased_on_a_white_chart():
    hero, carried = white_through(True), white_through(False, seed=2)
    se = math.sqrt(hero.var(ddof=1) / hero.size + carried.var(ddof=1) / carried.size)
    assert abs(hero.mean() - carried.mean()) / se < 4.0
    assert hero.mean() == pytest.approx(1.0, abs=0.005)  # equal-energy white of radiance 1 has Y ~ 1


def test_termination_costs_at_least_four_times_the_variance_on_white():  # measured 74x
    ratio = white_through(True).var(ddof=1) / white_through(False, seed=2).var(ddof=1)
    assert ratio >= 4.0


# ------------------------------------------------------------------ chromatic focus

SPHERE_D, F_NUMBER, VERTEX_MM, CHART_MM = -4.0, 2.0, 10.0, 914.4
DEFOCUS_D = 0.4  # the camera focused 0.4 D off the d-line image: blur of the same sign at every wavelength
_SUB = (np.arange(16) + 0.5) / 16 - 0.5


def _image_vergence_d(power_d: float) -> float:
    chart = -1000.0 / (CHART_MM - VERTEX_MM)
    after = chart + power_d
    return after / (1.0 - VERTEX_MM / 1000.0 * after)  # carried from the lens to the camera


FOCUS_MM = -1000.0 / (_image_vergence_d(SPHERE_D) - DEFOCUS_D)


def oracle_blur_arcmin(wavelength_nm: float, pupil_mm: float) -> float:
    power = SPHERE_D * (crown_index(wavelength_nm) - 1.0) / (crown_index(D_LINE_NM) - 1.0)
    defocus_d = _image_vergence_d(power) + 1000.0 / FOCUS_MM
    return math.degrees(pupil_mm * abs(defocus_d) / 1000.0) * 60.0


def _disc_esf(x, radius, x0, amplitude, offset):
    u = np.clip((x[:, None] + _SUB[None, :] - x0) / radius, -1.0, 1.0)
    return offset + amplitude * (0.5 + (u * np.sqrt(1.0 - u * u) + np.arcsin(u)) / np.pi).mean(axis=1)


def fitted_blur_px(profile: np.ndarray) -> float:
    x = np.arange(profile.size) - (profile.size - 1) / 2
    fit = least_squares(lambda p: _disc_esf(x, *p) - profile, [5.0, 0.0, np.ptp(profile), profile.min()],
                        bounds=([1e-3, -5.0, 0.0, -1.0], [np.inf, 5.0, 2.0, 1.0]))
    return 2.0 * fit.x[0]


def edge_blur_arcmin(wavelength_nm: float, dispersion: bool = True) -> tuple[float, float]:
    """(measured, oracle) blur diameter of a vertical edge seen in a 1 nm band around ``wavelength_nm``."""
    bench = DslrBench(lenses=(TrialLens(SPHERE_D),), f_number=F_NUMBER, focus_distance_mm=FOCUS_MM,
                      size_px=(16, 64), spp=64, seed=3)
    mm = 0.05
    x = (np.arange(4000) + 0.5 - 2000) * mm
    chart = np.broadcast_to((x > 0).astype(np.float32)[None, :], (400, x.size)).copy()
    scene = dslr_scene(bench, chart, mm, kind="spectral")
    if not dispersion:
        del scene["lens_0"]["bsdf"]["dispersion"]
    scene["camera"]["srf"] = {"type": "regular", "wavelength_min": wavelength_nm - 0.5,
                              "wavelength_max": wavelength_nm + 0.5, "values": "1, 1"}
    profile = render_scene(scene, kind="spectral", spp=bench.spp, seed=bench.seed).pixels.astype(np.float64).mean(axis=0)
    profile = profile if profile[-1] > profile[0] else profile[::-1]
    measured = fitted_blur_px(profile / profile.max()) * bench.arcmin_per_px
    return measured, oracle_blur_arcmin(wavelength_nm, bench.entrance_pupil_diameter_mm)


def test_blue_and_red_focus_where_the_lensmaker_with_crown_index_puts_them():
    """-4 D crown lens, 9 mm pupil: the blur changes by -2.0' (450 nm) and +0.5' (650 nm) from the d line.

    Measured when written: d line 12.52' (oracle 12.38', thin lens at the back vertex); the changes
    -2.00' and +0.52' against -2.04' and +0.53' (2 % off).  Tolerance: 8 % of each change, and 2 %
    on the d-line blur (the thick lens's spherical aberration over 9 mm).
    """
    d_measured, d_oracle = edge_blur_arcmin(D_LINE_NM)
    assert d_measured == pytest.approx(d_oracle, rel=0.02)
    for wavelength in (450.0, 650.0):
        measured, oracle = edge_blur_arcmin(wavelength)
        assert measured - d_measured == pytest.approx(oracle - d_oracle, rel=0.08)


def test_without_dispersion_blue_focuses_with_the_d_line():
    """Control: the same render through the non-dispersive lens does not move with wavelength."""
    blue, _ = edge_blur_arcmin(450.0, dispersion=False)
    d_line, _ = edge_blur_arcmin(D_LINE_NM, dispersion=False)
    assert blue == pytest.approx(d_line, abs=0.1)  # the dispersive lens moves it by 2.0'


# ------------------------------------------------------------------ mono variants, defaults, the bench's mode


def mono_edge_blur_arcmin(bsdf_extra: dict) -> float:
    bench = DslrBench(lenses=(TrialLens(SPHERE_D),), f_number=F_NUMBER, focus_distance_mm=FOCUS_MM,
                      size_px=(16, 64), spp=64, seed=3)
    mm = 0.05
    x = (np.arange(4000) + 0.5 - 2000) * mm
    chart = np.broadcast_to((x > 0).astype(np.float32)[None, :], (400, x.size)).copy()
    scene = dslr_scene(bench, chart, mm, kind="mono")
    scene["lens_0"]["bsdf"].update(bsdf_extra)
    pixels = render_scene(scene, kind="mono", spp=bench.spp, seed=bench.seed).pixels
    return pixels


def test_mono_variant_refracts_at_the_stated_wavelength_and_the_d_line_is_bitwise_the_default():
    plain = mono_edge_blur_arcmin({})
    at_d = mono_edge_blur_arcmin({"dispersion": "crown"})  # wavelength_nm defaults to the d line
    assert np.array_equal(plain, at_d)
    blue = mono_edge_blur_arcmin({"dispersion": "crown", "wavelength_nm": 450.0}).astype(np.float64).mean(axis=0)
    blue = blue if blue[-1] > blue[0] else blue[::-1]
    pupil = DslrBench(f_number=F_NUMBER).entrance_pupil_diameter_mm
    assert fitted_blur_px(blue / blue.max()) - oracle_blur_arcmin(450.0, pupil) == pytest.approx(
        fitted_blur_px(_rising(plain)) - oracle_blur_arcmin(D_LINE_NM, pupil), abs=0.15)


def _rising(pixels: np.ndarray) -> np.ndarray:
    profile = pixels.astype(np.float64).mean(axis=0)
    profile = profile if profile[-1] > profile[0] else profile[::-1]
    return profile / profile.max()


def test_default_bench_scene_has_no_dispersion_and_the_spectral_one_has_crown():
    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(8, 8), spp=4)
    assert "dispersion" not in dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL)["lens_0"]["bsdf"]
    assert dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL, kind="spectral")["lens_0"]["bsdf"]["dispersion"] == "crown"


def test_an_unknown_dispersion_is_refused():
    from vissim.errors import VissimInputError

    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(8, 8), spp=4)
    scene = dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL)
    scene["lens_0"]["bsdf"]["dispersion"] = "flint"
    # Mitsuba passes the plugin's error on as a RuntimeError carrying its message
    with pytest.raises((VissimInputError, RuntimeError), match="dispersion must be one of none, crown, got 'flint'"):
        render_scene(scene, spp=4)


def test_spectral_bench_render_records_its_spectrum_and_response():
    from vissim.charts import single_letter_spec
    from vissim.render.run import render_bench

    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(24, 24), spp=8)
    result = render_bench(bench, single_letter_spec("K", 1.0), kind="spectral")
    assert result.pixels.shape == (24, 24) and "spectral" in result.variant
    spectral = result.provenance["inputs"]["spectral"]
    assert "illuminant E" in spectral["emitter_spectrum"] and "luminance Y" in spectral["response"]


def test_render_bench_spectral_writes_a_luminance_exr_with_its_spectral_mode(tmp_path, capsys):
    from vissim.cli import main
    from vissim.imageio import read_image

    out = tmp_path / "s.exr"
    assert main(["render", "bench", "--spectral", "--sphere", "2", "--size", "16x16", "--spp", "4", "-o", str(out)]) == 0
    image = read_image(out)
    assert np.asarray(image.pixels).shape[:2] == (16, 16)
    inputs = image.provenance["inputs"]
    assert inputs["kind"] == "spectral" and "spectral" in inputs["variant"]
    assert "crown" in inputs["spectral"]["glass"]
    assert main(["render", "bench", "--spectral", "--rgb", "-o", str(tmp_path / "x.exr")]) == 2
    assert "--rgb: not allowed with argument --spectral" in capsys.readouterr().err


def test_render_bench_spectral_is_not_a_wave_truth_option(tmp_path):
    from vissim.cli import main

    assert main(["render", "bench", "--spectral", "--optics", "wave", "-o", str(tmp_path / "w.exr")]) == 2
    assert not (tmp_path / "w.exr").exists()


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_dispersive_spectral_renders_are_bit_identical_per_seed(variant):
    if variant.startswith("llvm") and not choose_variant("spectral").variant.startswith("llvm"):
        pytest.skip("no LLVM variant here")
    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(8, 8), spp=16, seed=1)
    scene = dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL, kind="spectral")
    first, again, other = (render_scene(scene, kind="spectral", spp=16, seed=seed, variant=variant)
                           for seed in (1, 1, 2))
    assert first.deterministic and np.array_equal(first.pixels, again.pixels)
    assert not np.array_equal(first.pixels, other.pixels)
    assert first.pixels.mean() == pytest.approx(1.0, abs=0.03)  # 64 samples of one wavelength each: ~1 % noise


def test_a_sensor_that_ends_the_secondaries_itself_gets_no_factor_of_four():
    """With ``sensor_terminates_secondary`` the lens only zeroes the others: behind Mitsuba's
    thinlens (which ends nothing) the white keeps the hero's quarter of its luminance."""
    bench = DslrBench(lenses=(TrialLens(2.0),), size_px=(24, 24), spp=64, seed=1)
    scene = dslr_scene(bench, WHITE, WHITE_MM_PER_TEXEL, kind="spectral")
    scene["lens_0"]["bsdf"]["sensor_terminates_secondary"] = True
    assert render_scene(scene, kind="spectral", spp=64, seed=1).pixels.mean() == pytest.approx(0.25, abs=0.005)
