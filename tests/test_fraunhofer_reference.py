"""The wave-PSF oracle (tests/fraunhofer_reference.py) against closed forms, and its convergence."""

import math

import numpy as np
import pytest
from fraunhofer_reference import (
    RAD_PER_ARCMIN,
    airy_intensity_per_sr,
    airy_pixel_values,
    defocus_otf,
    directions_rad,
    pixel_gl_order,
    pixel_values,
    zernike_osa,
)
from scipy.integrate import dblquad, quad
from scipy.special import j0, j1

WAVELENGTH_NM = 550.0
WAVELENGTH_MM = WAVELENGTH_NM * 1e-6
PUPIL_MM = 3.0
AREA_MM2 = math.pi * (PUPIL_MM / 2) ** 2
PEAK_PER_SR = AREA_MM2 / WAVELENGTH_MM**2  # I(0) of a perfect pupil


def test_zernike_closed_forms():
    # Thibos et al. 2002 (OSA/ANSI Z80.28) Table: unit-RMS terms, m < 0 carries sin |m|θ.
    rho, theta = np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 2 * np.pi, 11))
    expected = {
        (1, 1): 2 * rho * np.cos(theta),
        (1, -1): 2 * rho * np.sin(theta),
        (2, -2): math.sqrt(6) * rho**2 * np.sin(2 * theta),
        (2, 0): math.sqrt(3) * (2 * rho**2 - 1),
        (2, 2): math.sqrt(6) * rho**2 * np.cos(2 * theta),
        (3, -1): math.sqrt(8) * (3 * rho**3 - 2 * rho) * np.sin(theta),
        (3, 3): math.sqrt(8) * rho**3 * np.cos(3 * theta),
        (4, 0): math.sqrt(5) * (6 * rho**4 - 6 * rho**2 + 1),
        (5, -5): math.sqrt(12) * rho**5 * np.sin(5 * theta),
        (6, 0): math.sqrt(7) * (20 * rho**6 - 30 * rho**4 + 12 * rho**2 - 1),
    }
    for (n, m), value in expected.items():
        np.testing.assert_allclose(zernike_osa(n, m, rho, theta), value, atol=1e-12, err_msg=str((n, m)))


def test_zernikes_are_orthonormal_over_the_unit_disc():
    # Unit RMS: (1/π) ∫ Z_i Z_j = δ_ij up to n = 6 (exact quadrature: GL in ρ, trapezoid in θ).
    t, w = np.polynomial.legendre.leggauss(12)
    rho, w_rho = (t + 1) / 2, w / 2 * (t + 1) / 2
    theta = 2 * np.pi * np.arange(32) / 32
    rr, tt = np.meshgrid(rho, theta, indexing="ij")
    weights = (w_rho[:, None] * np.full(32, 2 * np.pi / 32)).ravel() / math.pi
    terms = [(n, m) for n in range(7) for m in range(-n, n + 1, 2)]
    basis = np.stack([zernike_osa(n, m, rr, tt).ravel() for n, m in terms])
    np.testing.assert_allclose((basis * weights) @ basis.T, np.eye(len(terms)), atol=1e-12)


OFFSETS_PX = np.array([(0, 0), (0, 1), (1, 1), (0, 3), (2, -5), (7, 4), (0, 20), (-15, 15), (-30, -1)])


