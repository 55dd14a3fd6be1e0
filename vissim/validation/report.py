"""Reports of a campaign run: metrics (JSON, CSV), thesis-style tables, figures, HTML.

Everything is rebuilt from the finished items' ``result.json`` files and images, so
``vissim report RUN`` regenerates a report without rendering anything.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
import logging
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vissim.atomic import atomic_output, write_json_atomic, write_text_atomic  # noqa: E402
from vissim.errors import VissimInputError  # noqa: E402
from vissim.imageio import read_image, write_image  # noqa: E402
from vissim.progress import Progress, counter  # noqa: E402
from vissim.provenance import make_provenance  # noqa: E402
from vissim.validation.fit_report import fit_table  # noqa: E402
from vissim.validation.optics_figures import optics_figures  # noqa: E402
from vissim.validation.report_figures import (Figure, arcmin_per_px_of, display_norm, lens_words,  # noqa: E402
                                              radiance_colorbar, scale_bar, tiles_alt)
from vissim.validation.report_summary import summary_table  # noqa: E402
from vissim.validation.wave_bench import TRACED_RAYS, WAVE_BENCH, WAVE_BENCH_NOTE  # noqa: E402
from vissim.validation.wave_bench_report import group_of, is_wave_bench_row, self_check_table, wave_bench_tables  # noqa: E402

__all__ = [
    "load_results",
    "build_report",
    "metrics_rows",
    "markdown_tables",
    "summary_table",
    "html_report",
    "write_report_files",
    "format_number",
    "metric_float",
    "json_rows",
    "reference_note",
    "Figure",
]

log = logging.getLogger(__name__)

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


def load_results(run_dir: str | Path) -> list[dict]:
    """The finished items of a run, in campaign order."""
    run_dir = Path(run_dir)
    order_file = run_dir / "campaign.json"
    order = json.loads(order_file.read_text())["items"] if order_file.exists() else []
    results = {}
    for path in sorted((run_dir / "items").glob("*/result.json")):
        result = json.loads(path.read_text())
        results[result["key"]] = result
    if not order:
        return [results[k] for k in sorted(results)]
    stale = set(results) - set(order)
    if stale:  # items of another campaign (or of an older simulator) left in the folder: not this run's
        log.info("ignoring %d finished items in %s that are not in its campaign", len(stale), run_dir / "items")
    # A configuration's name and group are not part of its item's key: a reused item takes the campaign's current ones.
    configurations = json.loads(order_file.read_text()).get("configurations") or []
    labels = {key: c for key, c in zip(order, configurations) if isinstance(c, dict)}
    for key, result in results.items():
        if isinstance(result.get("configuration"), dict):
            for field in ("name", "group"):
                if labels.get(key, {}).get(field):
                    result["configuration"][field] = labels[key][field]
    return [results[k] for k in order if k in results]


def metric_float(value) -> float:
    """A JSON metric back to a float: ``"inf"`` is infinite, None unknown (NaN)."""
    if value is None:
        return math.nan
    return math.inf if value == "inf" else float(value)


def metrics_rows(results: list[dict]) -> list[dict]:
    """One flat row per (configuration, simulation, input)."""
    rows = []
    for result in results:
        config = result["configuration"]
        for comp in result["comparisons"]:
            # no floor: a capture without a repeat, or the noise-free wave bench
            floor = result["noise_floor"].get(comp["reference_kind"]) or {"ssim": float("nan"), "psnr_db": float("nan")}
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
                    "ssim": comp["metrics"]["ssim"],
                    "psnr_db": metric_float(comp["metrics"]["psnr_db"]),
                    "mean_abs_diff": comp["metrics"]["mean_abs_diff"],
                    "noise_floor_ssim": floor["ssim"],
                    "noise_floor_psnr_db": metric_float(floor["psnr_db"]),
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


def json_rows(rows: list[dict]) -> list[dict]:
    """Rows for JSON: an unknown number (NaN, e.g. the wave bench's noise floor) is null, infinity ``"inf"``."""
    def cell(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
        return value

    return [{k: cell(v) for k, v in row.items()} for row in rows]


def format_number(value: float | None, digits: int) -> str:
    """A table cell: ``—`` for unknown (None/NaN), ``∞`` for infinite PSNR."""
    if value is None or math.isnan(value):
        return "—"
    return "∞" if math.isinf(value) else f"{value:.{digits}f}"


_fmt = format_number


def markdown_tables(results: list[dict]) -> str:
    """Thesis-style tables (one row per configuration), PSNR and SSIM, with noise floors; then the wave bench's."""
    all_rows = metrics_rows(results)
    if not all_rows:
        return "No finished items.\n"
    rows = [r for r in all_rows if not is_wave_bench_row(r)]
    columns = sorted({(r["simulation"], r["input"]) for r in rows}, key=lambda c: (ORDER.index(c[0]), c[1]))
    by_config: dict[str, dict] = {}
    for r in rows:
        by_config.setdefault(r["configuration"], {"_floor": {}, "_rx": "—"})[(r["simulation"], r["input"])] = r
        if r["simulation"] in ("wave", "geometric"):  # the bench's own optics (thesis mode has its own Rx)
            by_config[r["configuration"]]["_rx"] = r["camera_prescription"]
        by_config[r["configuration"]]["_floor"][REFERENCE_NOTE[r["simulation"]]] = (r["noise_floor_psnr_db"], r["noise_floor_ssim"])
    out = [summary_table(rows, [c for c in columns if c[0] != TRACED_RAYS])]
    self_check = self_check_table(rows)
    if self_check:
        out.append(self_check)
    for metric, label, digits in (("psnr_db", "PSNR (dB)", 2), ("ssim", "SSIM", 4)):
        floor_idx = 0 if metric == "psnr_db" else 1
        powers = ["trial lens(es)", "camera Rx (result)"] if metric == "psnr_db" else []
        header = ["configuration", *powers] + [f"{s} / {i}" for s, i in columns] + ["noise floor (render)",
                                                                                   "noise floor (+diffraction)"]
        out.append(f"### {label} against the bench\n")
        if metric == "psnr_db":
            out.append(COLUMNS_NOTE)
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "---|" * len(header))
        for name, cells in by_config.items():
            values = [_fmt(cells[c][metric], digits) if c in cells else "—" for c in columns]
            floors = [
                _fmt(cells["_floor"][note][floor_idx], digits) if note in cells["_floor"] else "—"
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


def column_title(result: dict, comparison: dict | None = None) -> str:
    """A figure column's header: the letter and its LogMAR, the trial lens, the camera's resulting Rx (`camera_rx`)."""
    config = result["configuration"]
    title = f"{config['letter']}, LogMAR {config['logmar']:.1f}\n{lens_words(result['lens_label'])}"
    if comparison is not None:
        title += f"\ncamera Rx {camera_rx(result, comparison)}"
    return title


def camera_rx(result: dict, comparison: dict | None = None) -> str:
    """The camera's resulting prescription behind the trial lenses: the bench's (the matched wave or geometric
    simulation's), which thesis mode replaces with its own; that comparison's if neither ran."""
    matched = next((c for c in result["comparisons"] if c["simulation"] in ("wave", "geometric")), comparison)
    return matched["setup"]["camera_prescription"] if matched else "—"


def png_bytes(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


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
    highest = max(float(np.percentile(read_image(run_dir / c["images"]["abs_diff_map"]).pixels, 99.9)) for _, c in columns)
    ad_max = max(1e-4 if wave_bench else 0.01, highest)  # the wave bench's differences are 100x smaller
    lo, hi = DISSIMILARITY_RANGE
    truth_label = "wave bench (truth)" if wave_bench else "bench (truth)"
    rows = [(truth_label, "gray", display_norm, None),
            (f"{simulation} sim.", "gray", display_norm, None),
            ("1 − SSIM (log)", "viridis", lambda: LogNorm(lo, hi), "1 − SSIM"),
            ("|difference|", "magma", lambda: Normalize(0, ad_max), "|difference| (relative radiance, linear)")]
    fig, axes = plt.subplots(4, len(columns), figsize=(1.9 * len(columns) + 1.8, 9.2), squeeze=False,
                             layout="constrained")
    shown = [None] * len(rows)
    bar_arcmin = None
    for j, (result, comp) in enumerate(columns):
        truth = _load(result, run_dir, comp["reference_image"])
        sim = read_image(run_dir / comp["images"]["simulation"]).pixels
        ssim_map = read_image(run_dir / comp["images"]["ssim_map"]).pixels
        ad_map = read_image(run_dir / comp["images"]["abs_diff_map"]).pixels
        images = [truth, sim, np.clip(1.0 - ssim_map, lo, hi), ad_map]
        for i, (img, (_, cmap, norm, _)) in enumerate(zip(images, rows)):
            ax = axes[i, j]
            shown[i] = ax.imshow(img, cmap=cmap, norm=norm(), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
        step = arcmin_per_px_of(result, campaign)
        if step is not None:
            bar_arcmin = scale_bar(axes[0, j], truth.shape[1], step)
        axes[0, j].set_title(column_title(result, comp), fontsize=7)
        axes[3, j].set_xlabel(f"SSIM {comp['metrics']['ssim']:.3f}\nPSNR {_fmt(metric_float(comp['metrics']['psnr_db']), 1)} dB", fontsize=8)
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
                    [f"{r['configuration']['name']}: SSIM {c['metrics']['ssim']:.3f}, "
                     f"PSNR {_fmt(metric_float(c['metrics']['psnr_db']), 1)} dB" for r, c in columns])
    return Figure("", png_bytes(fig), alt)


def _inline(text: str) -> str:
    """A line of Markdown as HTML: escaped, ``code`` spans as <code>."""
    parts = html.escape(text).split("`")
    return "".join(f"<code>{part}</code>" if k % 2 else part for k, part in enumerate(parts))


def _html_block(block: str) -> list[str]:
    """One ``### `` section of the Markdown: its heading, paragraphs and table (if any)."""
    lines = [line for line in block.strip().splitlines() if line.strip()]
    parts, body = [f"<h2>{_inline(lines[0])}</h2>"], lines[1:]
    rows = [line for line in body if line.startswith("|") and not line.startswith("|---")]
    first = next((k for k, line in enumerate(body) if line.startswith("|")), len(body))
    before, after = ([t for t in part if not t.startswith("|")] for part in (body[:first], body[first:]))
    parts += [f"<p>{_inline(t)}</p>" for t in before]
    if rows:
        parts.append("<table>")
        for k, line in enumerate(rows):
            tag = "th" if k == 0 else "td"
            cells = [c.strip() for c in line.strip("|").split("|")]
            parts.append("<tr>" + "".join(f"<{tag}>{_inline(c)}</{tag}>" for c in cells) + "</tr>")
        parts.append("</table>")
    parts += [f"<p>{_inline(t)}</p>" for t in after]
    return parts


def html_report(title: str, tables_md: str, figures: dict[str, Figure], footer: str = "", description: str = "") -> str:
    """A self-contained HTML page: the Markdown tables as HTML tables, figures inline (base64) with alt text."""
    parts = [f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1200px;margin:auto;padding:0 8px}"
             "table{border-collapse:collapse;font-size:12px;display:block;overflow-x:auto}"
             "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}td:first-child{text-align:left}"
             "code{background:#f3f3f3;padding:0 2px}</style></head><body>",
             f"<h1>{html.escape(title)}</h1>"]
    if description:
        parts.append(f"<p>{_inline(description)}</p>")
    for block in tables_md.split("### ")[1:]:
        parts += _html_block(block)
    for name, figure in figures.items():
        parts.append(f"<h2>{html.escape(name)}</h2><img style='max-width:100%' alt='{html.escape(figure.alt, quote=True)}' "
                     f"src='data:image/png;base64,{base64.b64encode(figure.png).decode()}'>")
    if footer:
        parts.append(f"<p><small>{_inline(footer)}</small></p>")
    parts.append("</body></html>")
    return "\n".join(parts)


def _render_records(tree) -> list[dict]:
    """Every render record (a dict with ``variant`` and ``spp_used``) found in a JSON tree."""
    if isinstance(tree, dict):
        found = [tree] if "variant" in tree and "spp_used" in tree else []
        return found + [r for value in tree.values() for r in _render_records(value)]
    if isinstance(tree, list):
        return [r for value in tree for r in _render_records(value)]
    return []


def renders_summary(results: list[dict]) -> list[dict]:
    """The distinct (variant, spp asked, spp used, deterministic) of the renders behind ``results``."""
    merged: dict[tuple, dict] = {}
    for record in _render_records(results):
        entry = merged.setdefault((record["variant"], record["spp_used"]), {})
        entry.update({k: record[k] for k in ("variant", "spp_requested", "spp_used", "deterministic") if k in record})
    return [merged[key] for key in sorted(merged, key=repr)]


def report_provenance(run_dir: Path, campaign: dict, results: list[dict]) -> dict:
    """Provenance of a report file: the campaign (name, source, settings), the items it shows and their renders."""
    return make_provenance(run=run_dir, campaign=campaign.get("name"), campaign_file=campaign.get("source"),
                           settings=campaign.get("settings"), items=campaign.get("items"),
                           renders=renders_summary(results))


def write_figure(path: Path, png: bytes, provenance: dict) -> bytes:
    """A figure's PNG through `vissim.imageio.write_image` (so it gets its provenance sidecar); its bytes."""
    from PIL import Image as PILImage

    codes = np.asarray(PILImage.open(io.BytesIO(png)).convert("RGB"), dtype=np.float32) / 255.0
    write_image(path, codes, provenance=provenance, overwrite=True, encoding="linear")  # codes kept exactly
    return path.read_bytes()


def write_report_files(run_dir: Path, *, title: str, metrics: dict, rows: list[dict], tables_md: str,
                       figures: dict[str, Figure]) -> list[Path]:
    """metrics.json, metrics.csv, tables.md, the figures and report.html.

    ``figures``: name -> `Figure` (file name, PNG, alt text, provenance extras); each is written
    with its sidecar and linked from tables.md (a Markdown image with its alt text) and shown in
    report.html.
    """
    campaign = json.loads((run_dir / "campaign.json").read_text()) if (run_dir / "campaign.json").exists() else {}
    provenance = report_provenance(run_dir, campaign, metrics["items"])
    written = [write_json_atomic(run_dir / "metrics.json", {**metrics, "provenance": provenance}, overwrite=True)]
    with atomic_output(run_dir / "metrics.csv", overwrite=True) as tmp:
        with open(tmp, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else ["configuration"])
            writer.writeheader()
            writer.writerows(rows)
    written.append(run_dir / "metrics.csv")
    made = (f"Made by vissim {provenance['vissim_version']} on {provenance['created_utc']} from "
            f"{campaign.get('source', 'an unknown campaign file')}; provenance in metrics.json.")
    links = "".join(f"### {name}\n\n![{_markdown_alt(f.alt)}]({f.file_name})\n\n" for name, f in figures.items())
    description = campaign.get("description", "")
    text = f"# {title}\n\n{description}\n\n{tables_md}\n{links}{made}\n"
    written.append(write_text_atomic(run_dir / "tables.md", text, overwrite=True))
    shown = {}
    for name, figure in figures.items():
        png = write_figure(run_dir / figure.file_name, figure.png,
                           {**provenance, **figure.extra, "figure": name, "alt": figure.alt})
        shown[name] = figure._replace(png=png)
        written += [run_dir / figure.file_name, run_dir / f"{figure.file_name}.json"]
    page = html_report(title, tables_md, shown, footer=made, description=description)
    written.append(write_text_atomic(run_dir / "report.html", page, overwrite=True))
    return written


def _markdown_alt(text: str) -> str:
    """Alt text inside ``![...]``: no brackets or line breaks."""
    return " ".join(text.replace("[", "(").replace("]", ")").split())


def campaign_name(run_dir: Path) -> str:
    order = run_dir / "campaign.json"
    return json.loads(order.read_text()).get("name", run_dir.name) if order.exists() else run_dir.name


def build_report(run_dir: str | Path, progress: Progress | None = None) -> list[Path]:
    """Write metrics.json, metrics.csv, tables.md, figure_*.png and report.html into ``run_dir``.

    The figures: Fig. 4.8-style panels per simulation on the no-lens render and, for the main
    simulations, on the synthetic chart; and per group the wave PSF (log scale), its MTF against the
    diffraction limit and a through-focus strip (`vissim.validation.optics_figures`).
    ``progress(stage, done, total)`` after each figure and the files (`vissim.progress`).
    """
    run_dir = Path(run_dir)
    results = load_results(run_dir)
    campaign = json.loads((run_dir / "campaign.json").read_text()) if (run_dir / "campaign.json").exists() else {}
    rows = metrics_rows(results)
    figures = {}
    wanted = [(s, "render", False, f"{s} simulation on the no-lens render", f"figure_{s}.png") for s in ORDER]
    wanted += [(s, "synthetic", False, f"{s} simulation on the synthetic chart", f"figure_{s}_synthetic.png")
               for s in SYNTHETIC_FIGURES]
    wanted.append(("wave", "synthetic", True, "wave simulation on the synthetic chart against the wave bench",
                   f"figure_wave_{WAVE_BENCH}.png"))
    advance = counter(progress, "report", len(wanted) + 2)
    for simulation, input_kind, wave_bench, name, file_name in wanted:
        figure = _figure(results, run_dir, simulation, input_kind, wave_bench=wave_bench, campaign=campaign)
        if figure is not None:
            figures[name] = figure._replace(file_name=file_name)
        advance()
    try:  # per group: the PSF (log), its MTF, through focus; the rest of the report does not depend on them
        optics = optics_figures(results, run_dir, display_norm)
    except (KeyError, OSError, ValueError, VissimInputError) as error:
        log.warning("report: the optics figures were skipped (%s: %s)", type(error).__name__, error)
        optics = {}
    for name, (file_name, fig, extra, alt) in optics.items():
        figures[name] = Figure(file_name, png_bytes(fig), alt, extra)
    advance()
    written = write_report_files(run_dir, title=f"vissim validation: {campaign_name(run_dir)}",
                                 metrics={"items": results, "rows": json_rows(rows)}, rows=rows,
                                 tables_md=markdown_tables(results), figures=figures)
    advance()
    log.info("report of %d items written to %s", len(results), run_dir)
    return written
