"""The ten Sloan letters as vector geometry, and their rasterisation to pixel coverage.

Design grid
-----------
Each letter is drawn on its 5 x 5 design grid (Sloan 1959; NAS-NRC Committee on Vision
1980): the letter is 5 units tall and 5 wide, every stroke is 1 unit (one MAR, 1/5 of the
letter height) and every counter is at least 1 unit.  Design coordinates: ``x`` to the
right, ``y`` UP, origin at the letter's lower-left corner; the letter fills [0, 5] x [0, 5].

The shapes are built from the published design rules, not traced from a font file:

* **O** an annulus, outer radius 2.5, inner 1.5.  **C** the O with a 1-unit gap on the
  right between y = 2 and y = 3 (a Landolt-style gap one stroke wide).
* **D** a stem, straight top and bottom runs to x = 2.5, and the right half of the O annulus.
* **H** two stems and a crossbar at y = 2..3.
* **R** a stem, bars at y = 4..5 and 2..3 running to x = 3.5, a round bowl (half annulus,
  radii 0.5 / 1.5, centred at (3.5, 3.5)) and a straight leg from (2.5, 2) to the lower-right
  corner.  **S** bars at y = 4..5, 2..3, 0..1 joined by two half-annulus bowls (radii 0.5 / 1.5),
  the upper one on the left, the lower one on the right.
* Slanted strokes are parallelograms with horizontal ends whose *perpendicular* width is
  exactly 1 unit (`_slanted_stroke`).  **N**: two stems and a diagonal whose outer
  corners are the top-left (0, 5) and bottom-right (5, 0).  **V**: two strokes from the top
  corners meeting in a flat foot centred at x = 2.5.  **Z**: bars at y = 4..5 and 0..1 and a
  diagonal from the top bar's right end to the bottom bar's left end.  **K**: a stem, an arm
  from the stem (upper edge meeting it at y = 2.5) to the top-right corner, and a leg from
  the arm's lower edge (at x = 2) to the bottom-right corner.

Each letter is a union of primitives -- convex polygons and annuli clipped to a convex
polygon -- with (a) an exact vectorised `SloanLetter.inside` test and (b)
`SloanLetter.patches` for vector output (one compound path per letter, filled with
the nonzero rule, so abutting pieces leave no seams; arcs are polygonised to within
1e-4 design units, i.e. 2e-5 of the letter height).

Rasterisation (`rasterize_letter`) gives each pixel the fraction of its area that is
ink, by exact classification of pixels far from an edge and supersampling of the rest with
at least n x n (default 16 x 16) points of a Fibonacci lattice.
Pixel ``(r, c)`` covers ``[r, r+1) x [c, c+1)`` in continuous pixel coordinates; row 0 is the
TOP of the image, so design y up maps to decreasing row.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from typing import Any

import numpy as np

from vissim.errors import VissimInputError

logger = logging.getLogger(__name__)

__all__ = ["DESIGN_UNITS", "SLOAN_LETTERS", "ClippedRing", "ConvexPolygon", "SloanLetter",
           "letter_coverage_window", "rasterize_letter", "sloan_letter"]

#: Design units per letter height (and width); one unit is one stroke.
DESIGN_UNITS = 5.0

#: The ten Sloan letters, in alphabetical order.
SLOAN_LETTERS = "CDHKNORSVZ"

#: Largest distance between a true arc and its polygon in `SloanLetter.patches`, in design units.
_ARC_TOLERANCE_UNITS = 1e-4

#: Samples evaluated at once while supersampling (bounds memory).
_CHUNK_SAMPLES = 1 << 20


# ---------------------------------------------------------------- primitives

HalfPlane = tuple[float, float, float]  # (a, b, c): the points with a*x + b*y <= c


def _right_of(p: tuple[float, float], q: tuple[float, float]) -> HalfPlane:
    """Half-plane on the right of the directed line p -> q (its boundary included)."""
    a, b = -(q[1] - p[1]), q[0] - p[0]
    return (a, b, a * p[0] + b * p[1])


def _clip(vertices: np.ndarray, plane: HalfPlane) -> np.ndarray:
    """Sutherland-Hodgman: the part of a convex polygon inside one half-plane."""
    a, b, c = plane
    out = []
    n = len(vertices)
    for i in range(n):
        p, q = vertices[i], vertices[(i + 1) % n]
        fp, fq = a * p[0] + b * p[1] - c, a * q[0] + b * q[1] - c
        if fp <= 0.0:
            out.append(p)
        if (fp < 0.0 < fq) or (fq < 0.0 < fp):
            out.append(p + (q - p) * (fp / (fp - fq)))
    return np.array(out, dtype=float).reshape(-1, 2)


@dataclasses.dataclass(frozen=True)
class ConvexPolygon:
    """A convex polygon given by its vertices in counter-clockwise order (design units)."""

    vertices: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3 or not np.all(np.isfinite(v)):
            raise VissimInputError(f"a polygon needs >= 3 finite (x, y) vertices, got {self.vertices!r}")
        edges = np.roll(v, -1, axis=0) - v
        turn = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        if np.any(turn < -1e-12) or self.area <= 0.0:
            raise VissimInputError(f"polygon vertices must be convex and counter-clockwise, got {self.vertices!r}")

    @classmethod
    def from_array(cls, vertices: np.ndarray) -> ConvexPolygon:
        return cls(tuple((float(x), float(y)) for x, y in vertices))

    @property
    def area(self) -> float:
        v = np.asarray(self.vertices, dtype=float)
        return 0.5 * float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))

    def clipped(self, *planes: HalfPlane) -> ConvexPolygon:
        v = np.asarray(self.vertices, dtype=float)
        for plane in planes:
            v = _clip(v, plane)
        keep = np.ones(len(v), dtype=bool)  # drop repeated vertices left by the clipping
        keep[1:] = np.any(np.abs(np.diff(v, axis=0)) > 1e-12, axis=1)
        v = v[keep]
        if len(v) > 1 and np.all(np.abs(v[0] - v[-1]) <= 1e-12):
            v = v[:-1]
        return ConvexPolygon.from_array(v)

    def signed_margin(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Distance to the nearest edge line: >= 0 inside; ``|margin| <= r`` unless a disk of
        radius ``r`` around the point lies wholly inside (margin >= r) or outside (<= -r)."""
        v = np.asarray(self.vertices, dtype=float)
        out = None
        for p, q in zip(v, np.roll(v, -1, axis=0)):
            d = q - p
            dist = (d[0] * (y - p[1]) - d[1] * (x - p[0])) / math.hypot(d[0], d[1])
            out = dist if out is None else np.minimum(out, dist)
        return out

    def outline(self) -> list[np.ndarray]:
        """Closed counter-clockwise rings whose winding number is 1 inside, 0 outside."""
        return [np.asarray(self.vertices, dtype=float)]


