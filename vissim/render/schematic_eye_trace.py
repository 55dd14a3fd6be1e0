"""A schematic eye traced from the retina outward in Dr.Jit arrays: the core of the eye sensor.

Frame: the eye's own (`vissim.optics.eyes.surfaces`): the corneal front vertex at the origin, z
from the cornea to the retina, x the examiner's right, y up.  Each surface is
``z = z_vertex + sag(x, y)`` (conic, biconic or plane; `vissim.optics.eyes.models`' signs) and the
rays travel towards -z, from a point on the retina out into the air in front of the cornea.

Per surface: the exact intersection (a conic's closed-form root, refined by Newton's method; a
biconic by Newton's method from the vertex plane), the exact normal ``(-grad sag, 1)`` (facing
the outgoing light) and vector Snell's law; a ray that misses a surface (beyond a conic's
domain) or is totally reflected is dropped (``valid`` False).  The iris is a plane: a ray that
crosses it farther than the iris radius from its centre (decentred ``stop_decentre_nasal_mm``
towards +x, as `vissim.optics.eyes.traced_wavefront` has it) is stopped (``valid`` False, and
``stopped`` True so a caller can count it).  A gradient-index lens half (Liou & Brennan) is
crossed by RK4 in Sharma's parameter with the numpy tracer's step rule
(`vissim.optics.raytrace.grin`: a fixed step h in t, the last step shortened by Newton's method
so the ray ends on the exit surface).

Indices: at one wavelength given as a number, each medium's formula evaluated exactly; at a
wavelength per ray (a Dr.Jit array: a spectral render's hero wavelength), each medium's n(λ)
tabulated at init every `TABLE_STEP_NM` over `vissim.checks.EYE_RENDER_WAVELENGTH_RANGE_NM` and interpolated linearly (error
below 1e-8 in n for these smooth formulas).

The arrays are those of the caller: ``mi.Float`` inside a render (float32 on the usual
variants), or a double-precision Dr.Jit type for checks.  Vectors are tuples of three arrays.
Nothing here imports Mitsuba; the numpy tracer is not used (it is the test's oracle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr

from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import GrinMedium
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.surfaces import vertex_positions_mm
from vissim.checks import EYE_RENDER_WAVELENGTH_RANGE_NM
from vissim.optics.raytrace.media import DEFAULT_GRIN_STEP_MM

__all__ = ["EyeTraceResult", "SchematicEyeTracer", "TABLE_STEP_NM"]

#: Wavelength step (nm) of the index tables used for a wavelength per ray (over
#: `vissim.checks.EYE_RENDER_WAVELENGTH_RANGE_NM`).
TABLE_STEP_NM = 0.1
#: Newton iterations: refining a conic's closed-form hit, a biconic's hit, a GRIN ray's last step.
CONIC_NEWTON, BICONIC_NEWTON, LANDING_NEWTON = 2, 12, 8


@dataclass
class EyeTraceResult:
    """Rays after the cornea: ``points`` on the corneal front (mm), unit ``directions`` in air,
    ``valid`` (mask: the ray got out), ``stopped`` (mask: the iris stopped it)."""

    points: tuple
    directions: tuple
    valid: object
    stopped: object


@dataclass(frozen=True)
class _Shape:
    kind: str  # "plane", "conic" or "biconic"
    c: float = 0.0
    conic: float = 0.0
    cy: float = 0.0
    conic_y: float = 0.0
    cos_a: float = 1.0
    sin_a: float = 0.0


def _shape(surface) -> _Shape:
    if surface.is_toric:
        a = math.radians(surface.axis_deg)
        return _Shape("biconic", 1.0 / surface.radius_mm, surface.conic, 1.0 / surface.radius_y_mm, surface.conic,
                      math.cos(a), math.sin(a))
    if math.isinf(surface.radius_mm):
        return _Shape("plane")
    return _Shape("conic", 1.0 / surface.radius_mm, surface.conic)


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _add(a, b, s=1.0):
    return (a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2])


def _scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def _not(mask):
    """Logical not of a Dr.Jit mask or a Python bool (scalar variants)."""
    return (not mask) if isinstance(mask, bool) else ~mask


def _select(mask, a, b):
    return tuple(dr.select(mask, x, y) for x, y in zip(a, b))


def _sag_and_gradient(shape: _Shape, x, y):
    """(sag, dsag/dx, dsag/dy) of ``shape`` at (x, y); NaN outside its domain."""
    if shape.kind == "plane":
        return 0.0 * x, 0.0 * x, 0.0 * x
    if shape.kind == "conic":
        c, k = shape.c, (1.0 + shape.conic) * shape.c * shape.c
        r2 = x * x + y * y
        w = dr.sqrt(1.0 - k * r2)
        return c * r2 / (1.0 + w), c * x / w, c * y / w
    u = x * shape.cos_a + y * shape.sin_a
    v = -x * shape.sin_a + y * shape.cos_a
    ax, ay = (1.0 + shape.conic) * shape.c ** 2, (1.0 + shape.conic_y) * shape.cy ** 2
    w = dr.sqrt(1.0 - ax * u * u - ay * v * v)
    one_w = 1.0 + w
    numerator = shape.c * u * u + shape.cy * v * v
    common = numerator / (w * one_w * one_w)
    gu = 2.0 * shape.c * u / one_w + common * ax * u
    gv = 2.0 * shape.cy * v / one_w + common * ay * v
    return numerator / one_w, gu * shape.cos_a - gv * shape.sin_a, gu * shape.sin_a + gv * shape.cos_a


def _first_distance(shape: _Shape, z_vertex: float, p, d):
    """Distance to the vertex branch: a conic's closed form (its root that tends to the plane's)."""
    zl = p[2] - z_vertex
    if shape.kind != "conic":
        return -zl / d[2]
    c, k = shape.c, (1.0 + shape.conic) * shape.c
    a = c * (d[0] * d[0] + d[1] * d[1]) + k * d[2] * d[2]
    b = 2.0 * (c * (p[0] * d[0] + p[1] * d[1]) - d[2] + k * zl * d[2])
    q = c * (p[0] * p[0] + p[1] * p[1]) - 2.0 * zl + k * zl * zl
    return 2.0 * q / (-b - dr.sqrt(b * b - 4.0 * a * q))  # d_z < 0: this root tends to -zl/d_z


def _intersect(shape: _Shape, z_vertex: float, p, d):
    """(hit point, valid mask) of straight rays with ``z = z_vertex + sag``."""
    s = _first_distance(shape, z_vertex, p, d)
    iterations = 0 if shape.kind == "plane" else (CONIC_NEWTON if shape.kind == "conic" else BICONIC_NEWTON)
    for _ in range(iterations):
        x, y = p[0] + s * d[0], p[1] + s * d[1]
        sag, gx, gy = _sag_and_gradient(shape, x, y)
        f = z_vertex + sag - (p[2] + s * d[2])
        s = s - f / (gx * d[0] + gy * d[1] - d[2])
    hit = _add(p, d, s)
    sag, _, _ = _sag_and_gradient(shape, hit[0], hit[1])
    return hit, dr.isfinite(s) & dr.isfinite(sag) & (s >= 0.0)


def _refract(shape: _Shape, hit, d, n1, n2):
    """Vector Snell's law at ``hit``; (new direction, not totally reflected)."""
    _, gx, gy = _sag_and_gradient(shape, hit[0], hit[1])
    inv = dr.rsqrt(gx * gx + gy * gy + 1.0)
    normal = (-gx * inv, -gy * inv, inv)  # faces the outgoing (-z) light: normal . d < 0
    mu = n1 / n2
    cos_i = -_dot(normal, d)
    sin2_t = mu * mu * (1.0 - cos_i * cos_i)
    ok = (sin2_t < 1.0) & (cos_i > 0.0)
    cos_t = dr.sqrt(dr.maximum(1.0 - sin2_t, 0.0))
    out = _add(_scale(d, mu), normal, mu * cos_i - cos_t)
    norm = dr.rsqrt(_dot(out, out))
    return _scale(out, norm), ok


