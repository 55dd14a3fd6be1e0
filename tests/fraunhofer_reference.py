"""Independent reference for wave PSFs (issue 12): direct quadrature of the Fraunhofer integral.

    E(a) = ∫_disc exp(i k [W(x) - x·a]) d²x,   I(a) = |E(a)|² / (λ² A),   ∫ I d²a = 1

with k = 2π/λ, a the viewing direction in radians and x the pupil point, both in the OSA frame
(+x examiner's right = observer's left, +y up).  Shares no code with vissim: its own OSA
Zernikes (factorial formula), its own units, numpy/scipy only.

Quadrature: Gauss-Legendre in r over [0, R] (the hard pupil edge is the interval's end, so it
is exact there), the trapezoid rule in θ (spectrally exact for a periodic integrand), and
q x q Gauss-Legendre points over each output pixel for pixel integrals.  Node counts follow
from the largest phase rate k (|∇W| + |a|) and the intensity's band limit D/λ; doubling them
(``node_scale=2``, ``gl_pixel=2q``) changes the answer by < 1e-6 of the peak
(tests/test_fraunhofer_reference.py).

Orientation (docs/conventions.md): output offsets (dr, dc) = (row - N//2, col - N//2) at step s
look in the OSA direction a = (-dc s, -dr s); light from pupil point x goes where ∇W(x) = a.
"""

from __future__ import annotations

import math

import numpy as np

RAD_PER_ARCMIN = math.pi / (180.0 * 60.0)
MM_PER_NM = 1e-6
MM_PER_UM = 1e-3
#: Largest complex work array, elements (16 B each): 2^22 = 64 MiB, a few alive at once.
CHUNK_ELEMENTS = 1 << 22