@pytest.mark.parametrize("arcmin_per_px", [0.05, 0.25, 1.0, 2.0])
def test_zero_wavefront_is_the_airy_pattern(arcmin_per_px):
    # Born & Wolf 8.5.2: I = (A/λ²)[2 J1(v)/v]², v = π D |a|/λ; pixel integrals by GL of the
    # analytic formula (itself converged: twice the points agree). Both to 1e-9 of the peak.
    step_rad = arcmin_per_px * RAD_PER_ARCMIN
    ax, ay = directions_rad(arcmin_per_px, OFFSETS_PX)
    point = airy_intensity_per_sr(PUPIL_MM, WAVELENGTH_NM, np.hypot(ax, ay)) * step_rad**2
    oracle_point = pixel_values({}, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, arcmin_per_px, OFFSETS_PX, integrate=False)
    np.testing.assert_allclose(oracle_point, point, rtol=0, atol=1e-9 * point[0])
    q = pixel_gl_order(PUPIL_MM, WAVELENGTH_NM, arcmin_per_px)
    analytic = airy_pixel_values(PUPIL_MM, WAVELENGTH_NM, arcmin_per_px, OFFSETS_PX)
    finer = airy_pixel_values(PUPIL_MM, WAVELENGTH_NM, arcmin_per_px, OFFSETS_PX, gl_pixel=2 * q)
    np.testing.assert_allclose(analytic, finer, rtol=0, atol=1e-12 * analytic[0])
    oracle = pixel_values({}, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, arcmin_per_px, OFFSETS_PX)
    np.testing.assert_allclose(oracle, analytic, rtol=0, atol=1e-9 * analytic[0])


@pytest.mark.parametrize("c11_um, c1m1_um", [(0.4, 0.0), (0.0, 0.4), (0.3, -0.25)])
def test_tilt_is_a_shifted_airy_pattern_on_the_observers_side(c11_um, c1m1_um):
    # W = c11 2x/R + c1-1 2y/R: the Airy pattern centred where a = ∇W = (2 c11/R, 2 c1-1/R) mrad
    # (OSA frame); docs/conventions.md puts a_x > 0 at the observer's left (col < N//2) and
    # a_y > 0 up (row < N//2). Point values to 1e-9 of the peak.
    radius_mm, step = PUPIL_MM / 2, 0.25
    centre_rad = np.array([2 * c11_um / radius_mm, 2 * c1m1_um / radius_mm]) * 1e-3
    offsets = np.array([(dr, dc) for dr in range(-12, 13) for dc in range(-12, 13)])
    ax, ay = directions_rad(step, offsets)
    expected = airy_intensity_per_sr(PUPIL_MM, WAVELENGTH_NM, np.hypot(ax - centre_rad[0], ay - centre_rad[1]))
    coefficients = {(1, 1): c11_um, (1, -1): c1m1_um}
    oracle = pixel_values(coefficients, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, step, offsets, integrate=False)
    np.testing.assert_allclose(oracle, expected * (step * RAD_PER_ARCMIN) ** 2, rtol=0, atol=1e-9 * oracle.max())
    dr, dc = offsets[np.argmax(oracle)]
    shift_px = centre_rad / RAD_PER_ARCMIN / step
    assert (dc, dr) == (round(-shift_px[0]), round(-shift_px[1]))
    assert np.sign(dc) == -np.sign(c11_um) and np.sign(dr) == -np.sign(c1m1_um)


@pytest.mark.parametrize("measured_mm, waves", [(3.0, 0.25), (3.0, 0.5), (3.0, 1.3), (6.0, 0.75)])
def test_on_axis_defocus_is_sinc_squared(measured_mm, waves):
    # Mahajan 1982: W = W020 ρ² on axis gives I(0) = (A/λ²) sinc²(W020/λ). With c(2,0) over a
    # larger measurement pupil, W020 = 2√3 c20 (D/D_meas)² on the D = 3 mm pupil. Rel 1e-10.
    w020_um = waves * WAVELENGTH_NM * 1e-3
    c20_um = w020_um / (2 * math.sqrt(3)) * (measured_mm / PUPIL_MM) ** 2
    value = pixel_values({(2, 0): c20_um}, measured_mm, PUPIL_MM, WAVELENGTH_NM, 0.1, [(0, 0)], integrate=False)[0]
    expected = PEAK_PER_SR * np.sinc(waves) ** 2 * (0.1 * RAD_PER_ARCMIN) ** 2
    assert value == pytest.approx(expected, rel=1e-10)


