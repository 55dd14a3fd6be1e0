"""The DSLR bench's report: metric rows, thesis-style tables and Fig. 4.8-style figures.

Rows and tables read the items' ``result.json`` numbers; the figures read their images.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.progress import counter
from vissim.validation.dslr.fit_report import fit_table
from vissim.validation.dslr.schema import lens_label_of
from vissim.validation.dslr.optics_figures import OPTICS_FIGURES, optics_cases, optics_figure
from vissim.validation.dslr.report_words import arcmin_per_px_of, column_title, group_of
from vissim.validation.dslr.wave_bench import TRACED_RAYS, WAVE_BENCH, WAVE_BENCH_NOTE
from vissim.validation.dslr.wave_bench_report import (SELF_CHECK_MARGIN_DB, is_wave_bench_row, self_check_table,
                                                      wave_bench_tables)
from vissim.validation.engine.helper_process import draw_figures
from vissim.validation.engine.figures import (Figure, PanelLayout, display_norm, panel_grid, png_bytes, pyplot,
                                              radiance_colorbar, scale_bar, tiles_alt)
from vissim.validation.engine.protocol import ReportParts
from vissim.validation.engine.metrics import (MEAN_ABS_DIFF, PSNR, SSIM, added_metrics, floor_column,
                                              metric_float)
from vissim.validation.engine.report import format_number
from vissim.validation.engine.reading import ONE_GREY_LEVEL_PSNR_DB, PERFECT_MARGIN_DB, how_to_read
from vissim.validation.engine.summary import NO_LENS, margin, summary_table, value_span

__all__ = ["metrics_rows", "markdown_tables", "reference_note", "dslr_report", "summary_lines", "REFERENCE_NOTE", "ORDER"]

log = logging.getLogger(__name__)

_fmt = format_number


REFERENCE_NOTE = {
    "wave": "render + bench diffraction",
    "thesis": "render + bench diffraction",
    "thesis_power": "render (no diffraction)",
    "thesis_pupil": "render (no diffraction)",
    "no_magnification": "render (no diffraction)",
    "geometric": "render (no diffraction)",
    TRACED_RAYS: "render (no diffraction)",
}


ORDER = ["wave", "geometric", "thesis", "thesis_power", "thesis_pupil", "no_magnification", TRACED_RAYS]


FIGURE_COLUMNS = 8


#: Simulations whose results on the synthetic chart get a figure of their own (besides the wave bench's).
SYNTHETIC_FIGURES = ("wave", "geometric", "thesis")


def metrics_rows(results: list[dict]) -> list[dict]:
    """One flat row per (configuration, simulation, input)."""
    rows = []
    for result in results:
        config = result["configuration"]
        for comp in result["comparisons"]:
            # no floor: a capture without a repeat, or the noise-free wave bench
            floor = result["noise_floor"].get(comp["reference_kind"]) or {m.name: float("nan") for m in (SSIM, PSNR)}
            rows.append(
                {
                    "configuration": config["name"],
                    "group": group_of(config),
                    "letter": config["letter"],
                    "logmar": config["logmar"],
                    "polarity": config["polarity"],
                    "lenses": lens_label_of(result),
                    "simulation": comp["simulation"],
                    "input": comp["input"],
                    "reference": reference_note(comp),
                    **{m.name: metric_float(comp["metrics"][m.name]) for m in (SSIM, PSNR, MEAN_ABS_DIFF)},
                    **{floor_column(m): metric_float(floor[m.name]) for m in (SSIM, PSNR)},
                    **{m.name: metric_float(comp["metrics"].get(m.name)) for m in added_metrics()},
                    "shift_rows_px": comp["registration"]["shift_rows_px"],
                    "shift_cols_px": comp["registration"]["shift_cols_px"],
                    "camera_prescription": comp["setup"]["camera_prescription"],
                    "pupil_diameter_mm": comp["setup"]["pupil_diameter_mm"],
                    "key": result["key"],
                }
            )
    return rows


def reference_note(comparison: dict) -> str:
    """What a comparison's simulation was compared with, in words (the ``reference`` column)."""
    if comparison.get("reference_kind") == WAVE_BENCH:
        return WAVE_BENCH_NOTE
    return REFERENCE_NOTE[comparison["simulation"]]