class _Index:
    """n(λ) of a homogeneous medium, or a GRIN half's axial shift, exact at a number, tabulated for arrays."""

    def __init__(self, function):
        self.function = function
        self._tables = {}

    def __call__(self, wavelength):
        if not dr.is_array_v(wavelength):
            return self.function(float(wavelength))
        kind = type(wavelength)
        if kind not in self._tables:
            lo, hi = EYE_RENDER_WAVELENGTH_RANGE_NM
            count = int(round((hi - lo) / TABLE_STEP_NM)) + 1
            self._tables[kind] = kind([self.function(lo + i * TABLE_STEP_NM) for i in range(count)])
        table = self._tables[kind]
        u = dr.clip((wavelength - EYE_RENDER_WAVELENGTH_RANGE_NM[0]) / TABLE_STEP_NM, 0.0, dr.width(table) - 1.000001)
        i = dr.floor(u)
        frac = u - i
        index_type = dr.uint32_array_t(kind)
        lo_n = dr.gather(kind, table, index_type(i))
        hi_n = dr.gather(kind, table, index_type(i) + 1)
        return lo_n + frac * (hi_n - lo_n)


@dataclass
class _Grin:
    axial: _Index  # a0 + dispersion shift
    a1: float
    a2: float
    b: float
    front_z_mm: float

    def index(self, r, a0):
        u = r[2] - self.front_z_mm
        return a0 + u * (self.a1 + self.a2 * u) + self.b * (r[0] * r[0] + r[1] * r[1])

    def n_grad_n(self, r, a0):
        n = self.index(r, a0)
        u = r[2] - self.front_z_mm
        return (n * 2.0 * self.b * r[0], n * 2.0 * self.b * r[1], n * (self.a1 + 2.0 * self.a2 * u))