def zernike_radial(n: int, m: int, rho):
    """R_n^|m|(ρ) = Σ_k (-1)^k (n-k)! / (k! ((n+m)/2-k)! ((n-m)/2-k)!) ρ^(n-2k)."""
    m = abs(m)
    if n < 0 or m > n or (n - m) % 2:
        raise ValueError(f"invalid Zernike term ({n}, {m})")
    rho = np.asarray(rho, dtype=float)
    out = np.zeros_like(rho)
    for k in range((n - m) // 2 + 1):
        coefficient = (-1) ** k * math.factorial(n - k) / (
            math.factorial(k) * math.factorial((n + m) // 2 - k) * math.factorial((n - m) // 2 - k)
        )
        out = out + coefficient * rho ** (n - 2 * k)
    return out


def zernike_osa(n: int, m: int, rho, theta):
    """OSA/ANSI unit-RMS term: √((2-δ_m0)(n+1)) R_n^|m| × cos(mθ) (m ≥ 0) or sin(|m|θ) (m < 0)."""
    norm = math.sqrt((1.0 if m == 0 else 2.0) * (n + 1))
    theta = np.asarray(theta, dtype=float)
    angular = np.cos(m * theta) if m >= 0 else np.sin(-m * theta)
    return norm * zernike_radial(n, m, rho) * angular


def wavefront_um(coefficients_um, measured_diameter_mm, x_mm, y_mm):
    """W (µm) at OSA pupil points (mm); the polynomials are normalised over the measurement pupil."""
    x_mm, y_mm = np.asarray(x_mm, dtype=float), np.asarray(y_mm, dtype=float)
    rho = np.hypot(x_mm, y_mm) / (measured_diameter_mm / 2.0)
    theta = np.arctan2(y_mm, x_mm)
    out = np.zeros(np.broadcast(x_mm, y_mm).shape)
    for (n, m), c_um in dict(coefficients_um).items():
        out = out + float(c_um) * zernike_osa(int(n), int(m), rho, theta)
    return out


def max_slope_rad(coefficients_um, measured_diameter_mm, pupil_diameter_mm) -> float:
    """Largest |∇W| over the pupil (µm/mm = mrad, returned in rad), central differences, +10 %."""
    radius_mm = pupil_diameter_mm / 2.0
    rho = np.linspace(0.0, 1.0, 65)
    theta = np.linspace(0.0, 2 * np.pi, 128, endpoint=False)
    x = radius_mm * rho[:, None] * np.cos(theta)[None, :]
    y = radius_mm * rho[:, None] * np.sin(theta)[None, :]
    h = 1e-4 * radius_mm

    def w(dx, dy):
        return wavefront_um(coefficients_um, measured_diameter_mm, x + dx, y + dy)

    gx = (w(h, 0) - w(-h, 0)) / (2 * h)
    gy = (w(0, h) - w(0, -h)) / (2 * h)
    return 1.1e-3 * float(np.max(np.hypot(gx, gy)))


def _gl_count(omega: float, floor: int) -> int:
    # Gauss-Legendre on exp(iωt), t in [-1, 1], is exact to ~1e-12 beyond n ≈ 0.55 ω + 15.
    return math.ceil(0.6 * omega + 3.0 * omega ** (1 / 3)) + floor


def node_counts(coefficients_um, measured_diameter_mm, pupil_diameter_mm, wavelength_nm, max_angle_rad):
    """(n_r, n_θ) for directions up to ``max_angle_rad``: from the largest phase rate k(|∇W| + |a|)."""
    k_per_mm = 2 * math.pi / (wavelength_nm * MM_PER_NM)
    radius_mm = pupil_diameter_mm / 2.0
    z = k_per_mm * radius_mm * (max_slope_rad(coefficients_um, measured_diameter_mm, pupil_diameter_mm) + max_angle_rad)
    n_r = _gl_count(z / 2.0, 16)  # half the radius per unit of t
    n_theta = math.ceil(z + 10.0 * z ** (1 / 3)) + 24  # trapezoid error ~ J_n(z), n > z
    return n_r, n_theta + n_theta % 2


def pixel_gl_order(pupil_diameter_mm, wavelength_nm, arcmin_per_px) -> int:
    """GL points per pixel axis: I(a) has band limit D/λ, so ω = π s D/λ over the half pixel."""
    omega = math.pi * arcmin_per_px * RAD_PER_ARCMIN * pupil_diameter_mm / (wavelength_nm * MM_PER_NM)
    return _gl_count(omega, 4)


def pupil_nodes(coefficients_um, measured_diameter_mm, pupil_diameter_mm, wavelength_nm, n_r, n_theta):
    """Nodes (x_mm, y_mm) and complex weights w exp(i k W) (mm²) of the pupil quadrature."""
    radius_mm = pupil_diameter_mm / 2.0
    t, wt = np.polynomial.legendre.leggauss(n_r)
    r = radius_mm * (t + 1) / 2
    w_r = wt * radius_mm / 2 * r  # includes the Jacobian r
    theta = 2 * np.pi * np.arange(n_theta) / n_theta
    x = (r[:, None] * np.cos(theta)[None, :]).ravel()
    y = (r[:, None] * np.sin(theta)[None, :]).ravel()
    k_per_um = 2 * math.pi / (wavelength_nm * 1e-3)
    phase = k_per_um * wavefront_um(coefficients_um, measured_diameter_mm, x, y)
    weights = (w_r[:, None] * np.full(n_theta, 2 * np.pi / n_theta)[None, :]).ravel() * np.exp(1j * phase)
    return x, y, weights


def directions_rad(arcmin_per_px, offsets_px):
    """OSA directions (a_x, a_y) in rad of output offsets (dr, dc): a = (-dc s, -dr s)."""
    offsets = np.asarray(offsets_px, dtype=float).reshape(-1, 2)
    step_rad = arcmin_per_px * RAD_PER_ARCMIN
    return -offsets[:, 1] * step_rad, -offsets[:, 0] * step_rad


def pixel_values(
    coefficients_um,
    measured_diameter_mm,
    pupil_diameter_mm,
    wavelength_nm,
    arcmin_per_px,
    offsets_px,
    *,
    integrate=True,
    gl_pixel=None,
    node_scale=1,
):
    """Absolute PSF values at output offsets ``offsets_px`` = [(dr, dc), ...].

    ``integrate=True``: B = ∫_pixel I d²a, the fraction of all the energy in the pixel (what
    ``compute_psf(pixel="integrate").data * energy_in_field`` holds).  ``integrate=False``:
    I(a) s² at the pixel centre (point value times the pixel's solid angle, s in rad).
    ``gl_pixel`` overrides q (GL points per pixel axis); ``node_scale`` multiplies the pupil's
    node counts (n_r, n_θ).  Doubling either is the convergence check.
    """
    ax, ay = directions_rad(arcmin_per_px, offsets_px)
    step_rad = arcmin_per_px * RAD_PER_ARCMIN
    q = (gl_pixel or pixel_gl_order(pupil_diameter_mm, wavelength_nm, arcmin_per_px)) if integrate else 1
    reach_rad = float(np.max(np.hypot(ax, ay), initial=0.0)) + (step_rad / math.sqrt(2) if integrate else 0.0)
    n_r, n_theta = node_counts(coefficients_um, measured_diameter_mm, pupil_diameter_mm, wavelength_nm, reach_rad)
    x, y, g = pupil_nodes(
        coefficients_um, measured_diameter_mm, pupil_diameter_mm, wavelength_nm, node_scale * n_r, node_scale * n_theta
    )
    k_per_mm = 2 * math.pi / (wavelength_nm * MM_PER_NM)
    if integrate:
        t, wt = np.polynomial.legendre.leggauss(q)
        delta_rad = step_rad / 2 * t  # sub-point offsets, the same along both axes
        sub_weights = (wt[:, None] * wt[None, :]) / 4.0  # fractions of the pixel (sum 1)
    else:
        delta_rad, sub_weights = np.zeros(1), np.ones((1, 1))
    n_pix = ax.size
    field = np.zeros((n_pix, q, q), dtype=complex)
    node_chunk = max(256, CHUNK_ELEMENTS // max(q * q, n_pix))
    pixel_chunk = max(1, CHUNK_ELEMENTS // (node_chunk * q))
    for lo in range(0, x.size, node_chunk):
        xs, ys, gs = x[lo : lo + node_chunk], y[lo : lo + node_chunk], g[lo : lo + node_chunk]
        ux = np.exp(-1j * k_per_mm * xs[:, None] * delta_rad[None, :])  # (nodes, q)
        uy = np.exp(-1j * k_per_mm * ys[:, None] * delta_rad[None, :])
        for p0 in range(0, n_pix, pixel_chunk):
            p1 = min(n_pix, p0 + pixel_chunk)
            h = gs[:, None] * np.exp(-1j * k_per_mm * (xs[:, None] * ax[None, p0:p1] + ys[:, None] * ay[None, p0:p1]))
            stacked = (h[:, :, None] * ux[:, None, :]).reshape(xs.size, -1)  # (nodes, pixels*q)
            field[p0:p1] += (stacked.T @ uy).reshape(p1 - p0, q, q)
    area_mm2 = math.pi * (pupil_diameter_mm / 2.0) ** 2
    intensity = np.abs(field) ** 2 / ((wavelength_nm * MM_PER_NM) ** 2 * area_mm2)  # per sr
    return np.einsum("pij,ij->p", intensity, sub_weights) * step_rad**2


def airy_intensity_per_sr(pupil_diameter_mm, wavelength_nm, angle_rad):
    """Analytic Airy pattern (A/λ²) [2 J1(v)/v]², v = π D |a| / λ (Born & Wolf 8.5.2)."""
    from scipy.special import j1

    wavelength_mm = wavelength_nm * MM_PER_NM
    v = np.pi * pupil_diameter_mm * np.abs(np.asarray(angle_rad, dtype=float)) / wavelength_mm
    safe = np.where(v == 0, 1.0, v)
    amplitude = np.where(v == 0, 1.0, 2 * j1(safe) / safe)
    area_mm2 = math.pi * (pupil_diameter_mm / 2.0) ** 2
    return area_mm2 / wavelength_mm**2 * amplitude**2


def airy_pixel_values(pupil_diameter_mm, wavelength_nm, arcmin_per_px, offsets_px, *, gl_pixel=None):
    """∫_pixel of the analytic Airy pattern (q x q Gauss-Legendre), fraction of the energy."""
    ax, ay = directions_rad(arcmin_per_px, offsets_px)
    step_rad = arcmin_per_px * RAD_PER_ARCMIN
    q = gl_pixel or pixel_gl_order(pupil_diameter_mm, wavelength_nm, arcmin_per_px)
    t, wt = np.polynomial.legendre.leggauss(q)
    d = step_rad / 2 * t
    out = np.zeros(ax.size)
    for i in range(q):
        for j in range(q):
            angle = np.hypot(ax + d[i], ay + d[j])
            out += wt[i] * wt[j] / 4.0 * airy_intensity_per_sr(pupil_diameter_mm, wavelength_nm, angle)
    return out * step_rad**2


def defocus_otf(pupil_diameter_mm, wavelength_nm, w020_um, shift_mm):
    """Exact OTF of a circular pupil with defocus W = W020 (r/R)², at pupil shift d = λ ν (mm).

    OTF(d) = (1/A) ∫ h(u) cos(2 k β d u) du over the lens-shaped overlap, h its chord height,
    β = W020/R² (Hopkins 1955; Goodman, Introduction to Fourier Optics §6.4); with
    u + d/2 = R sin φ the integrand is smooth and scipy.integrate.quad converges fully.
    """
    from scipy.integrate import quad

    radius_mm = pupil_diameter_mm / 2.0
    d = abs(float(shift_mm))
    if d >= 2 * radius_mm:
        return 0.0
    k_per_mm = 2 * math.pi / (wavelength_nm * MM_PER_NM)
    omega = 2 * k_per_mm * (w020_um * MM_PER_UM / radius_mm**2) * d  # phase per mm of u
    phi0 = math.asin(d / (2 * radius_mm))

    def integrand(phi):
        return 2 * radius_mm**2 * math.cos(phi) ** 2 * math.cos(omega * (radius_mm * math.sin(phi) - d / 2))

    value, _ = quad(integrand, phi0, math.pi / 2, limit=400, epsabs=1e-13, epsrel=1e-12)
    return 2 * value / (math.pi * radius_mm**2)  # both halves u < 0 and u > 0


def probe_pixels(values, rng, n_line=13, n_random=12):
    """(row, col) of pixels everywhere: peak and its 3x3, centre, lines through the peak,
    random pixels (half of them in the bright part), the four corners."""
    n = values.shape[0]
    peak = np.unravel_index(int(np.argmax(values)), values.shape)
    points = {(n // 2, n // 2), (0, 0), (0, n - 1), (n - 1, 0), (n - 1, n - 1)}
    points |= {(min(max(peak[0] + d, 0), n - 1), min(max(peak[1] + e, 0), n - 1)) for d in (-1, 0, 1) for e in (-1, 0, 1)}
    for v in np.linspace(0, n - 1, n_line).round().astype(int):
        points |= {(peak[0], int(v)), (int(v), peak[1])}
    points |= {tuple(int(i) for i in p) for p in rng.integers(0, n, size=(n_random // 2, 2))}
    bright = np.argwhere(values > 1e-2 * values.max())
    points |= {tuple(int(i) for i in p) for p in bright[rng.choice(len(bright), n_random - n_random // 2)]}
    return np.array(sorted(points))
