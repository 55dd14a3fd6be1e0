"""Sloan letter geometry and rasterisation (vissim.optotypes)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optotypes import SLOAN_LETTERS, ConvexPolygon, rasterize_letter, sloan_letter

# Design-grid areas from the construction (Sloan 1959; NAS-NRC 1980): O is an annulus of
# radii 2.5 and 1.5; C is O less the part of it with 2 <= y <= 3 right of the centre.
O_AREA = math.pi * (2.5**2 - 1.5**2)


def _half_chord_integral(v: float, r: float) -> float:
    return 0.5 * (v * math.sqrt(r * r - v * v) + r * r * math.asin(v / r))


C_GAP_AREA = (_half_chord_integral(0.5, 2.5) - _half_chord_integral(-0.5, 2.5)) - (
    _half_chord_integral(0.5, 1.5) - _half_chord_integral(-0.5, 1.5)
)
C_AREA = O_AREA - C_GAP_AREA
H_AREA = 2 * 5.0 + 3.0  # two 1 x 5 stems and the 3 x 1 crossbar between them


def raster50(letter: str) -> np.ndarray:
    """The letter 50 px tall filling a 50 x 50 image: 10 px per design unit."""
    return rasterize_letter(letter, 50, (50, 50), (25.0, 25.0))


def pixel_of(x: float, y: float) -> tuple[int, int]:
    """Pixel of design point (x, y) in :func:`raster50` (y up -> row down)."""
    return int((5.0 - y) * 10), int(x * 10)


def test_stroke_is_one_fifth_of_letter_height_on_h():
    cov = raster50("H")
    # Row 10 (y = 3.85) crosses only the two stems; column 25 (x = 2.55) only the crossbar.
    assert cov[10, :25].sum() == pytest.approx(10.0, rel=0.02)
    assert cov[10, 25:].sum() == pytest.approx(10.0, rel=0.02)
    assert cov[:, 25].sum() == pytest.approx(10.0, rel=0.02)
    # Off the pixel grid the same widths, spread over more pixels.
    shifted = rasterize_letter("H", 50, (60, 60), (30.37, 29.61))
    assert shifted[15, :30].sum() == pytest.approx(10.0, rel=0.02)
    assert shifted[:, 30].sum() == pytest.approx(10.0, rel=0.02)


def test_round_strokes_are_one_fifth_of_letter_height():
    cov = raster50("O")
    # Row 24 (y = 2.55) cuts the ring twice, nearly radially.
    assert cov[24, :25].sum() == pytest.approx(10.0, rel=0.02)
    assert cov[24, 25:].sum() == pytest.approx(10.0, rel=0.02)


def test_n_diagonal_has_the_horizontal_width_of_a_unit_perpendicular_stroke():
    # The diagonal runs from (0, 5) to (5, 0) outer corners: horizontal width h solves
    # h * 5 / sqrt((5 - h)^2 + 25) = 1, i.e. h = 1.25 units = 12.5 px at 50 px.
    cov = raster50("N")
    assert cov[24].sum() - 20.0 == pytest.approx(12.5, rel=0.02)


def _parallel_edge_gaps(poly: ConvexPolygon) -> list[float]:
    v = np.asarray(poly.vertices)
    edges = [(p, q - p) for p, q in zip(v, np.roll(v, -1, axis=0))]
    slanted = [(p, d / np.hypot(*d)) for p, d in edges if abs(d[0]) > 1e-9 and abs(d[1]) > 1e-9]
    gaps = []
    for i, (p, d) in enumerate(slanted):
        for q, e in slanted[i + 1:]:
            if abs(d[0] * e[1] - d[1] * e[0]) < 1e-9:  # parallel: distance between the lines
                gaps.append(abs(d[0] * (q - p)[1] - d[1] * (q - p)[0]))
    return gaps


@pytest.mark.parametrize("name", ["K", "N", "R", "V", "Z"])
def test_slanted_strokes_are_one_unit_wide_perpendicular(name):
    gaps = [g for prim in sloan_letter(name).primitives if isinstance(prim, ConvexPolygon)
            for g in _parallel_edge_gaps(prim)]
    assert gaps, f"{name} has no slanted stroke"
    assert gaps == pytest.approx([1.0] * len(gaps), abs=1e-9)


def test_every_letter_fills_its_5_by_5_box():
    for name in SLOAN_LETTERS:
        cov = raster50(name)
        rows, cols = np.nonzero(cov > 0.5)
        right = 45 if name == "C" else 49  # the C's gap is where the ring would reach x = 5
        assert (rows.min(), rows.max(), cols.min(), cols.max() >= right) == (0, 49, 0, True), name


@pytest.mark.parametrize(("name", "area"), [("O", O_AREA), ("C", C_AREA), ("H", H_AREA)])
def test_ink_area_matches_analytic_area(name, area):
    for height_px, center in ((50, (25.0, 25.0)), (37.3, (30.2, 29.9))):
        cov = rasterize_letter(name, height_px, (60, 60), center)
        assert cov.sum() / height_px**2 == pytest.approx(area / 25.0, rel=0.005)


@settings(max_examples=30, deadline=None)
@given(
    st.sampled_from(SLOAN_LETTERS),
    st.floats(min_value=10.0, max_value=60.0),
    st.floats(min_value=0.0, max_value=1.0),
    st.floats(min_value=0.0, max_value=1.0),
)
def test_subpixel_shifts_conserve_ink(name, height_px, d_row, d_col):
    base = rasterize_letter(name, height_px, (70, 70), (35.0, 35.0)).sum()
    shifted = rasterize_letter(name, height_px, (70, 70), (35.0 + d_row, 35.0 + d_col)).sum()
    assert shifted == pytest.approx(base, rel=0.005)


def test_pixel_grid_convention():
    # A 5-px letter centred at (2.5, 2.5) fills a 5 x 5 image, one pixel per design unit.
    cov = rasterize_letter("H", 5, (5, 5), (2.5, 2.5))
    np.testing.assert_allclose(cov[0], [1, 0, 0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(cov[2], [1, 1, 1, 1, 1], atol=1e-12)
    # Default centre is the image centre; coverage lies in [0, 1].
    np.testing.assert_array_equal(rasterize_letter("H", 5, (5, 5)), cov)
    assert 0.0 <= rasterize_letter("O", 13.7, (20, 20)).min() <= rasterize_letter("O", 13.7, (20, 20)).max() <= 1.0


# Orientation pins: design points (x right, y up) that are ink / paper.  A mirrored or
# upside-down letter fails at least one of them.
ORIENTATION = {
    "C": ([(0.5, 2.5), (4.5, 3.5), (4.5, 1.5)], [(4.5, 2.5)]),  # gap on the right
    "D": ([(0.5, 4.5), (0.5, 0.5), (4.5, 2.5)], [(4.5, 4.7), (4.5, 0.3)]),  # square corners on the left
    "K": ([(0.5, 2.5), (4.0, 4.5), (4.5, 0.2)], [(4.5, 2.5), (2.5, 4.5)]),  # stem left, arms right
    "N": ([(1.5, 4.0), (3.5, 1.0)], [(3.5, 4.0), (1.5, 1.0)]),  # diagonal from top-left to bottom-right
    "R": ([(0.5, 0.5), (4.5, 3.5), (4.5, 0.2)], [(4.5, 1.5), (1.5, 0.5)]),  # bowl top-right, leg bottom-right
    "S": ([(0.5, 3.5), (4.5, 1.5), (4.5, 4.5), (0.5, 0.5)], [(4.5, 3.5), (0.5, 1.5)]),  # upper bowl on the left
    "Z": ([(0.5, 4.5), (3.8, 3.5), (1.2, 1.5)], [(1.2, 3.5), (3.8, 1.5)]),  # diagonal top-right to bottom-left
    "V": ([(0.5, 4.5), (4.5, 4.5), (2.5, 0.2)], [(2.5, 4.5), (0.3, 0.3)]),  # point at the bottom
}


@pytest.mark.parametrize("name", sorted(ORIENTATION))
def test_letters_are_not_mirrored(name):
    ink, paper = ORIENTATION[name]
    letter = sloan_letter(name)
    cov = raster50(name)
    for x, y in ink:
        assert letter.inside(x, y) and cov[pixel_of(x, y)] > 0.99, (name, x, y)
    for x, y in paper:
        assert not letter.inside(x, y) and cov[pixel_of(x, y)] < 0.01, (name, x, y)


def test_c_gap_is_on_the_image_right():
    cov = raster50("C")
    assert cov[20:30, 45:].max() < 0.01  # right middle: the gap
    assert cov[20:30, 2:8].min() > 0.99  # left middle: ink
    assert cov[0:5, 0:50].sum() > 0  # design y up -> row 0 is the top of the letter


def test_vector_patches_draw_the_same_letter_as_the_raster():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    for name in SLOAN_LETTERS:
        fig = Figure(figsize=(1, 1), dpi=100)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.set_xlim(0, 5)
        ax.set_ylim(0, 5)
        ax.set_axis_off()
        for patch in sloan_letter(name).patches((0.0, 0.0), 5.0):
            ax.add_patch(patch)
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        drawn = 1.0 - np.asarray(canvas.buffer_rgba())[..., 0] / 255.0
        assert np.abs(drawn - rasterize_letter(name, 100, (100, 100))).mean() < 0.01, name


def test_unknown_letter_names_it_and_lists_the_ten():
    with pytest.raises(VissimInputError, match=r"'E'.*C D H K N O R S V Z"):
        sloan_letter("E")
    assert sloan_letter("n").name == "N"


@pytest.mark.parametrize("height_px", [0.0, -3.0, math.nan, math.inf])
def test_bad_letter_height_raises(height_px):
    with pytest.raises(VissimInputError, match="px"):
        rasterize_letter("O", height_px, (10, 10))
