"""The DSLR bench's report: metric rows, thesis-style tables and Fig. 4.8-style figures.

Rows and tables read the items' ``result.json`` numbers; the figures read their images.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.progress import counter
from vissim.validation.dslr.fit_report import fit_table
from vissim.validation.dslr.optics_figures import optics_figures
from vissim.validation.dslr.report_words import arcmin_per_px_of, column_title, group_of
from vissim.validation.dslr.wave_bench import TRACED_RAYS, WAVE_BENCH, WAVE_BENCH_NOTE
from vissim.validation.dslr.wave_bench_report import is_wave_bench_row, self_check_table, wave_bench_tables
from vissim.validation.engine.figures import (Figure, display_norm, pyplot, png_bytes, radiance_colorbar, scale_bar,
                                              tiles_alt)
from vissim.validation.engine.protocol import ReportParts
from vissim.validation.engine.metrics import (MEAN_ABS_DIFF, PSNR, SSIM, added_metrics, floor_column,
                                              metric_float)
from vissim.validation.engine.report import format_number
from vissim.validation.engine.summary import summary_table

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
                    "lenses": result["lens_label"],
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
    out = [summary_table(rows, [c for c in columns if c[0] != TRACED_RAYS])]
    self_check = self_check_table(rows)
    if self_check:
        out.append(self_check)
    for metric in (PSNR, SSIM):
        powers = ["trial lens(es)", "camera Rx (result)"] if metric is PSNR else []
        header = ["configuration", *powers] + [f"{s} / {i}" for s, i in columns] + ["noise floor (render)",
                                                                                   "noise floor (+diffraction)"]
        out.append(f"### {metric.heading()} against the bench\n")
        if metric is PSNR:
            out.append(COLUMNS_NOTE)
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "---|" * len(header))
        for name, cells in by_config.items():
            values = [_fmt(cells[c][metric.name], metric.digits) if c in cells else "—" for c in columns]
            floors = [
                _fmt(cells["_floor"][note][floor_column(metric)], metric.digits) if note in cells["_floor"] else "—"
                for note in (REFERENCE_NOTE["geometric"], REFERENCE_NOTE["wave"])
            ]
            shown = [cells[c] for c in columns if c in cells][0]
            rx = [shown["lenses"], cells["_rx"]] if powers else []
            out.append("| " + " | ".join([name, *rx] + values + floors) + " |")
        out.append("")
    wave_bench = wave_bench_tables(results, all_rows)
    if wave_bench:
        out.append(wave_bench)
    fits = fit_table(results)
    if fits:
        out.append(fits)
    return "\n".join(out)


COLUMNS_NOTE = (
    "Columns are simulation / input: `render` = applied to the bench's no-lens render (as the thesis did), "
    "`synthetic` = applied to the synthetic chart. `wave` and `thesis` are compared with the render convolved "
    "with the bench aperture's diffraction (Mitsuba renders none); `geometric` and the one-erratum variants "
    "(`thesis_power`, `thesis_pupil`, `no_magnification`, geometric optics) with the render as it is. The trial "
    "lens is the power in the holder in front of the camera; the camera Rx is the prescription the camera then "
    "has (the correcting lens at its pupil, minus cylinder), which the simulations blur with. The noise floor "
    "compares the two renders of the bench (seeds differ); the summary above explains how to read a score "
    "against it.\n")


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
    rows = [(truth_label, "gray", display_norm, None),
            (f"{simulation} sim.", "gray", display_norm, None),
            ("1 − SSIM (log)", "viridis", lambda: LogNorm(lo, hi), "1 − SSIM"),
            ("|difference|", "magma", lambda: Normalize(0, ad_max), "|difference| (relative radiance, linear)")]
    fig, axes = pyplot.subplots(4, len(columns), figsize=(1.9 * len(columns) + 1.8, 9.2), squeeze=False,
                             layout="constrained")
    shown = [None] * len(rows)
    bar_arcmin = None
    for j, (result, comp) in enumerate(columns):
        truth = _load(result, run_dir, comp["reference_image"])
        sim = read_image(run_dir / comp["images"]["simulation"]).pixels
        ssim_map = read_image(run_dir / comp["images"]["ssim_map"]).pixels
        images = [truth, sim, np.clip(1.0 - ssim_map, lo, hi), ad_maps[j]]
        for i, (img, (_, cmap, norm, _)) in enumerate(zip(images, rows)):
            ax = axes[i, j]
            shown[i] = ax.imshow(img, cmap=cmap, norm=norm(), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
        step = arcmin_per_px_of(result, campaign)
        if step is not None:
            bar_arcmin = scale_bar(axes[0, j], truth.shape[1], step)
        axes[0, j].set_title(column_title(result, comp), fontsize=7)
        axes[3, j].set_xlabel(f"SSIM {comp['metrics'][SSIM.name]:.3f}\nPSNR {_fmt(metric_float(comp['metrics'][PSNR.name]), 1)} dB", fontsize=8)
    for i, (label, _, _, bar_label) in enumerate(rows):
        axes[i, 0].set_ylabel(label, fontsize=9)
        bar = fig.colorbar(shown[i], ax=axes[i, :], shrink=0.9, pad=0.02, aspect=15)
        bar.ax.tick_params(labelsize=7)
        if bar_label is None:
            radiance_colorbar(bar)
        else:
            bar.set_label(bar_label, fontsize=8)
    scale = f"; scale bars {bar_arcmin:g} arcmin" if bar_arcmin else ""
    fig.suptitle(f"{simulation} simulation applied to the {input_kind} input, against {reference_note(columns[0][1])}"
                 f"{scale}", fontsize=10)
    alt = tiles_alt(f"{simulation} simulation of the {input_kind} input against {reference_note(columns[0][1])}, "
                    "as letter tiles with an angular scale bar",
                    [truth_label, f"the {simulation} simulation", "1 − SSIM map on a log scale",
                     "absolute difference map"],
                    [f"{r['configuration']['name']}: SSIM {c['metrics'][SSIM.name]:.3f}, "
                     f"PSNR {_fmt(metric_float(c['metrics'][PSNR.name]), 1)} dB" for r, c in columns])
    return Figure("", png_bytes(fig), alt)


def dslr_report(results: list[dict], run_dir: Path, record: dict, progress=None) -> ReportParts:
    """The DSLR report's rows, tables and figures.

    The figures: Fig. 4.8-style panels per simulation on the no-lens render and, for the main
    simulations, on the synthetic chart; and per group the wave PSF (log scale), its MTF against the
    diffraction limit and a through-focus strip (`vissim.validation.dslr.optics_figures`).
    ``progress(stage, done, total)`` after each figure (`vissim.progress`).
    """
    figures = {}
    wanted = [(s, "render", False, f"{s} simulation on the no-lens render", f"figure_{s}.png") for s in ORDER]
    wanted += [(s, "synthetic", False, f"{s} simulation on the synthetic chart", f"figure_{s}_synthetic.png")
               for s in SYNTHETIC_FIGURES]
    wanted.append(("wave", "synthetic", True, "wave simulation on the synthetic chart against the wave bench",
                   f"figure_wave_{WAVE_BENCH}.png"))
    advance = counter(progress, "figures", len(wanted) + 1)
    for simulation, input_kind, wave_bench, name, file_name in wanted:
        figure = _figure(results, run_dir, simulation, input_kind, wave_bench=wave_bench, campaign=record)
        if figure is not None:
            figures[name] = figure._replace(file_name=file_name)
        advance()
    try:  # per group: the PSF (log), its MTF, through focus; the rest of the report does not depend on them
        optics = optics_figures(results, run_dir, record, display_norm)
    except (KeyError, OSError, ValueError, VissimInputError) as error:
        log.warning("report: the optics figures were skipped (%s: %s)", type(error).__name__, error)
        optics = {}
    for name, (file_name, fig, extra, alt) in optics.items():
        figures[name] = Figure(file_name, png_bytes(fig), alt, extra)
    advance()
    title = f"vissim validation: {record.get('name', run_dir.name)}"
    rows = metrics_rows(results)
    return ReportParts(title, rows, markdown_tables(results, rows), figures)


def summary_lines(rows: list[dict]) -> list[str]:
    """The terminal summary of a run: one line per comparison (no floor: ``—``)."""
    width = min(max([len("configuration"), *(len(r["configuration"]) for r in rows)]), 72)  # names whole, up to 72
    lines = [(f"{'configuration':{width}s} {'simulation':>16s} {'input':>9s} {'SSIM':>7s} {'PSNR dB':>8s} "
              f"{'floor dB':>8s} {'against':>10s}")]
    for r in rows:
        against = "wave bench" if is_wave_bench_row(r) else "render"
        lines.append(f"{r['configuration'][:width]:{width}s} {r['simulation']:>16s} {r['input']:>9s} {r[SSIM.name]:7.4f} "
                     f"{format_number(r[PSNR.name], 2):>8s} {format_number(r[floor_column(PSNR)], 2):>8s} "
                     f"{against:>10s}")
    return lines