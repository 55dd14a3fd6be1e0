"""LogMAR letter charts and single-optotype tiles, rendered in angle or for print.

Layout (ETDRS: Ferris, Kassoff, Bresnick & Bailey 1982, following Bailey & Lovie 1976):
five Sloan letters per row (any number on request), the gap between neighbouring letters
is one letter width, the gap between a row's baseline and the top of the next row is the
height of the letters in that next row, rows are centred on the chart's vertical midline,
and every margin is one letter width of the largest row.  Letter height is
``5 * 10**LogMAR`` arcmin (`vissim.acuity`).

One `ChartSpec` gives two renderings of the same layout:

* `render_chart_angular` -- a pixel grid in visual angle (``arcmin_per_px``), the
  input to a blur simulation; the thesis used 1 arcmin per pixel.
* `render_chart_print` / `save_chart_pdf` / `save_chart_png` -- the chart
  at its physical size for the viewing distance (letter heights from
  `vissim.acuity.letter_height_mm`, thesis Eq. 4.1 generalised).

Pixels are float32 *linear reflectance*: ``paper_reflectance`` where there is no ink and
``ink_reflectance`` under ink, mixed by the ink's area in each pixel.  "black-on-white"
prints letters in ink on bare paper; "white-on-black" swaps them (background in ink).
Print files carry the printer's view instead: the PDF fills ink black on an unprinted page
and the PNG stores bare paper as 1 and full ink as 0.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vissim.acuity import letter_height_arcmin, letter_height_mm, logmar_to_snellen, subtense_arcmin, subtense_mm
from vissim.chart_defaults import DEFAULT_LETTER_SEED, INK_REFLECTANCE, MM_PER_INCH, PAPER_REFLECTANCE, POLARITIES
from vissim.checks import LOGMAR_RANGE, VIEWING_DISTANCE_RANGE_M, number_within, size_text
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import check_allocation, describe, finite_number, instance_of, positive_number
from vissim.errors import VissimInputError, VissimTypeError
from vissim.optotypes import SLOAN_LETTERS, letter_coverage_window, sloan_letter
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_TILE_SHAPE_PX
from vissim.units import mm_to_m

logger = logging.getLogger(__name__)

__all__ = ["DEFAULT_LETTER_SEED", "MM_PER_INCH", "POLARITIES", "Chart", "ChartLayout",
           "ChartRow", "ChartSpec", "LetterBox", "etdrs_chart_spec", "layout_chart", "logmar_steps",
           "optotype_tile", "render_chart_angular", "render_chart_print", "save_chart_pdf", "save_chart_png",
           "single_letter_spec"]

_LETTERS_PER_ROW = 5
_SIDECAR_SCHEMA = "vissim.chart-letters/1"
_BOX_KEYS = ("top", "left", "bottom", "right")


def _number(value: Any, name: str, unit: str, *, positive: bool = False) -> float:
    return positive_number(value, name, unit) if positive else finite_number(value, name, unit)


@dataclasses.dataclass(frozen=True)
class ChartRow:
    """One chart row: its LogMAR and its letters, left to right.

    Parameters
    ----------
    logmar : float
        Letter size, log10 of the minimum angle of resolution in arcmin (1.0 = 20/200, 0.0 = 20/20:
        a letter 5 x 10^logmar arcmin tall at the chart's viewing distance).
    letters : str
        Sloan letters (C D H K N O R S V Z), left to right; spaces are ignored.

    Raises
    ------
    VissimInputError
        A LogMAR that is not a finite number, no letters, or a letter that is not a Sloan letter.

    Examples
    --------
    >>> from vissim.charts import ChartRow
    >>> ChartRow(0.5, "K N Z")
    ChartRow(logmar=0.5, letters='KNZ')
    """

    logmar: float
    letters: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "logmar", number_within(self.logmar, "LogMAR", "LogMAR", LOGMAR_RANGE,
                                                         " (20/2 to 20/2000, beyond any chart)"))
        letters = "".join(sloan_letter(ch).name for ch in str(self.letters) if not ch.isspace())
        if not letters:
            raise VissimInputError(f"a chart row needs at least one letter, got {self.letters!r}")
        object.__setattr__(self, "letters", letters)


@dataclasses.dataclass(frozen=True)
class ChartSpec:
    """What a chart shows and how it is printed; rendering resolution is chosen later.

    Build one with `etdrs_chart_spec` or `single_letter_spec`; render it with
    `render_chart_angular` (pixels of so many arcmin) or `render_chart_print` (its
    physical size at a dpi).

    Parameters
    ----------
    rows : tuple of ChartRow
        The rows, top to bottom (at least one).
    viewing_distance_m : float
        The distance the chart is printed for, metres: each row's letters subtend their LogMAR
        there (default: the thesis's 3 ft, 0.9144 m).
    polarity : {"black-on-white", "white-on-black"}
        Dark letters on paper, or the reverse.
    paper_reflectance : float
        Linear reflectance (a fraction, ink < paper <= 1) of the paper (default 0.9,
        laser-printed paper).
    ink_reflectance : float
        Linear reflectance (a fraction, 0 <= ink < paper) of the ink (default 0.04, toner).
    letter_seed : int, optional
        The seed that chose the letters, when they were chosen at random (recorded, not used).

    Attributes
    ----------
    background_reflectance, letter_reflectance : float
        The reflectance around and inside the letters for the polarity.

    Raises
    ------
    VissimInputError
        No rows, an unknown polarity, a viewing distance outside ``VIEWING_DISTANCE_RANGE_M``
        (0.001-1e6 m) or reflectances out of order.

    Examples
    --------
    >>> import vissim
    >>> spec = vissim.single_letter_spec("K", 1.0, polarity="white-on-black")
    >>> spec.viewing_distance_m, spec.background_reflectance, spec.letter_reflectance
    (0.9144, 0.04, 0.9)
    >>> len(vissim.etdrs_chart_spec().rows)  # LogMAR 1.0 down to -0.3
    14
    """

    rows: tuple[ChartRow, ...]
    viewing_distance_m: float = mm_to_m(THESIS_CHART_DISTANCE_MM)
    polarity: str = "black-on-white"
    paper_reflectance: float = PAPER_REFLECTANCE
    ink_reflectance: float = INK_REFLECTANCE
    letter_seed: int | None = None  # the seed that chose the letters, when they were chosen at random

    def __post_init__(self) -> None:
        rows = tuple(self.rows)
        if not rows or not all(isinstance(r, ChartRow) for r in rows):
            raise VissimInputError(f"a chart needs at least one ChartRow, got {self.rows!r}")
        object.__setattr__(self, "rows", rows)
        distance_m = _number(self.viewing_distance_m, "viewing distance", "m", positive=True)
        if not VIEWING_DISTANCE_RANGE_M[0] <= distance_m <= VIEWING_DISTANCE_RANGE_M[1]:
            raise VissimInputError("viewing distance must be {:g}-{:g} m, got {:g} m".format(*VIEWING_DISTANCE_RANGE_M, distance_m))
        if self.polarity not in POLARITIES:
            raise VissimInputError(f"polarity must be one of {', '.join(POLARITIES)}; got {self.polarity!r}")
        paper = _number(self.paper_reflectance, "paper reflectance", "fraction 0-1")
        ink = _number(self.ink_reflectance, "ink reflectance", "fraction 0-1")
        if not 0.0 <= ink < paper <= 1.0:
            raise VissimInputError(
                f"reflectances must satisfy 0 <= ink < paper <= 1 (fractions), got ink {ink:g}, paper {paper:g}"
            )

    @property
    def background_reflectance(self) -> float:
        return self.paper_reflectance if self.polarity == "black-on-white" else self.ink_reflectance

    @property
    def letter_reflectance(self) -> float:
        return self.ink_reflectance if self.polarity == "black-on-white" else self.paper_reflectance


def logmar_steps(start: float, stop: float, step: float = 0.1) -> tuple[float, ...]:
    """LogMAR values from ``start`` to ``stop`` inclusive in steps of ``step`` (either direction)."""
    start = _number(start, "LogMAR range start", "log10 arcmin")
    stop = _number(stop, "LogMAR range end", "log10 arcmin")
    step = _number(step, "LogMAR step", "log10 arcmin", positive=True)
    count = abs(stop - start) / step
    if abs(count - round(count)) > 1e-6:
        raise VissimInputError(f"LogMAR range {start:g} to {stop:g} is not a whole number of {step:g} steps")
    sign = -1.0 if stop < start else 1.0
    return tuple(round(start + sign * i * step, 10) for i in range(int(round(count)) + 1))


def _row_letters(letters: str | Sequence[str] | None, n_rows: int, seed: int) -> list[str]:
    if letters is None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise VissimInputError(f"the letter seed must be a whole number >= 0, got {seed!r}")
        rng = np.random.default_rng(seed)
        return ["".join(rng.choice(list(SLOAN_LETTERS), _LETTERS_PER_ROW, replace=False)) for _ in range(n_rows)]
    if not isinstance(letters, (str, list, tuple)) or not all(isinstance(g, str) for g in letters):
        raise VissimTypeError(f"letters must be a str such as 'NCKZO' or a list of str, one per row, got {describe(letters)}")
    if isinstance(letters, str):
        groups = letters.replace(",", " ").replace("/", " ").split()
        groups = groups if len(groups) > 1 else groups * n_rows
    else:
        groups = [str(g) for g in letters]
    if len(groups) != n_rows:
        raise VissimInputError(f"got letters for {len(groups)} rows but the chart has {n_rows} rows")
    return groups


def etdrs_chart_spec(
    logmar_range: tuple[float, float] = (1.0, -0.3),
    logmar_step: float = 0.1,
    *,
    letters: str | Sequence[str] | None = None,
    seed: int = DEFAULT_LETTER_SEED,
    **spec_kwargs: Any,
) -> ChartSpec:
    """An ETDRS-style chart, one row per LogMAR step (default 1.0 down to -0.3, as the thesis).

    Parameters
    ----------
    logmar_range : (float, float)
        The first (top) and last (bottom) rows' LogMAR, both included.
    logmar_step : float
        LogMAR between rows (0.1: the ETDRS progression).
    letters : str or sequence of str, optional
        None picks 5 distinct Sloan letters per row with ``numpy.random.default_rng(seed)``;
        a string such as ``"NCKZO"`` is used for every row; rows separated by spaces, commas or
        slashes (``"NCKZO HVORS ..."``) or a sequence give each row its own letters.
    seed : int
        Seed of the random letters.
    **spec_kwargs
        Passed to `ChartSpec` (viewing distance, polarity, reflectances).

    Returns
    -------
    ChartSpec

    Examples
    --------
    >>> import vissim
    >>> spec = vissim.etdrs_chart_spec((1.0, 0.8), letters="NCKZO", viewing_distance_m=6.0)
    >>> [(row.logmar, row.letters) for row in spec.rows]
    [(1.0, 'NCKZO'), (0.9, 'NCKZO'), (0.8, 'NCKZO')]
    """
    if not isinstance(logmar_range, (tuple, list)) or len(logmar_range) != 2:
        raise VissimTypeError(f"logmar_range must be (first, last) LogMAR, e.g. (1.0, -0.3), got {describe(logmar_range)}")
    logmars = logmar_steps(*logmar_range, logmar_step)
    groups = _row_letters(letters, len(logmars), seed)
    rows = tuple(ChartRow(lm, g) for lm, g in zip(logmars, groups))
    return ChartSpec(rows, letter_seed=seed if letters is None else None, **spec_kwargs)


def single_letter_spec(letter: str, logmar: float, **spec_kwargs: Any) -> ChartSpec:
    """A chart of one optotype: one row of one letter, with the usual one-letter margins.

    Parameters
    ----------
    letter : str
        One Sloan letter (C D H K N O R S V Z).
    logmar : float
        Its size, LogMAR (log10 arcmin of the stroke width; the letter is 5 strokes tall).
    **spec_kwargs
        Passed to `ChartSpec` (viewing distance, polarity, reflectances).

    Returns
    -------
    ChartSpec

    Examples
    --------
    >>> import vissim
    >>> vissim.single_letter_spec("Z", 0.5).rows
    (ChartRow(logmar=0.5, letters='Z'),)
    """
    if isinstance(letter, str) and len(letter) != 1:
        raise VissimInputError(f"a single-letter chart takes one Sloan letter ({' '.join(SLOAN_LETTERS)}), got "
                               f"{letter!r}")
    return ChartSpec((ChartRow(logmar, letter),), **spec_kwargs)


# ---------------------------------------------------------------- layout


@dataclasses.dataclass(frozen=True)
class LetterBox:
    """Where one letter is.  Boxes are ``(top, left, bottom, right)`` from the top-left corner.

    ``box_px`` is in the rendered image's pixel coordinates (pixel ``(r, c)`` covers
    ``[r, r+1) x [c, c+1)``); ``box_arcmin`` is the same box in visual angle (image pixels times
    the angular scale of the grid); ``box_mm`` is where the letter sits on the printed chart.
    """

    letter: str
    logmar: float
    row: int
    position: int
    box_px: tuple[float, float, float, float]
    box_arcmin: tuple[float, float, float, float]
    box_mm: tuple[float, float, float, float]

    @property
    def height_px(self) -> float:
        return self.box_px[2] - self.box_px[0]

    @property
    def center_rc(self) -> tuple[float, float]:
        return (0.5 * (self.box_px[0] + self.box_px[2]), 0.5 * (self.box_px[1] + self.box_px[3]))

    def to_dict(self) -> dict[str, Any]:
        return {
            "letter": self.letter,
            "logmar": self.logmar,
            "snellen_20ft": logmar_to_snellen(self.logmar),
            "row": self.row,
            "position": self.position,
            "height_arcmin": letter_height_arcmin(self.logmar),
            **{f"box_{u}": dict(zip(_BOX_KEYS, getattr(self, f"box_{u}"))) for u in ("px", "arcmin", "mm")},
        }


def _etdrs_boxes(heights: Sequence[float], counts: Sequence[int]) -> tuple[list[list[tuple]], tuple[float, float]]:
    """ETDRS boxes (top, left, bottom, right) for rows of letter ``heights``, in the heights' unit."""
    margin = max(heights)
    width = 2.0 * margin + max((2 * n - 1) * h for h, n in zip(heights, counts))
    boxes, top = [], margin
    for i, (h, n) in enumerate(zip(heights, counts)):
        if i:
            top += h  # baseline of the row above to the top of this row: this row's letter height
        left = 0.5 * (width - (2 * n - 1) * h)
        boxes.append([(top, left + 2 * j * h, top + h, left + 2 * j * h + h) for j in range(n)])
        top += h
    return boxes, (top + margin, width)


@dataclasses.dataclass(frozen=True)
class ChartLayout:
    """Every letter box of a chart on one pixel grid, with that grid's scales."""

    letters: tuple[LetterBox, ...]
    shape_px: tuple[int, int]
    arcmin_per_px: float
    mm_per_px: float
    page_size_mm: tuple[float, float]  # (height, width) of the printed chart
    rendering: str  # "angular" or "print"
    dpi: float | None = None


def layout_chart(
    spec: ChartSpec,
    *,
    arcmin_per_px: float | None = None,
    dpi: float | None = None,
    size_px: tuple[int, int] | None = None,
    snap_to_pixels: bool = False,
) -> ChartLayout:
    """Letter boxes of ``spec`` on an angular grid (``arcmin_per_px``) or a print grid (``dpi``).

    ``size_px`` (rows, cols; angular only) fixes the image size and centres the letters in it, ignoring
    the margins; ``snap_to_pixels`` moves each letter's top-left corner to the nearest pixel
    corner (by < 0.5 px) so that letters a whole number of pixels tall have crisp edges.
    """
    instance_of(spec, ChartSpec, "the chart spec", "a ChartSpec (from vissim.etdrs_chart_spec or vissim.single_letter_spec)")
    if (arcmin_per_px is None) == (dpi is None):
        raise VissimInputError("give exactly one of arcmin_per_px (angular grid) or dpi (print grid)")
    counts = [len(r.letters) for r in spec.rows]
    arcmin_boxes, arcmin_size = _etdrs_boxes([letter_height_arcmin(r.logmar) for r in spec.rows], counts)
    mm_boxes, mm_size = _etdrs_boxes([letter_height_mm(r.logmar, spec.viewing_distance_m) for r in spec.rows], counts)
    if dpi is not None:
        dpi = _number(dpi, "print resolution", "dots per inch", positive=True)
        mm_per_px = MM_PER_INCH / dpi
        arcmin_per_px = subtense_arcmin(mm_per_px, spec.viewing_distance_m)
        src_boxes, src_size, px_per_unit = mm_boxes, mm_size, 1.0 / mm_per_px
    else:
        arcmin_per_px = check_arcmin_per_px(arcmin_per_px, "angular pixel size")
        mm_per_px = subtense_mm(arcmin_per_px, spec.viewing_distance_m)
        src_boxes, src_size, px_per_unit = arcmin_boxes, arcmin_size, 1.0 / arcmin_per_px
    offset = (0.0, 0.0)
    if size_px is None:
        extent = [s * px_per_unit for s in src_size]
        if not all(math.isfinite(e) for e in extent):
            step = f"{dpi:g} dpi" if dpi is not None else f"{arcmin_per_px:g} arcmin/px"
            raise VissimInputError(f"a chart at {step} would be an infinitely large image; use a coarser sampling")
        shape = tuple(max(1, math.ceil(e - 1e-9)) for e in extent)
    else:
        if dpi is not None:
            raise VissimInputError("size_px applies to angular charts only; a print chart's size follows its layout")
        shape = tuple(int(s) for s in size_px)
        flat = [b for row in src_boxes for b in row]
        lo = (min(b[0] for b in flat), min(b[1] for b in flat))
        hi = (max(b[2] for b in flat), max(b[3] for b in flat))
        content = [(h - l) * px_per_unit for l, h in zip(lo, hi)]
        if any(c > s + 1e-9 for c, s in zip(content, shape)) or min(shape) < 1:
            raise VissimInputError(
                f"letters {size_text([round(c, 1) for c in content])} do not fit a {size_text(shape)} image"
            )
        offset = tuple(0.5 * (s - c) - l * px_per_unit for s, c, l in zip(shape, content, lo))
    letters = []
    for i, row in enumerate(spec.rows):
        for j, name in enumerate(row.letters):
            t, l, b, r = (v * px_per_unit for v in src_boxes[i][j])
            t, l, b, r = t + offset[0], l + offset[1], b + offset[0], r + offset[1]
            if snap_to_pixels:
                dt, dl = math.floor(t + 0.5) - t, math.floor(l + 0.5) - l
                t, l, b, r = t + dt, l + dl, b + dt, r + dl
            box_px = (t, l, b, r)
            letters.append(LetterBox(
                letter=name, logmar=row.logmar, row=i, position=j, box_px=box_px,
                box_arcmin=arcmin_boxes[i][j] if dpi is not None else tuple(v * arcmin_per_px for v in box_px),
                box_mm=mm_boxes[i][j],
            ))
    return ChartLayout(
        letters=tuple(letters), shape_px=shape, arcmin_per_px=float(arcmin_per_px), mm_per_px=float(mm_per_px),
        page_size_mm=mm_size, rendering="print" if dpi is not None else "angular", dpi=dpi,
    )


# ---------------------------------------------------------------- rendering


@dataclasses.dataclass(frozen=True)
class Chart:
    """A rendered chart: float32 linear-reflectance ``pixels`` (H, W), its layout and its spec."""

    pixels: np.ndarray
    layout: ChartLayout
    spec: ChartSpec

    def __post_init__(self) -> None:
        if not (isinstance(self.pixels, np.ndarray) and self.pixels.dtype == np.float32 and self.pixels.ndim == 2):
            raise VissimInputError(f"Chart.pixels must be a 2-D float32 array, got {getattr(self.pixels, 'dtype', '?')}")
        if self.pixels.shape != tuple(self.layout.shape_px):
            raise VissimInputError(f"Chart.pixels are {size_text(self.pixels.shape)}, its layout {size_text(self.layout.shape_px)}")

    arcmin_per_px = property(lambda self: self.layout.arcmin_per_px)
    mm_per_px = property(lambda self: self.layout.mm_per_px)
    letters = property(lambda self: self.layout.letters)
    viewing_distance_m = property(lambda self: self.spec.viewing_distance_m)
    polarity = property(lambda self: self.spec.polarity)
    paper_reflectance = property(lambda self: self.spec.paper_reflectance)
    ink_reflectance = property(lambda self: self.spec.ink_reflectance)

    def sidecar(self) -> dict[str, Any]:
        """JSON-safe description of every letter box: all a later step needs to crop letters."""
        return chart_sidecar(self.spec, self.layout)


def chart_sidecar(spec: ChartSpec, layout: ChartLayout) -> dict[str, Any]:
    """The sidecar dict of `Chart.sidecar`, from a spec and a layout (no pixels needed)."""
    return {
        "schema": _SIDECAR_SCHEMA,
        "rendering": layout.rendering,
        "shape_px": list(layout.shape_px),
        "arcmin_per_px": layout.arcmin_per_px,
        "mm_per_px": layout.mm_per_px,
        "dpi": layout.dpi,
        "page_size_mm": {"height": layout.page_size_mm[0], "width": layout.page_size_mm[1]},
        "viewing_distance_m": spec.viewing_distance_m,
        "polarity": spec.polarity,
        "paper_reflectance": spec.paper_reflectance,
        "ink_reflectance": spec.ink_reflectance,
        "background_reflectance": spec.background_reflectance,
        "letter_reflectance": spec.letter_reflectance,
        "letter_seed": spec.letter_seed,
        "layout": "ETDRS (Ferris et al. 1982; Bailey & Lovie 1976): letter gap = letter width, "
                  "row gap = next row's letter height, margins = largest letter width",
        "conventions": "boxes are top, left, bottom, right from the top-left corner; pixel (r, c) covers "
                       "[r, r+1) x [c, c+1); row 0 is the top; box_mm is on the printed chart",
        "letters": [box.to_dict() for box in layout.letters],
    }


#: Peak bytes per chart pixel (float64 coverage, its float64 blend, float32 result) and per
#: pixel of the largest letter's window (edge distances of its strokes, float64 temporaries).
_BYTES_PER_CHART_PX = 24
_BYTES_PER_LETTER_PX = 80


def _render(spec: ChartSpec, layout: ChartLayout, supersample: int) -> Chart:
    rows, cols = layout.shape_px
    tallest = max((box.height_px for box in layout.letters), default=0.0)
    letter_px = tallest * tallest
    check_allocation(float(rows) * cols * _BYTES_PER_CHART_PX + letter_px * _BYTES_PER_LETTER_PX,
                     f"a {size_text((rows, cols))} chart ({layout.rendering})")
    coverage = np.zeros(layout.shape_px, dtype=float)
    for box in layout.letters:
        window = letter_coverage_window(box.letter, box.height_px, layout.shape_px, box.center_rc,
                                        supersample=supersample)
        if window is None:
            continue
        r0, c0, cov = window
        view = coverage[r0:r0 + cov.shape[0], c0:c0 + cov.shape[1]]
        np.maximum(view, cov, out=view)
    bg, fg = spec.background_reflectance, spec.letter_reflectance
    pixels = (bg + (fg - bg) * coverage).astype(np.float32)
    logger.debug("rendered %s chart %s px, %d letters", layout.rendering, layout.shape_px, len(layout.letters))
    return Chart(pixels, layout, spec)


def render_chart_angular(
    spec: ChartSpec,
    arcmin_per_px: float = 1.0,
    *,
    size_px: tuple[int, int] | None = None,
    snap_to_pixels: bool = False,
    supersample: int = 16,
) -> Chart:
    """Render ``spec`` on a grid in visual angle (for simulation); see `layout_chart`.

    Parameters
    ----------
    spec : ChartSpec
        From `etdrs_chart_spec` or `single_letter_spec`.
    arcmin_per_px : float
        Angular sampling, arcmin per pixel.
    size_px : (int, int), optional
        Image size (rows, cols); default: just large enough for the chart and its margin.
    snap_to_pixels : bool
        Round letter positions and sizes to whole pixels.
    supersample : int
        Subsamples per pixel side for anti-aliasing.

    Returns
    -------
    Chart
        ``pixels``: float32 (H, W) linear reflectance (dark letters on white by default), row 0
        at the top, columns to the observer's right; ``layout``; ``spec``.

    Examples
    --------
    >>> import vissim
    >>> chart = vissim.render_chart_angular(vissim.single_letter_spec("K", 1.0), arcmin_per_px=1.0)
    >>> chart.pixels.shape, chart.pixels.dtype.name, chart.arcmin_per_px
    ((150, 150), 'float32', 1.0)
    """
    layout = layout_chart(spec, arcmin_per_px=arcmin_per_px, size_px=size_px, snap_to_pixels=snap_to_pixels)
    return _render(spec, layout, supersample)


def render_chart_print(spec: ChartSpec, dpi: float = 360.0, *, supersample: int = 16) -> Chart:
    """Render ``spec`` at its physical size for its viewing distance, ``dpi`` pixels per inch.

    The letters are sized so that each row subtends its LogMAR at ``spec.viewing_distance_m``;
    the page is what a printer should print at ``dpi`` (see `save_chart_pdf` and
    `save_chart_png` for files).

    Parameters
    ----------
    spec : ChartSpec
        What to draw.
    dpi : float
        Pixels per inch of the page (25.4 / dpi mm per pixel).
    supersample : int
        Sub-samples per pixel per axis when rasterising the letters' edges (area coverage).

    Returns
    -------
    Chart
        ``pixels``: float32 linear reflectance of shape (rows, cols), row 0 at the top of the
        page, columns left to right as the observer sees the chart; ``mm_per_px`` and
        ``arcmin_per_px`` (at the viewing distance) give its sampling; ``sidecar()`` the
        letter boxes.

    Examples
    --------
    >>> import vissim
    >>> chart = vissim.render_chart_print(vissim.single_letter_spec("K", 1.0, viewing_distance_m=6.0), dpi=100)
    >>> chart.pixels.shape, chart.pixels.dtype.name, round(chart.mm_per_px, 3)
    ((1031, 1031), 'float32', 0.254)
    """
    return _render(spec, layout_chart(spec, dpi=dpi), supersample)


def optotype_tile(
    letter: str,
    logmar: float,
    *,
    arcmin_per_px: float = 1.0,
    size_px: tuple[int, int] = THESIS_TILE_SHAPE_PX,
    polarity: str = "black-on-white",
    paper_reflectance: float = PAPER_REFLECTANCE,
    ink_reflectance: float = INK_REFLECTANCE,
    viewing_distance_m: float = mm_to_m(THESIS_CHART_DISTANCE_MM),
    snap_to_pixels: bool = True,
    supersample: int = 16,
) -> Chart:
    """One letter centred on a tile: the thesis's 113 x 133 px (1.88 x 2.22 deg) tile at 1 arcmin/px.

    ``size_px`` is (rows, cols).  With ``snap_to_pixels`` the letter's top-left corner sits
    on a pixel corner, so it is centred to within half a pixel.
    """
    spec = single_letter_spec(letter, logmar, viewing_distance_m=viewing_distance_m, polarity=polarity,
                              paper_reflectance=paper_reflectance, ink_reflectance=ink_reflectance)
    return render_chart_angular(spec, arcmin_per_px, size_px=size_px, snap_to_pixels=snap_to_pixels,
                                supersample=supersample)


# ---------------------------------------------------------------- print files


def save_chart_pdf(
    spec: ChartSpec, path: str | os.PathLike[str], overwrite: bool = False, *, provenance: dict | None = None
) -> Path:
    """Write ``spec`` as a vector PDF whose page is the chart's physical size; return the path.

    Ink is filled black on the unprinted (white) page; one compound path per letter from
    `vissim.optotypes.SloanLetter.patches`.  ``provenance`` goes into the PDF's
    Keywords as JSON.  The write is atomic and refuses to replace a file unless ``overwrite``.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from vissim.atomic import atomic_output
    from vissim.provenance import to_json

    layout = layout_chart(spec, dpi=72.0)
    height_mm, width_mm = layout.page_size_mm
    fig = Figure(figsize=(width_mm / MM_PER_INCH, height_mm / MM_PER_INCH), facecolor="white")
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0.0, width_mm)
    ax.set_ylim(0.0, height_mm)
    ax.set_axis_off()
    letter_colour = "black"
    if spec.polarity == "white-on-black":
        ax.add_patch(Rectangle((0.0, 0.0), width_mm, height_mm, facecolor="black", edgecolor="none", linewidth=0))
        letter_colour = "white"
    for box in layout.letters:
        top, left, bottom, _ = box.box_mm
        for patch in sloan_letter(box.letter).patches((left, height_mm - bottom), bottom - top,
                                                      facecolor=letter_colour):
            ax.add_artist(patch)  # add_artist: no autoscaling pass over every vertex
    metadata = {"Title": f"vissim LogMAR chart for {spec.viewing_distance_m:g} m", "Creator": "vissim"}
    if provenance is not None:
        metadata["Keywords"] = to_json(provenance)
    path = Path(path)
    with atomic_output(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="pdf", metadata=metadata)
    logger.info("wrote %s (%.1f x %.1f mm)", path, width_mm, height_mm)
    return path


def save_chart_png(
    spec: ChartSpec,
    path: str | os.PathLike[str],
    *,
    dpi: float = 360.0,
    overwrite: bool = False,
    provenance: dict | None = None,
    supersample: int = 16,
) -> Chart:
    """Write the print raster of ``spec`` at ``dpi`` as an sRGB PNG (or TIFF); return the rendered chart.

    The file holds what the printer should lay down: bare paper is 1 (white), full ink 0
    (black), edge pixels the linear-light mix by ink area.
    """
    from vissim.imageio import write_image

    chart = render_chart_print(spec, dpi, supersample=supersample)
    ink, paper = spec.ink_reflectance, spec.paper_reflectance
    printer = ((chart.pixels - np.float32(ink)) / np.float32(paper - ink)).clip(0.0, 1.0)
    write_image(path, printer, provenance=provenance, overwrite=overwrite, encoding="srgb")
    return chart