def _medium(medium, front_z_mm: float):
    if isinstance(medium, GrinMedium):
        coefficients = tuple(medium.z_coefficients) + (0.0,) * (3 - len(medium.z_coefficients))
        if len(coefficients) > 3:
            raise VissimInputError(f"the {medium.name}'s index is of degree {len(coefficients) - 1} in z; "
                                   "the trace takes up to 2")
        a0 = coefficients[0]
        return _Grin(_Index(lambda wl: a0 + medium.shift(wl)), coefficients[1], coefficients[2],
                     medium.r2_coefficient, front_z_mm)
    return _Index(medium.index)


def _phase_gradient(plane, x, y):
    """(∂φ/∂x, ∂φ/∂y) of a phase plane's polynomial ``Σ c u^p v^q`` (u, v: about its centre over its radius)."""
    r = plane.radius_mm
    u, v = (x - plane.centre_mm[0]) / r, (y - plane.centre_mm[1]) / r
    top = max((max(p, q) for p, q, _ in plane.terms), default=0)
    u_pow, v_pow = [1.0 + 0.0 * u], [1.0 + 0.0 * v]
    for _ in range(top):
        u_pow.append(u_pow[-1] * u)
        v_pow.append(v_pow[-1] * v)
    gx, gy = 0.0 * u, 0.0 * v
    for p, q, c in plane.terms:
        if p > 0:
            gx = gx + (c * p / r) * u_pow[p - 1] * v_pow[q]
        if q > 0:
            gy = gy + (c * q / r) * u_pow[p] * v_pow[q - 1]
    return gx, gy


def _excess(shape: _Shape, z_vertex: float, r):
    """``z_vertex + sag(x, y) - z``: negative before the surface (for light going to -z), positive beyond."""
    sag, _, _ = _sag_and_gradient(shape, r[0], r[1])
    return z_vertex + sag - r[2]


def _rk4(grin: _Grin, a0, r, t_vec, h):
    """One classical RK4 step of size ``h`` in Sharma's t: dr/dt = T, dT/dt = n grad n."""
    k1r, k1t = t_vec, grin.n_grad_n(r, a0)
    k2r = _add(t_vec, k1t, 0.5 * h)
    k2t = grin.n_grad_n(_add(r, k1r, 0.5 * h), a0)
    k3r = _add(t_vec, k2t, 0.5 * h)
    k3t = grin.n_grad_n(_add(r, k2r, 0.5 * h), a0)
    k4r = _add(t_vec, k3t, h)
    k4t = grin.n_grad_n(_add(r, k3r, h), a0)
    sixth = h / 6.0
    r_new = tuple(r[i] + sixth * (k1r[i] + 2.0 * k2r[i] + 2.0 * k3r[i] + k4r[i]) for i in range(3))
    t_new = tuple(t_vec[i] + sixth * (k1t[i] + 2.0 * k2t[i] + 2.0 * k3t[i] + k4t[i]) for i in range(3))
    return r_new, t_new