def markdown_tables(results: list[dict], all_rows: list[dict] | None = None) -> str:
    """Thesis-style tables (one row per configuration), PSNR and SSIM, with noise floors; then the wave bench's."""
    all_rows = metrics_rows(results) if all_rows is None else all_rows
    if not all_rows:
        return "No finished items.\n"
    rows = [r for r in all_rows if not is_wave_bench_row(r)]
    columns = sorted({(r["simulation"], r["input"]) for r in rows}, key=lambda c: (ORDER.index(c[0]), c[1]))
    by_config: dict[str, dict] = {}
    for r in rows:
        by_config.setdefault(r["configuration"], {"_floor": {}, "_rx": "—"})[(r["simulation"], r["input"])] = r
        if r["simulation"] in ("wave", "geometric"):  # the bench's own optics (thesis mode has its own Rx)
            by_config[r["configuration"]]["_rx"] = r["camera_prescription"]
        by_config[r["configuration"]]["_floor"][REFERENCE_NOTE[r["simulation"]]] = r
    out = [summary_table(rows, [c for c in columns if c[0] != TRACED_RAYS], column_words)]
    self_check = self_check_table(rows)
    if self_check:
        out.append(self_check)
    out.append(_scores_table(by_config, columns))
    wave_bench = wave_bench_tables(results, all_rows)
    if wave_bench:
        out.append(wave_bench)
    fits = fit_table(results)
    if fits:
        out.append(fits)
    return "\n".join(out)


#: The columns of the per-configuration table (simulation, input): vissim's own simulations (the verdict's); the rest
#: (the thesis method and its one-error variants, SSIM, the absolute PSNRs) are in metrics.csv and the summary's
#: medians.  Four, so that the table fits a page 800 px wide.
SCORE_COLUMNS = (("wave", "render"), ("wave", "synthetic"), ("geometric", "render"), ("geometric", "synthetic"))


def column_words(column: tuple[str, str]) -> str:
    """A (simulation, input) column in words: ``wave optics on the no-lens render``."""
    simulation, input_kind = column
    return f"{SIMULATION_WORDS.get(simulation, simulation)} {INPUT_WORDS.get(input_kind, input_kind)}"


#: The per-configuration table's short column names (its paragraph says them in full).
SHORT_WORDS = {"wave": "wave", "geometric": "ray", "thesis": "thesis", "render": "render", "synthetic": "chart"}


def _short_words(column: tuple[str, str]) -> str:
    """A (simulation, input) column in two words: ``wave, render``; ``ray, chart``."""
    return f"{SHORT_WORDS.get(column[0], column[0])}, {SHORT_WORDS.get(column[1], column[1])}"


def _render_floor(cells: dict) -> float:
    """A configuration's render noise floor (PSNR, dB): the two renders as they are (else the first row's floor)."""
    row = cells["_floor"].get(REFERENCE_NOTE["geometric"])
    if row is None:
        row = next(v for k, v in cells.items() if isinstance(k, tuple))
    return row[floor_column(PSNR)]


