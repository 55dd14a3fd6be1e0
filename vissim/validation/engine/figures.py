"""What every report figure shares: grey images at display gamma with a radiance colour bar, an
angular scale bar on image tiles, alt text, and the record a report keeps of each figure.

The charts are emissive in the renders (a chart texture of relative radiance), so grey images
show *relative radiance*, sRGB-encoded for display; their colour bars carry ticks at even steps of
the display scale, labelled with the linear radiance they stand for.
"""

from __future__ import annotations

from typing import NamedTuple

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as pyplot  # noqa: E402
import numpy as np  # noqa: E402

from vissim.imageio import encode_png, srgb_decode, srgb_encode  # noqa: E402

__all__ = ["Figure", "display_norm", "radiance_colorbar", "RADIANCE_LABEL", "DISPLAY_TICKS", "scale_bar",
           "scale_bar_arcmin", "tiles_alt", "png_bytes", "pyplot", "PanelLayout", "panel_grid", "titled_panel_grid",
           "wrapped_lines", "colorbar_beside"]

#: The label of every grey image's colour bar.
RADIANCE_LABEL = "relative radiance, display gamma"
#: Colour-bar ticks at these even steps of the display (sRGB) scale, labelled in linear radiance.
DISPLAY_TICKS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: A scale bar is the longest of these (arcmin) that fits in this fraction of a tile's width.
SCALE_BAR_STEPS_ARCMIN = (1, 2, 5, 10, 20, 50, 100, 200, 500)
SCALE_BAR_FRACTION = 0.4
#: Pixels per inch of every report figure.
FIGURE_DPI = 110
#: Orange reads on both the white paper and a white-on-black letter.
SCALE_BAR_COLOUR = "tab:orange"


class PanelLayout(NamedTuple):
    """A grid of equal panels at fixed places, inches: each panel's size, the margins around the grid (left: y
    labels; right: a colour bar; top: titles; bottom: x labels) and the gaps between panels.

    A fixed layout, not matplotlib's constrained one: that measures every label twice per drawing, which took
    half of a figure's time."""

    panel_width_in: float
    panel_height_in: float
    left_in: float
    right_in: float
    top_in: float
    bottom_in: float
    column_gap_in: float
    row_gap_in: float

    def size_in(self, n_rows: int, n_cols: int) -> tuple[float, float]:
        """The figure's (width, height) for ``n_rows`` x ``n_cols`` panels."""
        return (self.left_in + n_cols * self.panel_width_in + (n_cols - 1) * self.column_gap_in + self.right_in,
                self.top_in + n_rows * self.panel_height_in + (n_rows - 1) * self.row_gap_in + self.bottom_in)


def panel_grid(n_rows: int, n_cols: int, layout: PanelLayout):
    """A figure of ``n_rows`` x ``n_cols`` axes placed by ``layout``: (figure, axes array of shape (n_rows, n_cols))."""
    width, height = layout.size_in(n_rows, n_cols)
    fig = pyplot.figure(figsize=(width, height))
    axes = np.empty((n_rows, n_cols), dtype=object)
    for i in range(n_rows):
        bottom = height - layout.top_in - (i + 1) * layout.panel_height_in - i * layout.row_gap_in
        for j in range(n_cols):
            left = layout.left_in + j * (layout.panel_width_in + layout.column_gap_in)
            axes[i, j] = fig.add_axes((left / width, bottom / height, layout.panel_width_in / width,
                                       layout.panel_height_in / height))
    return fig, axes


#: Titles are wrapped to this share of their width (glyph widths measured unhinted; the drawn text, hinted, may
#: be a little wider), and each line the wrapping adds above the panels takes this many ems of height.
TITLE_WIDTH_SHARE, TITLE_LINE_EM = 0.97, 1.25


#: Points in an inch (typography's unit: font sizes are in points).
POINTS_PER_INCH = 72.0