def test_on_axis_astigmatism_is_a_bessel_integral():
    # W = c √6 ρ² sin 2θ: the θ integral is 2π J0(b ρ²), b = k c √6, so
    # I(0) = (A/λ²) [∫_0^1 J0(b u) du]² (u = ρ²). Rel 1e-9.
    c_um, pupil_mm = 0.3, 4.0
    b = 2 * math.pi / (WAVELENGTH_NM * 1e-3) * c_um * math.sqrt(6)
    radial, _ = quad(lambda u: j0(b * u), 0, 1, limit=200, epsabs=1e-14)
    expected = math.pi * (pupil_mm / 2) ** 2 / WAVELENGTH_MM**2 * radial**2 * (0.05 * RAD_PER_ARCMIN) ** 2
    value = pixel_values({(2, -2): c_um}, pupil_mm, pupil_mm, WAVELENGTH_NM, 0.05, [(0, 0)], integrate=False)[0]
    assert value == pytest.approx(expected, rel=1e-9)


def _probe_offsets(half_px, rng, n_random):
    lines = np.linspace(-half_px, half_px, 7).round().astype(int)
    fixed = [(0, 0), (half_px, half_px), (-half_px, half_px), (0, 1), (1, -2)]
    fixed += [(0, int(v)) for v in lines] + [(int(v), 0) for v in lines]
    return np.array(fixed + [tuple(p) for p in rng.integers(-half_px, half_px + 1, size=(n_random, 2))])


CONVERGENCE_CASES = [
    # (coefficients µm, measured mm, pupil mm, arcmin/px, half field px)
    pytest.param({(2, -2): -0.11, (2, 0): 0.65, (2, 2): -0.06, (3, -1): 0.1, (3, 3): 0.08, (4, 0): 0.05},
                 4.0, 4.0, 0.25, 80, id="issue-like-4mm-0.25"),
    pytest.param({(2, 0): 1.2, (2, 2): 0.4, (3, 1): -0.2, (4, -4): 0.15, (5, 1): 0.1, (6, 0): 0.08, (6, -2): -0.1},
                 6.0, 5.0, 0.6, 30, id="hoa-6th-order-5of6mm-0.6"),
    pytest.param({(2, 0): 2.0, (2, -2): -1.0, (4, 0): 0.2, (6, 6): 0.1}, 8.0, 8.0, 2.0, 16,
                 marks=pytest.mark.slow, id="large-8mm-2.0"),
]


@pytest.mark.parametrize("coefficients, measured_mm, pupil_mm, arcmin_per_px, half_px", CONVERGENCE_CASES)
def test_doubling_every_node_count_changes_less_than_1e_6_of_the_peak(coefficients, measured_mm, pupil_mm, arcmin_per_px, half_px):
    # Self-consistency of the quadrature at pixels across the whole field: doubling the pupil's
    # (r, θ) nodes, for pixel integrals and point values, and doubling the pixel's GL points
    # each change the answer by < 1e-6 of the peak.
    offsets = _probe_offsets(half_px, np.random.default_rng(12), 8)
    args = (coefficients, measured_mm, pupil_mm, WAVELENGTH_NM, arcmin_per_px)
    q = pixel_gl_order(pupil_mm, WAVELENGTH_NM, arcmin_per_px)
    for integrate in (True, False):
        base = pixel_values(*args, offsets, integrate=integrate)
        peak = max(base.max(), pixel_values(*args, [(0, 0)], integrate=integrate).max())
        doubled = pixel_values(*args, offsets, integrate=integrate, node_scale=2)
        assert np.max(np.abs(doubled - base)) < 1e-6 * peak, ("pupil nodes", integrate)
        if integrate:
            finer = pixel_values(*args, offsets, gl_pixel=2 * q)
            assert np.max(np.abs(finer - base)) < 1e-6 * peak, "pixel GL points"


