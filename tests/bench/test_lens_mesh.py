"""Trial-lens meshes: shape, normals, power, PLY bytes and the cache (no rendering).

Expected values come from the lens's own definition in :mod:`vissim.optics.rx.trial_lens`: the marked
power is the back vertex power, surface radii follow the lensmaker relation
(``TrialLens.surface_radii_mm``), and a sphere of radius R has sag R - sqrt(R^2 - a^2) at
semi-aperture a.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.optics.rx.trial_lens import lens_surface_curvatures_per_mm
from vissim.bench.lenses.mesh import (
    cached_lens_ply,
    lens_mesh,
    ply_bytes,
    realistic_center_thickness_mm,
    rim_thickness_mm,
    sag_gradient,
    sag_mm,
    write_ply,
)
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX, TrialLens

APERTURE_MM = 30.0


def thick_lens(sphere, cylinder=0.0, axis=180.0, back=0.0, aperture=APERTURE_MM):
    t = realistic_center_thickness_mm(TrialLens(sphere, cylinder, axis).marked_power, aperture, CROWN_GLASS_INDEX,
                                      back_surface_diopters=back)
    return TrialLens(sphere, cylinder, axis, refractive_index=CROWN_GLASS_INDEX, center_thickness_mm=t,
                     back_surface_diopters=back)


# ------------------------------------------------------------------ a ray tracer on the mesh


def _intersect(mesh, origin, direction):
    """Nearest hit of one ray with the mesh (Moller-Trumbore); (t, point, interpolated unit normal)."""
    v = mesh.vertices_mm[mesh.faces]
    e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - v[:, 0]
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    w = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= -1e-12) & (w >= -1e-12) & (u + w <= 1 + 1e-12) & (t > 1e-9)
    k = np.flatnonzero(hit)[np.argmin(t[hit])]
    n = mesh.normals[mesh.faces[k]]
    normal = (1 - u[k] - w[k]) * n[0] + u[k] * n[1] + w[k] * n[2]
    return t[k], origin + t[k] * direction, normal / np.linalg.norm(normal)


def _refract(direction, normal, n1, n2):
    if direction @ normal > 0:
        normal = -normal  # face the incoming ray
    eta = n1 / n2
    cos_i = -(direction @ normal)
    sin2_t = eta**2 * (1 - cos_i**2)
    return eta * direction + (eta * cos_i - math.sqrt(1 - sin2_t)) * normal


def _trace_back_vertex_power(mesh, height_xy_mm):
    """Trace a ray parallel to the axis from the chart side; return the power at the back vertex (D)."""
    n = mesh.refractive_index
    origin = np.array([*height_xy_mm, mesh.center_thickness_mm + 5.0])
    direction = np.array([0.0, 0.0, -1.0])
    _, point, normal = _intersect(mesh, origin, direction)
    direction = _refract(direction, normal, 1.0, n)
    _, point, normal = _intersect(mesh, point, direction)
    direction = _refract(direction, normal, n, 1.0)
    # Where the ray meets the axis in its meridian (z < 0: a real focus behind the back vertex).
    radial = np.asarray(height_xy_mm) / np.linalg.norm(height_xy_mm)
    height, slope = point[:2] @ radial, direction[:2] @ radial / direction[2]
    z_focus = point[2] - height / slope
    return -1000.0 / z_focus


# ------------------------------------------------------------------ tests


def test_plus_lens_keeps_one_mm_edge_and_minus_lens_one_mm_centre():
    plus, minus = thick_lens(+4.0), thick_lens(-4.0)
    assert rim_thickness_mm(plus, APERTURE_MM)[0] == pytest.approx(1.0, abs=1e-9)
    assert plus.center_thickness_mm > 1.0
    assert minus.center_thickness_mm == 1.0
    assert rim_thickness_mm(minus, APERTURE_MM)[0] > 1.0


@pytest.mark.parametrize("lens", [thick_lens(+4.0), thick_lens(-2.0), thick_lens(+2.0, -1.5, 30.0, back=-3.0)],
                         ids=["+4", "-2", "toric-meniscus"])
def test_vertex_normals_are_unit_and_match_finite_difference_surface_normals(lens):
    mesh = lens_mesh(lens, APERTURE_MM, rings=8, segments=32)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    front, back = lens_surface_curvatures_per_mm(lens)
    h = 1e-5  # mm; central differences, error ~ h^2 * curvature^3 << 1e-9
    n_cap = 1 + 8 * 32
    for curvature, z0, sign, sl in ((front, lens.center_thickness_mm, 1.0, slice(0, n_cap)),
                                    (back, 0.0, -1.0, slice(n_cap, 2 * n_cap))):
        xy = mesh.vertices_mm[sl, :2]
        assert np.allclose(mesh.vertices_mm[sl, 2], z0 - sag_mm(curvature, xy), atol=1e-12)
        fd = np.stack([(sag_mm(curvature, xy + d) - sag_mm(curvature, xy - d)) / (2 * h)
                       for d in (np.array([h, 0.0]), np.array([0.0, h]))], axis=1)
        assert np.allclose(sag_gradient(curvature, xy), fd, atol=1e-9)
        expected = sign * np.concatenate([fd, np.ones((len(xy), 1))], axis=1)
        expected /= np.linalg.norm(expected, axis=1, keepdims=True)
        assert np.allclose(mesh.normals[sl], expected, atol=1e-9)
    wall = mesh.normals[2 * n_cap:]
    assert np.allclose(wall[:, 2], 0.0) and np.allclose(np.linalg.norm(wall[:, :2], axis=1), 1.0)


def test_faces_wind_counter_clockwise_seen_from_outside():
    mesh = lens_mesh(thick_lens(+2.0, 1.0, 45.0, back=-2.0), APERTURE_MM, rings=6, segments=24)
    v = mesh.vertices_mm[mesh.faces]
    winding = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    assert np.all(np.einsum("ij,ij->i", winding, mesh.normals[mesh.faces].mean(axis=1)) > 0)


@pytest.mark.parametrize("sphere", [+4.0, -4.0])
def test_sag_at_the_rim_matches_the_lensmaker_radius(sphere):
    lens = thick_lens(sphere, back=-6.0)
    mesh = lens_mesh(lens, APERTURE_MM, rings=4, segments=16)
    (front_r, _), (back_r, _) = (r.radii_mm for r in lens.surface_radii_mm())
    a = APERTURE_MM / 2

    def sphere_sag(radius):  # signed: radius > 0 -> centre on the camera side, sag > 0
        return math.copysign(abs(radius) - math.sqrt(radius**2 - a**2), radius)

    n_cap = 1 + 4 * 16
    front_rim, back_rim = mesh.vertices_mm[n_cap - 16:n_cap], mesh.vertices_mm[2 * n_cap - 16:2 * n_cap]
    assert np.allclose(front_rim[:, 2], lens.center_thickness_mm - sphere_sag(front_r), atol=1e-12)
    assert np.allclose(back_rim[:, 2], -sphere_sag(back_r), atol=1e-12)


@pytest.mark.parametrize(
    "lens, meridian_deg",
    [(thick_lens(+4.0), 180.0), (thick_lens(-4.0, back=-6.0), 90.0), (thick_lens(+2.0), 90.0),
     (thick_lens(0.0, +2.0, 90.0), 180.0), (thick_lens(0.0, +2.0, 90.0), 90.0),
     (thick_lens(-1.0, -2.0, 180.0, back=-4.0), 90.0)],
    ids=["+4 x", "-4 meniscus y", "+2 y", "+2x90 x", "+2x90 y", "toric meniscus y"],
)
def test_paraxial_ray_through_the_mesh_reproduces_the_back_vertex_power(lens, meridian_deg):
    """Ray at 0.3 mm height: the 16-ring mesh refracts like a lens of the marked power to 2e-4 D.

    Measured when written: errors <= 1.4e-4 D (the -4 D meniscus; a 160-ring mesh gives 5e-5 D,
    the lens's own spherical aberration at 0.3 mm), the rest <= 5e-5 D."""
    mesh = lens_mesh(lens, APERTURE_MM)
    direction = np.array([math.cos(math.radians(meridian_deg)), math.sin(math.radians(meridian_deg))])
    traced = _trace_back_vertex_power(mesh, 0.3 * direction)
    assert traced == pytest.approx(lens.marked_power.meridian_power(meridian_deg), abs=2e-4)


def test_ply_bytes_are_deterministic_and_parse_back(tmp_path):
    lens = thick_lens(+2.0, -1.0, 30.0)
    data = ply_bytes(lens_mesh(lens, APERTURE_MM, rings=3, segments=12))
    assert data == ply_bytes(lens_mesh(lens, APERTURE_MM, rings=3, segments=12))
    path = write_ply(lens_mesh(lens, APERTURE_MM, rings=3, segments=12), tmp_path / "lens.ply")
    assert path.read_bytes() == data
    header, body = data.split(b"end_header\n", 1)
    assert b"format binary_little_endian 1.0" in header
    n_vertex = 1 + 2 * (1 + 3 * 12) - 1 + 2 * 12  # two caps of 37 vertices, two rims of 12
    assert f"element vertex {n_vertex}".encode() in header
    vertices = np.frombuffer(body[: n_vertex * 24], dtype="<f4").reshape(-1, 6)
    mesh = lens_mesh(lens, APERTURE_MM, rings=3, segments=12)
    assert np.allclose(vertices[:, :3], mesh.vertices_mm, atol=1e-5)
    faces = np.frombuffer(body[n_vertex * 24:], dtype=[("n", "u1"), ("i", "<i4", (3,))])
    assert np.all(faces["n"] == 3) and np.array_equal(faces["i"], mesh.faces)
    with pytest.raises(VissimInputError, match="already exists"):
        write_ply(mesh, path)


def test_cache_reuses_the_file_for_the_same_geometry(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path))
    lens = thick_lens(-2.0)
    first = cached_lens_ply(lens, APERTURE_MM, rings=4, segments=16)
    assert first.parent == tmp_path / "meshes"
    stamp = first.stat().st_mtime_ns
    again = cached_lens_ply(TrialLens(-2.0, refractive_index=CROWN_GLASS_INDEX, center_thickness_mm=1.0),
                            APERTURE_MM, rings=4, segments=16)
    assert again == first and again.stat().st_mtime_ns == stamp
    assert cached_lens_ply(lens, APERTURE_MM, rings=5, segments=16) != first
    assert cached_lens_ply(lens, APERTURE_MM + 1, rings=4, segments=16) != first
    assert first.read_bytes() == ply_bytes(lens_mesh(lens, APERTURE_MM, rings=4, segments=16))
    assert [p.name for p in (tmp_path / "meshes").iterdir() if p.name.startswith(".")] == []


def test_bad_meshes_are_refused_with_one_line_naming_the_value():
    with pytest.raises(VissimInputError, match="thin"):
        lens_mesh(TrialLens(2.0), APERTURE_MM)
    with pytest.raises(VissimInputError, match="edge"):
        lens_mesh(TrialLens(8.0, refractive_index=CROWN_GLASS_INDEX, center_thickness_mm=1.0), APERTURE_MM)
    with pytest.raises(VissimInputError, match="clear aperture"):
        lens_mesh(thick_lens(2.0), -3.0)
    with pytest.raises(VissimInputError, match="rings"):
        lens_mesh(thick_lens(2.0), APERTURE_MM, rings=0)