def wrapped_lines(text: str, width_in: float, fontsize: float) -> list[str]:
    """``text`` wrapped to ``width_in`` at ``fontsize`` (points), its own line breaks (blank lines too) kept: words
    added to a line while the line's measured width fits; a word wider than a line alone is cut where it fills one."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    font, room_pt = FontProperties(size=fontsize), TITLE_WIDTH_SHARE * width_in * POINTS_PER_INCH

    def fits(candidate: str) -> bool:
        return text_to_path.get_text_width_height_descent(candidate, font, ismath=False)[0] <= room_pt

    lines = []
    for part in text.split("\n"):
        line = ""
        for word in part.split():
            longer = f"{line} {word}" if line else word
            if not fits(longer):
                if line:
                    lines.append(line)
                while not fits(word) and len(word) > 1:  # the longest head that fits its own line
                    cut = max(n for n in range(1, len(word)) if n == 1 or fits(word[:n]))
                    lines.append(word[:cut])
                    word = word[cut:]
                longer = word
            line = longer
        lines.append(line)
    return lines


def titled_panel_grid(n_rows: int, n_cols: int, layout: PanelLayout, title: str, fontsize: float,
                      panel_titles: tuple[str, ...] = (), panel_fontsize: float = 8.0,
                      row_titles: tuple[str, ...] = (), row_fontsize: float = 7.0):
    """`panel_grid` under ``title``, wrapped to the figure's width, its first row's panels under ``panel_titles``
    (one a column), each wrapped to its panel and the gap beside it, and each row's first panel labelled on its left
    by ``row_titles`` (one a row), each wrapped to its panel's height: (figure, axes, the layout used).

    ``layout.top_in`` holds the titles as written (their own line breaks) and ``layout.left_in`` the row titles as
    written; each line the wrapping adds to the figure's title or to the longest panel title raises the top margin
    by one line, and each line it adds to the longest row title widens the left margin by one line."""
    width_in, _ = layout.size_in(n_rows, n_cols)
    lines = wrapped_lines(title, width_in, fontsize)
    panels = [wrapped_lines(t, layout.panel_width_in + layout.column_gap_in, panel_fontsize) for t in panel_titles]
    rows = [wrapped_lines(t, layout.panel_height_in, row_fontsize) for t in row_titles]
    layout = layout._replace(
        top_in=layout.top_in + _added_lines([title], [lines]) * TITLE_LINE_EM * fontsize / POINTS_PER_INCH
        + _added_lines(panel_titles, panels) * TITLE_LINE_EM * panel_fontsize / POINTS_PER_INCH,
        left_in=layout.left_in + _added_lines(row_titles, rows) * TITLE_LINE_EM * row_fontsize / POINTS_PER_INCH)
    fig, axes = panel_grid(n_rows, n_cols, layout)
    fig.suptitle("\n".join(lines), fontsize=fontsize)
    for ax, wrapped in zip(axes[0], panels):
        ax.set_title("\n".join(wrapped), fontsize=panel_fontsize)
    for ax, wrapped in zip(axes[:, 0], rows):
        ax.set_ylabel("\n".join(wrapped), fontsize=row_fontsize)
    return fig, axes, layout


def _added_lines(texts, wrapped) -> int:
    """The most lines wrapping added to any of ``texts`` (beyond its own line breaks)."""
    return max((len(w) - (t.count("\n") + 1) for t, w in zip(texts, wrapped)), default=0)


#: A colour bar beside a panel grid: its gap from the grid and its width, inches; its share of the grid's height.
COLORBAR_GAP_IN, COLORBAR_WIDTH_IN, COLORBAR_SHARE = 0.2, 0.15, 0.8
#: The least room (inches) between a title spreading into a gap and the colour bar beyond it.
TITLE_CLEARANCE_IN = 0.05


def colorbar_beside(fig, layout: PanelLayout, n_rows: int, n_cols: int, shown):
    """A colour bar of ``shown`` to the right of a `panel_grid`, centred on its height (in ``layout.right_in``), clear
    of the last panel's title (`titled_panel_grid` lets a title spread half a gap beyond its panel)."""
    width, height = layout.size_in(n_rows, n_cols)
    grid_height = height - layout.top_in - layout.bottom_in
    bar_height = COLORBAR_SHARE * grid_height
    left = width - layout.right_in + max(COLORBAR_GAP_IN, layout.column_gap_in / 2 + TITLE_CLEARANCE_IN)
    bottom = layout.bottom_in + (grid_height - bar_height) / 2
    cax = fig.add_axes((left / width, bottom / height, COLORBAR_WIDTH_IN / width, bar_height / height))
    return fig.colorbar(shown, cax=cax)