class SchematicEyeTracer:
    """``eye`` traced from the retina outward (module doc); ``iris_mm``: the iris diameter (None: no stop).

    ``grin_step_mm``: the RK4 step in t (the numpy tracer's default); ``max_grin_steps``: steps a
    ray may take in one GRIN half before it is dropped; ``phase``: a phase plane in the air before the
    cornea (`vissim.optics.raytrace.phase.PhasePlane`: a measured eye's), crossed last (`_through_phase`).
    """

    def __init__(self, eye: SchematicEye, iris_mm: float | None, grin_step_mm: float = DEFAULT_GRIN_STEP_MM,
                 max_grin_steps: int = 2000, phase=None):
        if iris_mm is not None and not (math.isfinite(iris_mm) and iris_mm > 0.0):
            raise VissimInputError(f"iris diameter must be a positive number of mm, got {iris_mm!r}")
        self.eye = eye
        self.iris_radius_mm = math.inf if iris_mm is None else 0.5 * float(iris_mm)
        self.grin_step_mm = float(grin_step_mm)
        self.max_grin_steps = int(max_grin_steps)
        positions = vertex_positions_mm(eye)
        self.z_mm = positions
        self.shapes = tuple(_shape(s) for s in eye.surfaces)
        self.media = tuple(_medium(s.medium_after, z) for s, z in zip(eye.surfaces, positions))
        self.air = _Index(eye.object_medium.index)
        self.phase = phase

    @property
    def retina_z_mm(self) -> float:
        """The retina's vertex z, mm."""
        return self.z_mm[-1]

    def retina_point(self, x, y):
        """The point of the retina above (x, y) (mm), as a 3-tuple."""
        sag, _, _ = _sag_and_gradient(self.shapes[-1], x, y)
        return (x, y, self.retina_z_mm + sag)

    def surface_point(self, i: int, x, y):
        """The point of surface ``i`` above (x, y) (mm), as a 3-tuple."""
        sag, _, _ = _sag_and_gradient(self.shapes[i], x, y)
        return (x, y, self.z_mm[i] + sag)

    def projected_solid_angle_weight(self, retina_points, offsets):
        """``cos θ_r |d_z| / |offset|²`` (1/mm²): the projected solid angle per unit x-y area at the far
        end of ``offsets`` (retina point to a point sampled uniformly in x, y), θ_r the angle between
        the ray and the retina's normal."""
        _, gx, gy = _sag_and_gradient(self.shapes[-1], retina_points[0], retina_points[1])
        inv_n = dr.rsqrt(gx * gx + gy * gy + 1.0)
        dist2 = _dot(offsets, offsets)
        inv_d = dr.rsqrt(dist2)
        cos_retina = (gx * offsets[0] + gy * offsets[1] - offsets[2]) * inv_n * inv_d
        return cos_retina * dr.abs(offsets[2]) * inv_d / dist2

    def trace_out(self, points, directions, wavelength_nm) -> EyeTraceResult:
        """Rays from ``points`` (3-tuples of arrays, on or in front of the retina, in the vitreous) along
        ``directions`` (d_z < 0) out through the eye into air, at ``wavelength_nm`` (a number or an array)."""
        p = tuple(points)
        norm = dr.rsqrt(_dot(directions, directions))
        d = _scale(directions, norm)
        valid = d[2] < 0.0
        stopped = valid & False
        for i in range(len(self.shapes) - 2, -1, -1):
            shape, z_vertex, inside = self.shapes[i], self.z_mm[i], self.media[i]
            outside = self.media[i - 1] if i > 0 else self.air
            if isinstance(inside, _Grin):
                p, d, ok = self._through_grin(inside, shape, z_vertex, p, d, wavelength_nm)
            else:
                p, ok = _intersect(shape, z_vertex, p, d)
            valid = valid & ok
            if self.eye.surfaces[i].kind == "stop":
                dx = p[0] - self.eye.stop_decentre_nasal_mm
                passes = dx * dx + p[1] * p[1] <= self.iris_radius_mm ** 2
                stopped = stopped | (valid & _not(passes))
                valid = valid & passes
            else:
                d, ok = _refract(shape, p, d, self._index(inside, p, wavelength_nm),
                                 self._index(outside, p, wavelength_nm))
                valid = valid & ok
            # dropped rays continue harmlessly along the axis, so no NaN reaches later surfaces
            p = _select(valid, p, (0.0 * p[0], 0.0 * p[0], z_vertex + 0.0 * p[0]))
            d = _select(valid, d, (0.0 * p[0], 0.0 * p[0], -1.0 + 0.0 * p[0]))
        if self.phase is not None:
            p, d, ok = self._through_phase(p, d, self.air(wavelength_nm))
            valid = valid & ok
        return EyeTraceResult(p, d, valid, stopped)

    def _through_phase(self, p, d, n_air):
        """The phase plane, virtual (`vissim.optics.raytrace.phase` module doc): along the ray to its plane, the
        direction cosines across the axis changed by its gradient over the index, back to the ray's own z."""
        plane = self.phase
        to_plane = (plane.vertex_z_mm - p[2]) / d[2]
        hit = _add(p, d, to_plane)
        gx, gy = _phase_gradient(plane, hit[0], hit[1])
        ax, ay = d[0] + gx / n_air, d[1] + gy / n_air
        left = 1.0 - ax * ax - ay * ay
        turned = (ax, ay, -dr.sqrt(dr.maximum(left, 0.0)))  # out of the eye: towards -z
        ok = left > 0.0
        back = (p[2] - hit[2]) / dr.select(ok, turned[2], -1.0)
        point = _select(ok, _add(hit, turned, back), p)  # a ray turned past grazing is dropped, harmlessly
        return point, _select(ok, turned, (0.0 * p[0], 0.0 * p[0], -1.0 + 0.0 * p[0])), ok

    @staticmethod
    def _index(medium, p, wavelength_nm):
        if isinstance(medium, _Grin):
            return medium.index(p, medium.axial(wavelength_nm))
        return medium(wavelength_nm)

    def _through_grin(self, grin: _Grin, exit_shape: _Shape, exit_z: float, p, d, wavelength_nm):
        """From the entrance point ``p`` (direction ``d`` inside) to the exit surface: (point, direction, ok)."""
        a0 = grin.axial(wavelength_nm)
        h = self.grin_step_mm
        t_vec = _scale(d, grin.index(p, a0))
        excess = _excess(exit_shape, exit_z, p)
        active = excess < 0.0
        lost = _not(active)
        e_after = excess * 0.0 + 1.0
        steps = dr.uint32_array_t(type(excess))(0) if dr.is_array_v(excess) else 0

        def cond(r0, r1, r2, t0, t1, t2, e, e_next, on, gone, k):
            return on

        def body(r0, r1, r2, t0, t1, t2, e, e_next, on, gone, k):
            r, t = (r0, r1, r2), (t0, t1, t2)
            r_new, t_new = _rk4(grin, a0, r, t, h)
            e_new = _excess(exit_shape, exit_z, r_new)
            bad = (t_new[2] >= 0.0) | _not(dr.isfinite(e_new))  # turned back or left the surface's domain
            crossed = (e_new >= 0.0) & _not(bad)
            advance = _not(crossed) & _not(bad)
            r = _select(advance, r_new, r)
            t = _select(advance, t_new, t)
            e = dr.select(advance, e_new, e)
            e_next = dr.select(crossed, e_new, e_next)
            k = k + 1
            gone = gone | bad | (advance & (k >= self.max_grin_steps))
            on = advance & (k < self.max_grin_steps)
            return (*r, *t, e, e_next, on, gone, k)

        state = dr.while_loop(state=(*p, *t_vec, excess, e_after, active, lost, steps), cond=cond, body=body,
                              labels=("r0", "r1", "r2", "t0", "t1", "t2", "e", "e_next", "on", "gone", "k"),
                              label="vissim_schematic_eye_grin")
        r, t_vec, excess, e_after, lost = state[0:3], state[3:6], state[6], state[7], state[9]
        return self._land(grin, a0, exit_shape, exit_z, r, t_vec, h * excess / (excess - e_after), _not(lost))

    @staticmethod
    def _land(grin, a0, exit_shape, exit_z, r, t_vec, h_try, ok):
        """The shortened last step (Newton on the exit surface's excess), then the unit direction."""
        for _ in range(LANDING_NEWTON):
            r_new, t_new = _rk4(grin, a0, r, t_vec, h_try)
            f = _excess(exit_shape, exit_z, r_new)
            _, gx, gy = _sag_and_gradient(exit_shape, r_new[0], r_new[1])
            h_try = h_try - f / (gx * t_new[0] + gy * t_new[1] - t_new[2])
        r_new, t_new = _rk4(grin, a0, r, t_vec, h_try)
        ok = ok & dr.isfinite(h_try) & (h_try >= 0.0)
        return r_new, _scale(t_new, dr.rsqrt(_dot(t_new, t_new))), ok