def _box(x0: float, y0: float, x1: float, y1: float) -> ConvexPolygon:
    return ConvexPolygon(((x0, y0), (x1, y0), (x1, y1), (x0, y1)))


@dataclasses.dataclass(frozen=True)
class ClippedRing:
    """The annulus ``r_inner <= |p - center| <= r_outer`` intersected with a convex polygon."""

    center: tuple[float, float]
    r_inner: float
    r_outer: float
    clip: ConvexPolygon | None = None

    def __post_init__(self) -> None:
        if not (0.0 <= self.r_inner < self.r_outer and math.isfinite(self.r_outer)):
            raise VissimInputError(
                f"a ring needs 0 <= r_inner < r_outer (design units), got {self.r_inner!r}, {self.r_outer!r}"
            )

    def signed_margin(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        rho = np.hypot(x - self.center[0], y - self.center[1])
        out = np.minimum(self.r_outer - rho, rho - self.r_inner)
        return out if self.clip is None else np.minimum(out, self.clip.signed_margin(x, y))

    def _disk(self, radius: float) -> np.ndarray:
        n = max(64, math.ceil(math.pi / math.acos(1.0 - _ARC_TOLERANCE_UNITS / radius)))
        t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        disk = np.column_stack([self.center[0] + radius * np.cos(t), self.center[1] + radius * np.sin(t)])
        if self.clip is not None:
            v = np.asarray(self.clip.vertices, dtype=float)
            for p, q in zip(v, np.roll(v, -1, axis=0)):
                disk = _clip(disk, _right_of(q, p))  # inside a CCW polygon = left of each edge
        return disk

    def outline(self) -> list[np.ndarray]:
        rings = [self._disk(self.r_outer)]
        if self.r_inner > 0.0:
            hole = self._disk(self.r_inner)
            if len(hole) >= 3:
                rings.append(hole[::-1])  # clockwise: cancels the outer ring's winding
        return rings


Primitive = ConvexPolygon | ClippedRing


# ---------------------------------------------------------------- letters


@dataclasses.dataclass(frozen=True)
class SloanLetter:
    """One Sloan letter: the union of its primitives on the 5 x 5 design grid."""

    name: str
    primitives: tuple[Primitive, ...]

    def signed_margin(self, x: Any, y: Any) -> np.ndarray:
        """Max over primitives of their margins (>= 0 on ink); see `ConvexPolygon.signed_margin`."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        return functools.reduce(np.maximum, (prim.signed_margin(x, y) for prim in self.primitives))

    def inside(self, x: Any, y: Any) -> np.ndarray:
        """True where design point (x, y) (x right, y up, units of 1/5 letter height) is ink."""
        return self.signed_margin(x, y) >= 0.0

    def outline(self, origin_xy: tuple[float, float] = (0.0, 0.0), height: float = DESIGN_UNITS) -> list[np.ndarray]:
        """Closed vertex rings (y up) of the letter with its lower-left corner at ``origin_xy``."""
        scale = float(height) / DESIGN_UNITS
        return [np.asarray(origin_xy, dtype=float) + scale * ring for p in self.primitives for ring in p.outline()]

    def path(self, origin_xy: tuple[float, float] = (0.0, 0.0), height: float = DESIGN_UNITS):
        """The letter as one compound `matplotlib.path.Path`, to be filled with the nonzero rule."""
        from matplotlib.path import Path

        rings = self.outline(origin_xy, height)
        return Path.make_compound_path(*(Path(np.vstack([ring, ring[:1]]), closed=False) for ring in rings))

    def patches(self, origin_xy: tuple[float, float] = (0.0, 0.0), height: float = DESIGN_UNITS, **patch_kwargs):
        """Matplotlib patches drawing the letter (lower-left corner at ``origin_xy``, y up, data units).

        ``patch_kwargs`` go to `matplotlib.patches.PathPatch` (default: black fill, no edge).
        """
        from matplotlib.patches import PathPatch

        kwargs = {"facecolor": "black", "edgecolor": "none", "linewidth": 0.0, **patch_kwargs}
        return [PathPatch(self.path(origin_xy, height), **kwargs)]


def _slanted_stroke(
    top_xy: tuple[float, float],
    top_anchor: float,
    bottom_xy: tuple[float, float],
    bottom_anchor: float,
    *,
    extend_y: tuple[float, float] | None = None,
    clip: tuple[HalfPlane, ...] = (),
) -> tuple[ConvexPolygon, tuple[np.ndarray, ...]]:
    """A slanted stroke of perpendicular width 1 with horizontal ends.

    The top end is the horizontal segment at ``top_xy[1]`` of length ``h`` whose point at
    fraction ``top_anchor`` (0 = left end, 1 = right end) is ``top_xy``; likewise the bottom.
    ``h`` solves ``h * dy / |edge| = 1``, a quadratic in ``h``.  ``extend_y`` prolongs the
    parallelogram along its edges to that y range before clipping to the letter box and to
    ``clip``.  Returns the polygon and the unclipped corners (bottom-left, bottom-right,
    top-right, top-left).
    """
    (xt, yt), (xb, yb) = top_xy, bottom_xy
    dy, dx, k = yt - yb, xt - xb, top_anchor - bottom_anchor
    h = (-dx * k + math.sqrt(dx * dx * k * k + (dy * dy - k * k) * (dx * dx + dy * dy))) / (dy * dy - k * k)
    left_top, left_bottom = xt - top_anchor * h, xb - bottom_anchor * h
    y0, y1 = extend_y if extend_y is not None else (yb, yt)
    slope = (left_top - left_bottom) / dy

    def left(y):
        return left_bottom + (y - yb) * slope

    corners = tuple(np.array(p) for p in ((left(y0), y0), (left(y0) + h, y0), (left(y1) + h, y1), (left(y1), y1)))
    box = _box(0.0, 0.0, DESIGN_UNITS, DESIGN_UNITS)
    box_planes = tuple(_right_of(q, p) for p, q in zip(box.vertices, box.vertices[1:] + box.vertices[:1]))
    poly = ConvexPolygon.from_array(np.array(corners)).clipped(*box_planes, *clip)
    return poly, corners


def _ring(cx: float, cy: float, r_inner: float, r_outer: float, clip: ConvexPolygon | None = None) -> ClippedRing:
    return ClippedRing((cx, cy), r_inner, r_outer, clip)


def _build_letters() -> dict[str, SloanLetter]:
    stem = _box(0, 0, 1, 5)
    letters: dict[str, tuple[Primitive, ...]] = {}
    letters["O"] = (_ring(2.5, 2.5, 1.5, 2.5),)
    letters["C"] = (
        _ring(2.5, 2.5, 1.5, 2.5, _box(0, 0, 2.5, 5)),
        _ring(2.5, 2.5, 1.5, 2.5, _box(2.5, 3, 5, 5)),
        _ring(2.5, 2.5, 1.5, 2.5, _box(2.5, 0, 5, 2)),
    )
    letters["D"] = (stem, _box(0, 4, 2.5, 5), _box(0, 0, 2.5, 1), _ring(2.5, 2.5, 1.5, 2.5, _box(2.5, 0, 5, 5)))
    letters["H"] = (stem, _box(4, 0, 5, 5), _box(0, 2, 5, 3))
    # K: the arm runs from the stem (its upper edge meets the stem at y = 2.5) to the
    # top-right corner; the leg leaves the arm's lower edge at x = 2 for the bottom-right corner.
    arm, (arm_bl, arm_br, arm_tr, arm_tl) = _slanted_stroke((5, 5), 1.0, (1, 2.5), 0.0, extend_y=(1.0, 5))
    y_leg = arm_br[1] + (2.0 - arm_br[0]) * (arm_tr[1] - arm_br[1]) / (arm_tr[0] - arm_br[0])
    leg, _ = _slanted_stroke((2.0, y_leg), 0.0, (5, 0), 1.0, extend_y=(0, 5), clip=(_right_of(arm_bl, arm_tl),))
    letters["K"] = (stem, arm, leg)
    diagonal, _ = _slanted_stroke((0, 5), 0.0, (5, 0), 1.0)
    letters["N"] = (stem, _box(4, 0, 5, 5), diagonal)
    r_leg, _ = _slanted_stroke((2.5, 2), 0.0, (5, 0), 1.0, extend_y=(0, 3))
    letters["R"] = (stem, _box(0, 4, 3.5, 5), _box(0, 2, 3.5, 3), _ring(3.5, 3.5, 0.5, 1.5, _box(3.5, 2, 5, 5)), r_leg)
    letters["S"] = (
        _box(1.5, 4, 5, 5),
        _ring(1.5, 3.5, 0.5, 1.5, _box(0, 2, 1.5, 5)),
        _box(1.5, 2, 3.5, 3),
        _ring(3.5, 1.5, 0.5, 1.5, _box(3.5, 0, 5, 3)),
        _box(0, 0, 3.5, 1),
    )
    v_left, _ = _slanted_stroke((0, 5), 0.0, (2.5, 0), 0.5)
    v_right, _ = _slanted_stroke((5, 5), 1.0, (2.5, 0), 0.5)
    letters["V"] = (v_left, v_right)
    z_diagonal, _ = _slanted_stroke((5, 4), 1.0, (0, 1), 0.0, extend_y=(0, 5))
    letters["Z"] = (_box(0, 4, 5, 5), _box(0, 0, 5, 1), z_diagonal)
    return {name: SloanLetter(name, prims) for name, prims in sorted(letters.items())}


_LETTERS = _build_letters()


def sloan_letter(name: str | SloanLetter) -> SloanLetter:
    """The Sloan letter called ``name`` (case-insensitive), one of C D H K N O R S V Z."""
    if isinstance(name, SloanLetter):
        return name
    key = str(name).strip().upper()
    if key not in _LETTERS:
        raise VissimInputError(f"unknown Sloan letter {name!r}; the ten Sloan letters are {' '.join(SLOAN_LETTERS)}")
    return _LETTERS[key]


# ---------------------------------------------------------------- rasterisation


def _validate_raster(height_px: float, supersample: int) -> tuple[float, int]:
    try:
        height_px = float(height_px)
    except (TypeError, ValueError):
        raise VissimInputError(f"letter height must be a number of pixels, got {height_px!r}") from None
    if not (math.isfinite(height_px) and height_px > 0.0):
        raise VissimInputError(f"letter height must be finite and > 0 px, got {height_px}")
    if int(supersample) != supersample or supersample < 1:
        raise VissimInputError(f"supersample must be a whole number >= 1 (samples per pixel side), got {supersample!r}")
    return height_px, int(supersample)


def _fibonacci_lattice(min_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Points of the Fibonacci lattice in the unit square, at least ``min_points`` of them.

    With F_k points, point i is at ((i + 1/2) / F_k, frac(i F_(k-1) / F_k + 1/(2 F_k))): every
    point has its own row and column offset, so an axis-aligned edge is placed to 1/F_k of a
    pixel (a regular n x n grid places it to 1/n), and slanted edges fare as well.
    """
    a, b = 1, 2
    while b < min_points:
        a, b = b, a + b
    i = np.arange(b)
    return (i + 0.5) / b, ((i * a) % b + 0.5) / b


def letter_coverage_window(
    letter: str | SloanLetter,
    height_px: float,
    shape: tuple[int, int],
    center_rc: tuple[float, float],
    *,
    supersample: int = 16,
) -> tuple[int, int, np.ndarray] | None:
    """Ink coverage of the pixels under the letter's box: ``(row0, col0, coverage)`` or None if off-image.

    ``coverage[i, j]`` belongs to pixel ``(row0 + i, col0 + j)``.  Pixels whose centre lies at
    least half a pixel diagonal from every edge are classified exactly; the others average
    at least ``supersample**2`` point samples on a Fibonacci lattice (`_fibonacci_lattice`).
    """
    glyph = sloan_letter(letter)
    height_px, n = _validate_raster(height_px, supersample)
    rows, cols = int(shape[0]), int(shape[1])
    rc, cc = float(center_rc[0]), float(center_rc[1])
    if not (math.isfinite(rc) and math.isfinite(cc)):
        raise VissimInputError(f"letter centre must be finite (row, col) pixel coordinates, got {center_rc!r}")
    half = height_px / 2.0
    r0, r1 = max(0, math.floor(rc - half)), min(rows, math.ceil(rc + half))
    c0, c1 = max(0, math.floor(cc - half)), min(cols, math.ceil(cc + half))
    if r0 >= r1 or c0 >= c1:
        return None
    units_per_px = DESIGN_UNITS / height_px

    def design(row, col):  # continuous pixel coordinates -> design units (y up)
        return (col - cc) * units_per_px + 2.5, 2.5 - (row - rc) * units_per_px

    row_c = np.arange(r0, r1, dtype=float)[:, None] + 0.5
    col_c = np.arange(c0, c1, dtype=float)[None, :] + 0.5
    margin = glyph.signed_margin(*design(row_c, col_c))
    reach = math.sqrt(0.5) * units_per_px  # half a pixel diagonal, in design units
    coverage = (margin >= reach).astype(float)
    edge_r, edge_c = np.nonzero(np.abs(margin) < reach)
    if edge_r.size:
        dr, dc = _fibonacci_lattice(n * n)
        dr, dc = dr[None, :] - 0.5, dc[None, :] - 0.5
        per_chunk = max(1, _CHUNK_SAMPLES // dr.size)
        for start in range(0, edge_r.size, per_chunk):
            er, ec = edge_r[start:start + per_chunk], edge_c[start:start + per_chunk]
            x, y = design(row_c[er, 0][:, None] + dr, col_c[0, ec][:, None] + dc)
            coverage[er, ec] = np.mean(glyph.inside(x, y), axis=1)
    return r0, c0, coverage


def rasterize_letter(
    letter: str | SloanLetter,
    height_px: float,
    shape: tuple[int, int],
    center_rc: tuple[float, float] | None = None,
    *,
    supersample: int = 16,
) -> np.ndarray:
    """Ink coverage in [0, 1] (float64, ``shape``) of one Sloan letter ``height_px`` pixels tall.

    ``center_rc`` is the letter's centre in continuous pixel coordinates (row, col); the
    default is the image centre ``(H / 2, W / 2)``.  Pixel ``(r, c)`` covers
    ``[r, r+1) x [c, c+1)``, so a 5-px letter centred at (2.5, 2.5) fills a 5 x 5 image.
    Row 0 is the top of the image.
    """
    try:
        rows, cols = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise VissimInputError(f"shape must be (rows, cols) in pixels, got {shape!r}") from None
    if rows < 1 or cols < 1:
        raise VissimInputError(f"shape must be at least 1 x 1 px, got {shape!r}")
    if center_rc is None:
        center_rc = (rows / 2.0, cols / 2.0)
    out = np.zeros((rows, cols), dtype=float)
    window = letter_coverage_window(letter, height_px, (rows, cols), center_rc, supersample=supersample)
    if window is not None:
        r0, c0, cov = window
        out[r0:r0 + cov.shape[0], c0:c0 + cov.shape[1]] = cov
    return out