class Figure(NamedTuple):
    """A report figure: its file, PNG bytes, alt text (what it shows, for readers who cannot see it), provenance extras."""

    file_name: str
    png: bytes
    alt: str
    extra: dict = {}


def display_norm():
    """Grey images as the eye sees them: linear relative radiance 0-1, sRGB-encoded."""
    from matplotlib.colors import FuncNorm

    return FuncNorm((lambda x: srgb_encode(np.clip(x, 0, 1)), lambda y: srgb_decode(np.clip(y, 0, 1))), vmin=0, vmax=1)


def radiance_colorbar(bar) -> None:
    """Label a grey image's colour bar: relative radiance at display gamma, ticks at even display steps."""
    values = [float(srgb_decode(np.asarray(t))) for t in DISPLAY_TICKS]
    bar.set_ticks(values, labels=[f"{v:.2g}" if 0 < v < 1 else f"{v:g}" for v in values])
    bar.set_label(RADIANCE_LABEL.replace(", ", ",\n"), fontsize=7)


def scale_bar_arcmin(width_px: int, arcmin_per_px: float) -> float:
    """The scale bar's length for a tile ``width_px`` wide: the longest round length within the fraction."""
    room = SCALE_BAR_FRACTION * width_px * arcmin_per_px
    fitting = [s for s in SCALE_BAR_STEPS_ARCMIN if s <= room]
    return float(fitting[-1]) if fitting else room


def scale_bar(ax, width_px: int, arcmin_per_px: float, *, corner: tuple[float, float] | None = None,
              inch_per_px: float = 1.0) -> float:
    """Draw an angular scale bar (arcmin) at the bottom left of an image tile; its length, arcmin.

    The tile is ``ax``'s image, or one of several in ``ax`` whose lower left corner is at ``corner`` (data
    coordinates, ``inch_per_px`` of them a pixel: `vissim.validation.dslr.report`'s rows of tiles).
    """
    from matplotlib.font_manager import FontProperties
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    length = scale_bar_arcmin(width_px, arcmin_per_px)
    label = f"{length:g}′" if length >= 1 else f"{length:.2g}′"
    anchor = {} if corner is None else {"bbox_to_anchor": corner, "bbox_transform": ax.transData}
    bar = AnchoredSizeBar(ax.transData, length / arcmin_per_px * inch_per_px, label, "lower left", pad=0.3,
                          borderpad=0.3, color=SCALE_BAR_COLOUR, frameon=False,
                          size_vertical=max(0.5, width_px / 80) * inch_per_px,
                          fontproperties=FontProperties(size=7, weight="bold"), **anchor)
    ax.add_artist(bar)
    return length


def tiles_alt(what: str, rows: list[str], columns: list[str], extra: str = "") -> str:
    """Alt text of a grid of image tiles: what it shows, its rows, its columns."""
    text = (f"{what}. Rows: {'; '.join(rows)}. Columns, one per configuration: {'; '.join(columns)}.")
    return f"{text} {extra}".strip()


def png_bytes(fig) -> bytes:
    """A figure as RGB PNG bytes (`FIGURE_DPI`, opaque: the figure's white background); the figure is closed."""
    fig.set_dpi(FIGURE_DPI)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    pyplot.close(fig)
    return encode_png(rgba[..., :3])