def _scores_table(by_config: dict, columns: list[tuple[str, str]]) -> str:
    """One row per configuration with a lens: the trial lens, the camera's Rx, the noise floor and the main
    simulations' dB over the floor; the configurations without a lens apart, by PSNR against one grey level."""
    shown = [c for c in SCORE_COLUMNS if c in columns]
    header = ["configuration", "trial lens(es) → camera Rx", "floor (dB)"] + [_short_words(c) for c in shown]
    out = ["### Scores per configuration (dB over the noise floor)\n",
           ("The main simulations of each configuration with a lens, scored as in How to read this page: "
            f"+{PERFECT_MARGIN_DB:.2f} dB a perfect simulation, 0 dB as close as a second render. The trial lens is "
            "the power in the holder in front of the camera; the camera Rx is the prescription the camera then has "
            "(the correcting lens at its pupil), which the simulations blur with; floor: the render's noise floor (PSNR). Wave optics and the thesis method "
            "are scored against the render blurred by the bench aperture's diffraction (the render has none), "
            "with that reference's own noise floor; ray optics against the render as it is. Columns: wave = wave optics, ray = ray optics; render = applied "
            "to the bench's no-lens render (as the thesis did), chart = applied to the chart drawn by vissim. Every "
            "other column (the thesis method and its one-error variants, SSIM, PSNR itself) is in "
            "metrics.csv; the summary above gives their medians.\n"),
           "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    bare = []
    for name, cells in by_config.items():
        first = [cells[c] for c in columns if c in cells][0]
        if first["lenses"] == NO_LENS:
            bare.append((name, cells))
            continue
        floor = _render_floor(cells)
        values = [f"{margin(cells[c]):+.2f}" if c in cells and math.isfinite(margin(cells[c])) else "—" for c in shown]
        out.append("| " + " | ".join([name, f"{first['lenses']} → {cells['_rx']}", _fmt(floor, 1)] + values) + " |")
    out.append("")
    if bare:
        out += ["### Configurations without a lens\n",
                ("With no lens there is no blur to simulate: the render is a sharp letter, and its two renders differ "
                 "only in a few edge pixels, so its noise floor is very high (PSNR "
                 f"{value_span([_render_floor(c) for _, c in bare], '.0f')} dB) and a "
                 "score over it measures the rasterisation of the letter, not optics (a fine simulation would read "
                 "-10 dB or less). These configurations are therefore judged by PSNR alone: a simulation passes if its "
                 f"RMS difference from the render is below one grey level of an 8-bit display (PSNR >= "
                 f"{ONE_GREY_LEVEL_PSNR_DB:.1f} dB), a difference no display shows: identical to the render within "
                 "what can be seen. PSNR in dB:\n"),
                "| configuration | " + " | ".join(_short_words(c) for c in shown) + " | all within one grey level |",
                "|---|" + "---|" * (len(shown) + 1)]
        for name, cells in bare:
            judged = [cells[c][PSNR.name] for c in shown if c in cells and c[0] in LIBRARY_SIMULATIONS]
            verdict = "yes" if judged and min(judged) >= ONE_GREY_LEVEL_PSNR_DB else "no"
            out.append(f"| {name} | " + " | ".join(_fmt(cells[c][PSNR.name], 1) if c in cells else "—" for c in shown)
                       + f" | {verdict} (wave and ray optics) |")
        out.append("")
    return "\n".join(out) + "\n"


def _load(result: dict, run_dir: Path, name: str) -> np.ndarray | None:
    rel = result["images"].get(name)
    if not rel:
        return None
    return read_image(run_dir / rel).pixels


#: 1 - SSIM is shown on a log scale over this range (the SSIM of a good simulation is 0.99+).
DISSIMILARITY_RANGE = (1e-4, 1.0)


def _columns(results: list[dict], simulation: str, input_kind: str, wave_bench: bool) -> list[tuple[dict, dict]]:
    columns = []
    for result in results:
        comp = next((c for c in result["comparisons"] if c["simulation"] == simulation and c["input"] == input_kind
                     and (c.get("reference_kind") == WAVE_BENCH) == wave_bench), None)
        if comp is not None:
            columns.append((result, comp))
    return columns[:FIGURE_COLUMNS]


#: The tile figures' fixed layout, inches: margins (left: the row labels; right: the colour bars; top: the title and
#: the column headings; bottom: the scores) and the gaps between tiles.  A fixed layout, not matplotlib's
#: constrained one, which took over half of the report's time.
GRID_LEFT_IN, GRID_RIGHT_IN, GRID_TOP_IN, GRID_BOTTOM_IN, GRID_GAP_IN = 0.35, 1.45, 0.95, 0.45, 0.08
#: Points between a tile and its heading above, its scores below, its row's label to the left (matplotlib's
#: title pad and label pad).
TITLE_PAD_PT, LABEL_PAD_PT = 6.0, 4.0


class _TileRows:
    """A figure of ``n_rows`` x ``n_cols`` image tiles (1.9 in a column), one axes a row and a colour bar a row.

    A row's tiles are images in one axes whose data coordinates are inches (an axes a tile made a figure 24
    axes, which cost more to draw than the images); each tile is centred in its cell at its own aspect and
    framed, as an axes of its own would show it.
    """

    def __init__(self, n_rows: int, n_cols: int):
        self.width, height = 1.9 * n_cols + 1.8, 9.2
        self.cell_w = (self.width - GRID_LEFT_IN - GRID_RIGHT_IN - GRID_GAP_IN * (n_cols - 1)) / n_cols
        self.cell_h = (height - GRID_TOP_IN - GRID_BOTTOM_IN - GRID_GAP_IN * (n_rows - 1)) / n_rows
        row_w = self.width - GRID_LEFT_IN - GRID_RIGHT_IN
        layout = PanelLayout(row_w, self.cell_h, left_in=GRID_LEFT_IN, right_in=GRID_RIGHT_IN, top_in=GRID_TOP_IN,
                             bottom_in=GRID_BOTTOM_IN, column_gap_in=0.0, row_gap_in=GRID_GAP_IN)
        self.fig, axes = panel_grid(n_rows, 1, layout)  # a row's tiles in one axes
        self.rows, self.bars = list(axes[:, 0]), []
        for ax in self.rows:
            ax.set_axis_off()
            ax.set_xlim(0.0, row_w)
            ax.set_ylim(0.0, self.cell_h)
            bottom = ax.get_position().y0 * height  # a colour bar a row, 0.84 of its height, beside it
            self.bars.append(self.fig.add_axes(((self.width - GRID_RIGHT_IN + 0.15) / self.width,
                                                (bottom + 0.08 * self.cell_h) / height, 0.13 / self.width,
                                                0.84 * self.cell_h / height)))

    def show(self, i: int, j: int, image: np.ndarray, **imshow) -> tuple:
        """Tile (i, j): ``image`` drawn and framed; the image artist and its box (x0, y0, width, height, inches)."""
        from matplotlib.patches import Rectangle

        rows, cols = image.shape[:2]
        inch_per_px = min(self.cell_w / cols, self.cell_h / rows)
        w, h = cols * inch_per_px, rows * inch_per_px
        x0, y0 = j * (self.cell_w + GRID_GAP_IN) + (self.cell_w - w) / 2, (self.cell_h - h) / 2
        ax = self.rows[i]
        shown = ax.imshow(image, extent=(x0, x0 + w, y0, y0 + h), aspect="auto", **imshow)
        ax.add_patch(Rectangle((x0, y0), w, h, fill=False, edgecolor="black", clip_on=False, zorder=2.5,
                               linewidth=pyplot.rcParams["axes.linewidth"]))  # as an axes' spines
        return shown, (x0, y0, w, h, inch_per_px)

    def text_by(self, i: int, box: tuple, where: str, text: str, fontsize: float) -> None:
        """``text`` above (``"top"``), below (``"bottom"``) or left of (``"left"``) a tile, as an axes' title, x label
        or y label would stand."""
        from matplotlib.transforms import offset_copy

        x0, y0, w, h = box[:4]
        ax = self.rows[i]
        if where == "left":
            shifted = offset_copy(ax.transData, fig=self.fig, x=-LABEL_PAD_PT, units="points")
            ax.text(x0, y0 + h / 2, text, transform=shifted, rotation=90, ha="right", va="center", fontsize=fontsize)
            return
        up = TITLE_PAD_PT if where == "top" else -LABEL_PAD_PT
        shifted = offset_copy(ax.transData, fig=self.fig, y=up, units="points")
        ax.text(x0 + w / 2, y0 + h if where == "top" else y0, text, transform=shifted, ha="center",
                va="bottom" if where == "top" else "top", fontsize=fontsize, multialignment="center")


def _figure(results: list[dict], run_dir: Path, simulation: str, input_kind: str,
            wave_bench: bool = False, campaign: dict | None = None) -> Figure | None:
    """Fig. 4.8-style: rows ground truth, simulation, 1 - SSIM map, AD map; a column per configuration.

    ``wave_bench``: the comparisons against the wave bench, else those against the render.
    """
    from matplotlib.colors import LogNorm, Normalize

    columns = _columns(results, simulation, input_kind, wave_bench)
    if not columns:
        return None
    ad_maps = [read_image(run_dir / c["images"]["abs_diff_map"]).pixels for _, c in columns]
    highest = max(float(np.percentile(ad, 99.9)) for ad in ad_maps)
    ad_max = max(1e-4 if wave_bench else 0.01, highest)  # the wave bench's differences are 100x smaller
    lo, hi = DISSIMILARITY_RANGE
    truth_label = "wave bench (truth)" if wave_bench else "bench (truth)"
    rows = [(truth_label, "gray", display_norm(), None),
            (SIMULATION_WORDS.get(simulation, simulation), "gray", display_norm(), None),
            ("1 − SSIM (log)", "viridis", LogNorm(lo, hi), "1 − SSIM"),
            ("|difference|", "magma", Normalize(0, ad_max), "|difference| (relative radiance, linear)")]
    grid = _TileRows(len(rows), len(columns))
    shown, first = [None] * len(rows), [None] * len(rows)
    bar_arcmin = None
    for j, (result, comp) in enumerate(columns):
        truth = _load(result, run_dir, comp["reference_image"])
        sim = read_image(run_dir / comp["images"]["simulation"]).pixels
        ssim_map = read_image(run_dir / comp["images"]["ssim_map"]).pixels
        images = [truth, sim, np.clip(1.0 - ssim_map, lo, hi), ad_maps[j]]
        boxes = []
        for i, (img, (_, cmap, norm, _)) in enumerate(zip(images, rows)):
            shown[i], box = grid.show(i, j, img, cmap=cmap, norm=norm, interpolation="nearest")
            first[i] = first[i] or box
            boxes.append(box)
        step = arcmin_per_px_of(result, campaign)
        if step is not None:
            bar_arcmin = scale_bar(grid.rows[0], truth.shape[1], step, corner=boxes[0][:2], inch_per_px=boxes[0][4])
        grid.text_by(0, boxes[0], "top", column_title(result, comp), 7)
        grid.text_by(len(rows) - 1, boxes[-1], "bottom", f"SSIM {comp['metrics'][SSIM.name]:.3f}\nPSNR "
                     f"{_fmt(metric_float(comp['metrics'][PSNR.name]), 1)} dB", 8)
    for i, (label, _, _, bar_label) in enumerate(rows):
        grid.text_by(i, first[i], "left", label, 9)
        bar = grid.fig.colorbar(shown[i], cax=grid.bars[i])
        bar.ax.tick_params(labelsize=7)
        if bar_label is None:
            radiance_colorbar(bar)
        else:
            bar.set_label(bar_label, fontsize=8)
    scale = f"; scale bars {bar_arcmin:g} arcmin" if bar_arcmin else ""
    grid.fig.suptitle(f"{column_words((simulation, input_kind))}, against {reference_note(columns[0][1])}"
                      f"{scale}", fontsize=10)
    alt = tiles_alt(f"{column_words((simulation, input_kind))}, against {reference_note(columns[0][1])}, "
                    "as letter tiles with an angular scale bar",
                    [truth_label, SIMULATION_WORDS.get(simulation, simulation), "1 − SSIM map on a log scale",
                     "absolute difference map"],
                    [f"{r['configuration']['name']}: SSIM {c['metrics'][SSIM.name]:.3f}, "
                     f"PSNR {_fmt(metric_float(c['metrics'][PSNR.name]), 1)} dB" for r, c in columns])
    return Figure("", png_bytes(grid.fig), alt)


_SKIPPED = (KeyError, OSError, ValueError, VissimInputError)  # what a run folder's records can hold against a figure


def _optics_figure(cases: list, name: str) -> Figure | str | None:
    """One optics figure (`vissim.validation.dslr.optics_figures.optics_figure`), None, or why it was skipped; the rest
    of the report does not depend on it."""
    try:
        drawn = optics_figure(cases, name, display_norm)
    except _SKIPPED as error:
        return f"report: the optics figure {name!r} was skipped ({type(error).__name__}: {error})"
    if drawn is None:
        return None
    file_name, fig, extra, alt = drawn
    return Figure(file_name, png_bytes(fig), alt, extra)


def _cases_or_none(results: list[dict], run_dir: Path, record: dict) -> list:
    """The optics figures' cases (read once, here), or none, the reason logged."""
    try:
        return optics_cases(results, run_dir, record)
    except _SKIPPED as error:
        log.warning("report: the optics figures were skipped (%s: %s)", type(error).__name__, error)
        return []


def dslr_report(results: list[dict], run_dir: Path, record: dict, progress=None) -> ReportParts:
    """The DSLR report's rows, tables and figures.

    The figures: Fig. 4.8-style panels per simulation on the no-lens render and, for the main
    simulations, on the synthetic chart; and per group the wave PSF (log scale), its MTF against the
    diffraction limit and a through-focus strip (`vissim.validation.dslr.optics_figures`).
    ``progress(stage, done, total)`` after each figure (`vissim.progress`).
    """
    figures = {}
    wanted = [(s, "render", False, column_words((s, "render")), f"figure_{s}.png") for s in ORDER]
    wanted += [(s, "synthetic", False, column_words((s, "synthetic")), f"figure_{s}_synthetic.png")
               for s in SYNTHETIC_FIGURES]
    wanted.append(("wave", "synthetic", True, f"{column_words(('wave', 'synthetic'))}, against the wave bench",
                   f"figure_wave_{WAVE_BENCH}.png"))
    advance = counter(progress, "figures", len(wanted) + len(OPTICS_FIGURES))
    cases = _cases_or_none(results, run_dir, record)
    order = list(reversed(OPTICS_FIGURES))  # the slowest first: the through-focus strip
    optics = [(_optics_figure, (cases, name)) for name in order]
    tiles = [(_figure, (results, run_dir, simulation, input_kind, wave_bench, record))
             for simulation, input_kind, wave_bench, _, _ in wanted]
    drawn = draw_figures(optics + tiles, advance)
    for (_, _, _, name, file_name), figure in zip(wanted, drawn[len(optics):]):
        if figure is not None:
            figures[name] = figure._replace(file_name=file_name)
    optics_drawn = dict(zip(order, drawn[:len(optics)]))
    for message in (figure for figure in optics_drawn.values() if isinstance(figure, str)):
        log.warning("%s", message)
    figures.update({name: optics_drawn[name] for name in OPTICS_FIGURES if isinstance(optics_drawn[name], Figure)})
    title = f"vissim validation: {record.get('name', run_dir.name)}"
    rows = metrics_rows(results)
    body = markdown_tables(results, rows)
    scores = ("**Reading a score.** The noise floor's two renders each hold the Monte-Carlo noise σ², so their squared "
              "difference is 2σ². A simulation is compared with one render: a perfect, noise-free one differs by σ² "
              f"and scores 10·log10(2) = +{PERFECT_MARGIN_DB:.2f} dB over the floor, on average. A simulation with an "
              "error e² of its own scores 10·log10(2σ² / (σ² + e²)): 0 dB when e² = σ², below 0 dB when its error "
              "exceeds the render's noise. Wave optics is scored against the render blurred by the aperture's "
              "diffraction, with the floor of two such blurred renders, so +3 dB is its perfect score too. A "
              "configuration without a lens has nothing to blur and is judged by PSNR instead (Configurations without "
              "a lens).\n")
    shown = " ".join(f"{name} {figure.alt}" for name, figure in figures.items())  # the engine appends them
    return ReportParts(title, rows, how_to_read(body + shown, scores) + body, figures)


#: vissim's own simulations of the bench: the verdict's subject.  ``thesis`` and its one-error variants reproduce the
#: thesis's method with its errors (docs/ERRATA.md), so they are reported apart, not judged.
LIBRARY_SIMULATIONS = ("wave", "geometric")
#: How the terminal and the tables name a simulation and an input.
SIMULATION_WORDS = {"wave": "wave optics", "geometric": "ray optics", "thesis": "thesis method",
                    "thesis_power": "thesis method, its lens power error only",
                    "thesis_pupil": "thesis method, its pupil error only",
                    "no_magnification": "ray optics without spectacle magnification", TRACED_RAYS: "self-check ray trace"}
INPUT_WORDS = {"render": "on the no-lens render", "synthetic": "on the drawn chart"}


def _name(r: dict) -> str:
    return f"{r['configuration']}, {SIMULATION_WORDS.get(r['simulation'], r['simulation'])} {INPUT_WORDS.get(r['input'], r['input'])}"


def summary_lines(rows: list[dict]) -> list[str]:
    """The terminal summary of a run: its verdict in a few plain lines (the numbers: tables.md, metrics.csv).

    vissim's simulations (`LIBRARY_SIMULATIONS`) of the configurations with a lens are judged by their score, PSNR
    against the render minus the render's noise floor (0 dB: as close as a second render; +3.01 dB: perfect).  A
    configuration without a lens has no blur to simulate and a meaningless floor (two renders of a sharp letter
    agree to 60-100 dB): its simulations are judged by their PSNR alone, against one 8-bit grey level
    (`ONE_GREY_LEVEL_PSNR_DB`: an RMS difference no display shows).
    """
    scored = [r for r in rows if not is_wave_bench_row(r) and math.isfinite(r[floor_column(PSNR)])]
    judged = [r for r in scored if r["simulation"] in LIBRARY_SIMULATIONS and r["lenses"] != NO_LENS]
    bare = [r for r in scored if r["simulation"] in LIBRARY_SIMULATIONS + (TRACED_RAYS,) and r["lenses"] == NO_LENS]
    lines = []
    if judged:
        worst = min(judged, key=margin)
        configurations = len({r["configuration"] for r in judged})
        at_floor = sum(margin(r) >= 0.0 for r in judged)
        what = f"{len(judged)} wave- and ray-optics simulations of the {configurations} configurations with a lens"
        if margin(worst) >= 0.0:
            head = f"verdict: all {what} at or above the render's noise floor"
        else:
            head = (f"verdict: all {what} within {-margin(worst):.1f} dB of the render's noise floor "
                    f"({at_floor} at or above it)")
        lines.append(f"{head}; worst: {_name(worst)}, {margin(worst):+.2f} dB.")
        lines.append(f"  (score = PSNR against the render minus that of two renders with different seeds: "
                     f"+{PERFECT_MARGIN_DB:.1f} dB a perfect simulation, 0 dB as close as a second render, below 0 dB "
                     "the simulation's own error exceeds the render's noise)")
    if bare:
        low = min(bare, key=lambda r: r[PSNR.name])
        passed = sum(r[PSNR.name] >= ONE_GREY_LEVEL_PSNR_DB for r in bare)
        count = len({r["configuration"] for r in bare})
        lines.append(f"no lens ({count} configuration{'s' if count > 1 else ''}, nothing to blur, so no noise "
                     f"floor to judge by): {passed} of {len(bare)} simulations within one 8-bit grey level of the render "
                     f"(PSNR >= {ONE_GREY_LEVEL_PSNR_DB:.1f} dB); lowest {low[PSNR.name]:.1f} dB ({_name(low)}).")
    checks = [r for r in scored if r["simulation"] == TRACED_RAYS and r["lenses"] != NO_LENS]
    if checks:
        passed = sum(margin(r) >= SELF_CHECK_MARGIN_DB for r in checks)
        lines.append(f"self-check (an independent ray trace of the lenses): {passed} of {len(checks)} at least "
                     f"+{SELF_CHECK_MARGIN_DB:g} dB over the floor; lowest {min(margin(r) for r in checks):+.2f} dB.")
    bench = [r for r in rows if is_wave_bench_row(r) and r["simulation"] == "wave" and r["lenses"] != NO_LENS]
    if bench:
        low = min(r[PSNR.name] for r in bench)
        lines.append(f"wave optics against the noise-free wave bench: PSNR {low:.1f} dB or more "
                     f"(RMS difference at most {100 * 10 ** (-low / 20):.2g} % of white).")
    thesis = [margin(r) for r in scored if r["simulation"] == "thesis" and r["lenses"] != NO_LENS]
    if thesis:
        lines.append(f"thesis method (reproduced with its published errors, docs/ERRATA.md; not judged): "
                     f"{value_span(sorted(thesis), '+.1f')} dB over the floor.")
    return lines
