"""OSA/ANSI Zernike polynomials: indices, normalisation, orthonormality."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.pupil.zernike import (
    ansi_j_to_nm,
    nm_to_ansi_j,
    nm_to_noll,
    noll_to_nm,
    zernike_nm,
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
