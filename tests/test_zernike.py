"""OSA/ANSI Zernike polynomials: indices, normalisation, orthonormality."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.pupil.zernike import (
    MAX_MONOMIAL_ORDER,
    ansi_j_to_nm,
    nm_to_ansi_j,
    nm_to_noll,
    noll_to_nm,
    zernike_basis,
    zernike_gradient,
    zernike_keys,
    zernike_monomials,
    zernike_nm,
    zernike_radial,
    zernike_sum,
)


def test_first_ansi_indices():
    # ANSI Z80.28 / Thibos et al. 2002, Table 1.
    assert [ansi_j_to_nm(j) for j in range(6)] == [(0, 0), (1, -1), (1, 1), (2, -2), (2, 0), (2, 2)]
    assert nm_to_ansi_j(4, 0) == 12


def test_first_noll_indices():
    # Noll 1976, Table 1: even j cosine, odd j sine.
    expected = [(0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2), (3, -1), (3, 1), (3, -3), (3, 3), (4, 0)]
    assert [noll_to_nm(j) for j in range(1, 12)] == expected


@given(st.integers(0, 5000))
def test_ansi_round_trip(j):
    assert nm_to_ansi_j(*ansi_j_to_nm(j)) == j


@given(st.integers(1, 2000))
def test_noll_round_trip(j):
    assert nm_to_noll(*noll_to_nm(j)) == j


def test_invalid_terms_are_refused():
    for n, m in [(2, 1), (1, 3), (-1, 1)]:
        with pytest.raises(VissimInputError):
            nm_to_ansi_j(n, m)


def test_second_order_terms_use_double_angles():
    # ERRATA item 2: Z(2,-2) = sqrt6 rho^2 sin 2theta, Z(2,2) = sqrt6 rho^2 cos 2theta.
    rho, theta = 0.7, 0.3
    assert zernike_nm(2, -2, rho, theta) == pytest.approx(math.sqrt(6) * rho**2 * math.sin(2 * theta))
    assert zernike_nm(2, 2, rho, theta) == pytest.approx(math.sqrt(6) * rho**2 * math.cos(2 * theta))
    assert zernike_nm(2, 0, rho, theta) == pytest.approx(math.sqrt(3) * (2 * rho**2 - 1))
    assert zernike_nm(4, 0, rho, theta) == pytest.approx(math.sqrt(5) * (6 * rho**4 - 6 * rho**2 + 1))


def test_orthonormal_over_the_unit_disc_to_order_8():
    # Gauss-Legendre in rho^2 (exact for polynomials) x uniform in theta: <Zi Zj> = delta_ij.
    nodes, weights = np.polynomial.legendre.leggauss(24)
    s = 0.5 * (nodes + 1)  # s = rho^2 on [0, 1], d(area)/pi = ds dtheta / (2 pi)
    w_s = 0.5 * weights
    theta = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    rr, tt = np.meshgrid(np.sqrt(s), theta, indexing="ij")
    ww = np.repeat(w_s[:, None], theta.size, axis=1) / theta.size
    terms = [ansi_j_to_nm(j) for j in range(nm_to_ansi_j(8, 8) + 1)]
    basis = np.stack([zernike_nm(n, m, rr, tt).ravel() for n, m in terms])
    gram = (basis * ww.ravel()) @ basis.T
    np.testing.assert_allclose(gram, np.eye(len(terms)), atol=1e-10)


def test_high_orders_stay_bounded():
    # |R_n^m(rho)| <= 1 on the unit disc for any order (Jacobi evaluation, no cancellation).
    rho = np.linspace(0, 1, 501)
    for n in (30, 41, 60):
        values = zernike_nm(n, n % 2, rho, 0.0) / math.sqrt(2 * (n + 1) / (2 if n % 2 == 0 else 1))
        assert np.max(np.abs(values)) <= 1 + 1e-9
        assert values[-1] == pytest.approx(1.0)


def _radial_by_factorials(n, m, rho):
    """Born & Wolf 9.2 (the factorial sum), in exact integers then floats: the oracle for low orders."""
    m = abs(m)
    return sum((-1) ** s * math.factorial(n - s) / (math.factorial(s) * math.factorial((n + m) // 2 - s)
                                                    * math.factorial((n - m) // 2 - s)) * rho ** (n - 2 * s)
               for s in range((n - m) // 2 + 1))


def test_radial_polynomials_match_scipys_jacobi_and_the_factorial_sum():
    """vissim's own Jacobi recurrence (no scipy.special at import) against scipy.special.eval_jacobi to order 40,
    and against the factorial sum to order 12 (where the sum's cancellation is still harmless)."""
    from scipy.special import eval_jacobi

    rho = np.linspace(0.0, 1.0, 401)
    for n in range(41):
        for m in range(n % 2, n + 1, 2):
            k = (n - m) // 2
            jacobi = (-1) ** k * rho**m * eval_jacobi(k, m, 0.0, 1.0 - 2.0 * rho**2)
            np.testing.assert_allclose(zernike_radial(n, m, rho), jacobi, rtol=0, atol=1e-12)
            if n <= 12:
                np.testing.assert_allclose(zernike_radial(n, m, rho), _radial_by_factorials(n, m, rho), atol=1e-12)


@pytest.mark.parametrize("order", [2, 8, 12, 16])
def test_sum_basis_and_monomials_equal_the_terms_one_by_one(order):
    """`zernike_sum` (monomials by Horner to order 12, shared recurrences above), `zernike_basis` and
    `zernike_monomials` equal summing `zernike_nm` term by term, inside and just outside the disc, to 1e-12 of
    the front's largest value."""
    rng = np.random.default_rng(order)
    coefficients = {key: rng.normal() for key in zernike_keys(order)}
    rho, theta = np.sqrt(rng.uniform(0.0, 1.2, 2000)), rng.uniform(0.0, 2 * np.pi, 2000)
    u, v = rho * np.cos(theta), rho * np.sin(theta)
    terms = sum(c * zernike_nm(n, m, rho, theta) for (n, m), c in coefficients.items())
    scale = np.max(np.abs(terms))
    np.testing.assert_allclose(zernike_sum(coefficients, u, v), terms, rtol=0, atol=1e-12 * scale)
    basis = zernike_basis(list(coefficients), u, v)
    np.testing.assert_allclose(basis @ np.array(list(coefficients.values())), terms, rtol=0, atol=1e-12 * scale)
    if order <= 12:
        table = zernike_monomials(coefficients)
        np.testing.assert_allclose(np.polynomial.polynomial.polyval2d(u, v, table), terms, rtol=0,
                                   atol=1e-12 * scale)


def test_monomials_of_the_second_order_are_the_textbooks():
    """Z(2,0) = sqrt3 (2u^2 + 2v^2 - 1), Z(2,-2) = sqrt6 2uv, Z(2,2) = sqrt6 (u^2 - v^2) (errata item 2)."""
    assert zernike_monomials({(2, 0): 1.0}) == pytest.approx(
        math.sqrt(3) * np.array([[-1, 0, 2], [0, 0, 0], [2, 0, 0]]))
    assert zernike_monomials({(2, -2): 1.0}) == pytest.approx(math.sqrt(6) * np.array([[0, 0, 0], [0, 2, 0], [0, 0, 0]]))
    assert zernike_monomials({(2, 2): 1.0}) == pytest.approx(math.sqrt(6) * np.array([[0, 0, -1], [0, 0, 0], [1, 0, 0]]))


@pytest.mark.parametrize("order", [8, 14])
def test_a_pupil_grid_takes_the_front_term_by_term(order):
    """The wave PSF's OPD on its pupil grid (cell centres as two matrix products of monomials to order 12, the
    rim's quadrature points by `zernike_sum`; above order 12 every point summed) equals the terms one by one."""
    from vissim.optics.pupil.grid import opd_on_points_um, pupil_grid
    from vissim.optics.pupil.wavefront import Wavefront

    rng = np.random.default_rng(order)
    front = Wavefront({key: 0.2 * rng.normal() for key in zernike_keys(order)}, 6.0)
    grid = pupil_grid(0.11, 5.0)
    x, y = grid.points()
    rho, theta = np.hypot(x, y) / 3.0, np.arctan2(y, x)
    terms = sum(c * zernike_nm(n, m, rho, theta) for (n, m), c in front.coefficients_um.items() if n > 0)
    np.testing.assert_allclose(opd_on_points_um(grid, front), terms, rtol=0, atol=1e-12 * np.max(np.abs(terms)))


def test_a_fit_recovers_known_terms_and_equals_the_svd_solution():
    # Independent oracle: numpy's SVD least squares on a basis written term by term with zernike_nm.
    from vissim.optics.pupil.zernike import fit_zernike_um, zernike_keys, zernike_nm

    rng = np.random.default_rng(3)
    x, y = rng.uniform(-2.0, 2.0, (2, 4000))
    keys = zernike_keys(8)
    truth = {k: rng.normal(0.0, 0.2) for k in keys}
    rho, theta = np.hypot(x, y) / 2.0, np.arctan2(y, x)
    basis = np.stack([zernike_nm(n, m, rho, theta) for n, m in keys], axis=1)
    opd = basis @ np.array([truth[k] for k in keys]) + rng.normal(0.0, 1e-3, x.size)
    fitted, residual = fit_zernike_um(x, y, opd, 4.0, 8)
    inside = rho <= 1.0
    svd, *_ = np.linalg.lstsq(basis[inside], opd[inside], rcond=None)
    assert max(abs(fitted[k] - v) for k, v in zip(keys, svd)) < 1e-12
    assert max(abs(fitted[k] - truth[k]) for k in keys) < 1e-3  # the noise's reach, 1e-3 / sqrt(N) per term
    assert residual == pytest.approx(1e-3, rel=0.1)


def test_a_fit_whose_samples_cannot_tell_terms_apart_goes_by_the_svd():
    # Samples on one line (y = 0) make the odd-in-y terms invisible: the normal matrix is singular.
    from vissim.optics.pupil.zernike import fit_zernike_um

    x = np.linspace(-1.9, 1.9, 400)
    fitted, residual = fit_zernike_um(x, np.zeros_like(x), 0.3 * x**2, 4.0, 2)
    assert np.isfinite(list(fitted.values())).all() and residual < 1e-12
    assert fitted[(1, -1)] == pytest.approx(0.0, abs=1e-12) and fitted[(2, -2)] == pytest.approx(0.0, abs=1e-12)


def test_the_gradient_of_a_defocus_and_astigmatism_is_the_textbooks():
    # Oracle: W = c20 sqrt(3) (2 rho^2 - 1) + c22 sqrt(6) (u^2 - v^2) + c2m2 sqrt(6) 2 u v (Thibos et al. 2002,
    # Table 1), differentiated by hand: dW/du = 4 sqrt(3) c20 u + 2 sqrt(6) (c22 u + c2m2 v), and likewise in v.
    c20, c22, c2m2 = 0.7, -0.3, 0.2
    u, v = np.meshgrid(np.linspace(-1.2, 1.2, 9), np.linspace(-1.1, 1.0, 7))
    du, dv = zernike_gradient({(2, 0): c20, (2, 2): c22, (2, -2): c2m2}, u, v)
    np.testing.assert_allclose(du, 4 * math.sqrt(3) * c20 * u + 2 * math.sqrt(6) * (c22 * u + c2m2 * v), atol=1e-13)
    np.testing.assert_allclose(dv, 4 * math.sqrt(3) * c20 * v + 2 * math.sqrt(6) * (-c22 * v + c2m2 * u), atol=1e-13)


@pytest.mark.parametrize("order", [1, 4, 8, 12])
def test_the_gradient_equals_central_differences_of_the_terms_one_by_one(order):
    # Oracle: zernike_nm term by term (its own Jacobi radial polynomials, not the monomials), differenced at a step
    # of 1e-5: truncation ~1e-10, round-off ~1e-11 of the front's scale.
    rng = np.random.default_rng(order)
    terms = {key: rng.normal() for key in zernike_keys(order)}
    u, v = rng.uniform(-0.7, 0.7, 200), rng.uniform(-0.7, 0.7, 200)
    h = 1e-5

    def front(a, b):
        rho, theta = np.hypot(a, b), np.arctan2(b, a)
        return sum(c * zernike_nm(n, m, rho, theta) for (n, m), c in terms.items())

    du, dv = zernike_gradient(terms, u, v)
    scale = max(np.abs(du).max(), np.abs(dv).max())
    np.testing.assert_allclose(du, (front(u + h, v) - front(u - h, v)) / (2 * h), atol=1e-8 * scale)
    np.testing.assert_allclose(dv, (front(u, v + h) - front(u, v - h)) / (2 * h), atol=1e-8 * scale)


def test_no_gradient_above_the_monomial_orders():
    assert zernike_gradient({(MAX_MONOMIAL_ORDER + 1, 1): 1.0}, 0.1, 0.2) is None
    du, dv = zernike_gradient({}, np.zeros(3), np.zeros(3))
    assert not du.any() and not dv.any()