def _airy_encircled_energy(radius_rad):
    v = math.pi * PUPIL_MM * radius_rad / WAVELENGTH_MM
    return 1 - j0(v) ** 2 - j1(v) ** 2  # Born & Wolf 8.5.2


def _square(half_px):
    return np.array([(r, c) for r in range(-half_px, half_px + 1) for c in range(-half_px, half_px + 1)])


def test_pixel_energies_in_growing_fields_sum_towards_one():
    # ∫ I d²a = 1 (Parseval): the energy in a square field of pixels lies between the Airy
    # encircled energies of its inscribed and circumscribed circles (Born & Wolf 8.5.2).
    step = 3.0 * WAVELENGTH_MM / PUPIL_MM / RAD_PER_ARCMIN  # 3 λ/D pixels
    sums = []
    for half in (2, 5, 9):
        total = float(pixel_values({}, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, step, _square(half)).sum())
        edge_rad = (half + 0.5) * step * RAD_PER_ARCMIN
        assert _airy_encircled_energy(edge_rad) <= total <= _airy_encircled_energy(math.sqrt(2) * edge_rad)
        sums.append(total)
    assert sums[0] < sums[1] < sums[2] and sums[2] > 0.99


def test_point_values_of_an_aberrated_psf_sum_to_one():
    # Poisson summation: Σ I(n s) s² over all n is exactly ∫ I = 1 for s < λ/D (I has band limit
    # D/λ), whatever the aberration. A 23 arcmin field holding the 5 arcmin blur misses only the
    # diffraction tail, which is that of the Airy pattern: the two sums agree to 2e-3 and
    # exceed 0.985.
    step = 0.9 * WAVELENGTH_MM / PUPIL_MM / RAD_PER_ARCMIN
    offsets = _square(20)
    aberrated = pixel_values({(2, 0): 0.25, (2, 2): 0.1}, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, step, offsets,
                             integrate=False).sum()
    airy = pixel_values({}, PUPIL_MM, PUPIL_MM, WAVELENGTH_NM, step, offsets, integrate=False).sum()
    assert 0.985 < airy < 1.0 and 0.985 < aberrated < 1.0
    assert aberrated == pytest.approx(airy, abs=2e-3)


@pytest.mark.parametrize("waves", [0.0, 0.5, 1.0, 2.5])
def test_defocus_otf_is_the_overlap_integral(waves):
    # Hopkins 1955 / Goodman §6.4: OTF(d) = (1/A) ∫∫_overlap cos(2kβ d x) d²x, checked by a plain
    # 2-D quadrature over the lens-shaped overlap; W020 = 0 is Goodman Eq. 6-32. Abs 1e-9.
    radius_mm = PUPIL_MM / 2
    w020_um = waves * WAVELENGTH_NM * 1e-3
    omega_per_mm2 = 2 * (2 * math.pi / WAVELENGTH_MM) * w020_um * 1e-3 / radius_mm**2
    for d_mm in (0.0, 0.3, 1.1, 2.2, 2.9):
        half = radius_mm - d_mm / 2

        def height(x, d_mm=d_mm):
            return math.sqrt(max(radius_mm**2 - (abs(x) + d_mm / 2) ** 2, 0.0))

        value, _ = dblquad(lambda y, x, d_mm=d_mm: math.cos(omega_per_mm2 * d_mm * x), -half, half,
                           lambda x: -height(x), height, epsabs=1e-12, epsrel=1e-12)
        assert defocus_otf(PUPIL_MM, WAVELENGTH_NM, w020_um, d_mm) == pytest.approx(value / (math.pi * radius_mm**2), abs=1e-9)
        if waves == 0.0:
            nu = d_mm / PUPIL_MM
            assert defocus_otf(PUPIL_MM, WAVELENGTH_NM, 0.0, d_mm) == pytest.approx(
                2 / math.pi * (math.acos(nu) - nu * math.sqrt(1 - nu**2)), abs=1e-12)
