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
from vissim.imageio import read_image, srgb_decode, srgb_encode, write_image  # noqa: E402
from vissim.progress import Progress, counter  # noqa: E402
from vissim.provenance import make_provenance  # noqa: E402
from vissim.validation.fit_report import fit_table  # noqa: E402
from vissim.validation.optics_figures import optics_figures  # noqa: E402
from vissim.validation.wave_bench import TRACED_RAYS, WAVE_BENCH, WAVE_BENCH_NOTE  # noqa: E402
from vissim.validation.wave_bench_report import is_wave_bench_row, self_check_table, wave_bench_tables  # noqa: E402

__all__ = [
    "load_results",
    "build_report",
    "metrics_rows",
    "markdown_tables",
    "summary_table",
    "html_report",
    "write_report_files",
    "format_number",
    "json_rows",
    "reference_note",
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
    return [results[k] for k in order if k in results]


def _num(value) -> float:
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
                    "letter": config["letter"],
                    "logmar": config["logmar"],
                    "polarity": config["polarity"],
                    "lenses": result["lens_label"],
                    "simulation": comp["simulation"],
                    "input": comp["input"],
                    "reference": reference_note(comp),
                    "ssim": comp["metrics"]["ssim"],
                    "psnr_db": _num(comp["metrics"]["psnr_db"]),
                    "mean_abs_diff": comp["metrics"]["mean_abs_diff"],
                    "noise_floor_ssim": floor["ssim"],
                    "noise_floor_psnr_db": _num(floor["psnr_db"]),
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
        by_config.setdefault(r["configuration"], {"_floor": {}})[(r["simulation"], r["input"])] = r
        by_config[r["configuration"]]["_floor"][REFERENCE_NOTE[r["simulation"]]] = (r["noise_floor_psnr_db"], r["noise_floor_ssim"])
    out = [summary_table(rows, [c for c in columns if c[0] != TRACED_RAYS])]
    self_check = self_check_table(rows)
    if self_check:
        out.append(self_check)
    for metric, label, digits in (("psnr_db", "PSNR (dB)", 2), ("ssim", "SSIM", 4)):
        floor_idx = 0 if metric == "psnr_db" else 1
        header = ["configuration"] + [f"{s} / {i}" for s, i in columns] + ["noise floor (render)", "noise floor (+diffraction)"]
        out.append(f"### {label} against the bench\n")
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "---|" * len(header))
        for name, cells in by_config.items():
            values = [_fmt(cells[c][metric], digits) if c in cells else "—" for c in columns]
            floors = [
                _fmt(cells["_floor"][note][floor_idx], digits) if note in cells["_floor"] else "—"
                for note in (REFERENCE_NOTE["geometric"], REFERENCE_NOTE["wave"])
            ]
            out.append("| " + " | ".join([name] + values + floors) + " |")
        out.append("")
    out.append(
        "Columns are simulation / input: `render` = applied to the bench's no-lens render (as the thesis "
        "did), `synthetic` = applied to the synthetic chart. `wave` and `thesis` are compared with the "
        "render convolved with the bench aperture's diffraction (Mitsuba renders none); `geometric` and "
        "the one-erratum variants (`thesis_power`, `thesis_pupil`, `no_magnification`, geometric optics) "
        "with the render as it is. The noise floor compares the two ground-truth renders (seeds differ): "
        "each simulation is compared with the first, so a perfect, noise-free simulation would score "
        "3.0 dB above the floor's PSNR (MSE sigma^2 instead of 2 sigma^2); a score near floor + 3 dB "
        "means the agreement is as good as the renders' Monte-Carlo noise can show.\n"
    )
    wave_bench = wave_bench_tables(results, all_rows)
    if wave_bench:
        out.append(wave_bench)
    fits = fit_table(results)
    if fits:
        out.append(fits)
    return "\n".join(out)


def summary_table(rows: list[dict], columns: list[tuple[str, str]]) -> str:
    """Median PSNR minus the noise floor per group of configurations (a sweep, or one item).

    0 dB is the floor; +3 dB is what a perfect, noise-free simulation would score.
    """
    groups: dict[str, dict] = {}
    for r in rows:
        group = r["configuration"].split(":")[0]
        margin = r["psnr_db"] - r["noise_floor_psnr_db"]
        groups.setdefault(group, {}).setdefault((r["simulation"], r["input"]), []).append(margin)
    header = ["group (configurations)"] + [f"{s} / {i}" for s, i in columns]
    lines = [
        "### Summary: median PSNR minus the noise floor (dB)\n",
        "A perfect, noise-free simulation scores +3 dB; 0 dB means it differs from the bench as much "
        "as two renders differ from each other.\n",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for group, cells in groups.items():
        n = max(len(v) for v in cells.values())
        values = [_fmt(float(np.median(cells[c])), 1) if c in cells else "—" for c in columns]
        lines.append("| " + " | ".join([f"{group} ({n})"] + values) + " |")
    return "\n".join(lines) + "\n"


def _load(result: dict, run_dir: Path, name: str) -> np.ndarray | None:
    rel = result["images"].get(name)
    if not rel:
        return None
    return read_image(run_dir / rel).pixels


#: 1 - SSIM is shown on a log scale over this range (the SSIM of a good simulation is 0.99+).
DISSIMILARITY_RANGE = (1e-4, 1.0)


def reflectance_norm():
    """Grey images as the eye sees them (sRGB), colour bars in linear reflectance."""
    from matplotlib.colors import FuncNorm

    return FuncNorm((lambda x: srgb_encode(np.clip(x, 0, 1)), lambda y: srgb_decode(np.clip(y, 0, 1))), vmin=0, vmax=1)


def column_title(result: dict) -> str:
    """A figure column's header: the letter, its LogMAR and the lenses."""
    config = result["configuration"]
    return f"{config['letter']}, LogMAR {config['logmar']:.1f}\n{result['lens_label']}"


def png_bytes(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def _figure(results: list[dict], run_dir: Path, simulation: str, input_kind: str,
            wave_bench: bool = False) -> bytes | None:
    """Fig. 4.8-style: rows ground truth, simulation, 1 - SSIM map, AD map; a column per configuration.

    ``wave_bench``: the comparisons against the wave bench, else those against the render.
    """
    from matplotlib.colors import LogNorm, Normalize

    columns = []
    for result in results:
        comp = next((c for c in result["comparisons"] if c["simulation"] == simulation and c["input"] == input_kind
                     and (c.get("reference_kind") == WAVE_BENCH) == wave_bench), None)
        if comp is not None:
            columns.append((result, comp))
    if not columns:
        return None
    columns = columns[:FIGURE_COLUMNS]
    highest = max(float(np.percentile(read_image(run_dir / c["images"]["abs_diff_map"]).pixels, 99.9)) for _, c in columns)
    ad_max = max(1e-4 if wave_bench else 0.01, highest)  # the wave bench's differences are 100x smaller
    lo, hi = DISSIMILARITY_RANGE
    rows = [("wave bench (truth)" if wave_bench else "bench (truth)", "gray", reflectance_norm, "reflectance"),
            (f"{simulation} sim.", "gray", reflectance_norm, "reflectance"),
            ("1 − SSIM (log)", "viridis", lambda: LogNorm(lo, hi), "1 − SSIM"),
            ("|difference|", "magma", lambda: Normalize(0, ad_max), "|difference| (reflectance)")]
    fig, axes = plt.subplots(4, len(columns), figsize=(1.9 * len(columns) + 1.6, 8.8), squeeze=False,
                             layout="constrained")
    shown = [None] * len(rows)
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
        axes[0, j].set_title(column_title(result), fontsize=8)
        axes[3, j].set_xlabel(f"SSIM {comp['metrics']['ssim']:.3f}\nPSNR {_fmt(_num(comp['metrics']['psnr_db']), 1)} dB", fontsize=8)
    for i, (label, _, _, bar_label) in enumerate(rows):
        axes[i, 0].set_ylabel(label, fontsize=9)
        bar = fig.colorbar(shown[i], ax=axes[i, :], shrink=0.9, pad=0.02, aspect=15)
        bar.set_label(bar_label, fontsize=8)
        bar.ax.tick_params(labelsize=7)
    fig.suptitle(f"{simulation} simulation applied to the {input_kind} input, against {reference_note(columns[0][1])}",
                 fontsize=10)
    return png_bytes(fig)


def html_report(title: str, tables_md: str, figures: dict[str, bytes], footer: str = "") -> str:
    """A self-contained HTML page: the Markdown tables as HTML tables, figures inline (base64)."""
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}"
             "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px;"
             "text-align:right}td:first-child{text-align:left}</style></head><body>",
             f"<h1>{html.escape(title)}</h1>"]
    for block in tables_md.split("### ")[1:]:
        lines = [line for line in block.strip().splitlines() if line.strip()]
        parts.append(f"<h2>{html.escape(lines[0])}</h2>")
        rows = [line for line in lines[1:] if line.startswith("|") and not line.startswith("|---")]
        parts += [f"<p>{html.escape(t)}</p>" for t in lines[1:] if not t.startswith("|")]
        parts.append("<table>")
        for k, line in enumerate(rows):
            tag = "th" if k == 0 else "td"
            cells = [c.strip() for c in line.strip("|").split("|")]
            parts.append("<tr>" + "".join(f"<{tag}>{html.escape(c)}</{tag}>" for c in cells) + "</tr>")
        parts.append("</table>")
    for name, png in figures.items():
        parts.append(f"<h2>{html.escape(name)}</h2><img style='max-width:100%' "
                     f"src='data:image/png;base64,{base64.b64encode(png).decode()}'>")
    if footer:
        parts.append(f"<p><small>{html.escape(footer)}</small></p>")
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
    """A figure's PNG through :func:`vissim.imageio.write_image` (so it gets its provenance sidecar); its bytes."""
    from PIL import Image as PILImage

    codes = np.asarray(PILImage.open(io.BytesIO(png)).convert("RGB"), dtype=np.float32) / 255.0
    write_image(path, codes, provenance=provenance, overwrite=True, encoding="linear")  # codes kept exactly
    return path.read_bytes()


def write_report_files(run_dir: Path, *, title: str, metrics: dict, rows: list[dict], tables_md: str,
                       figures: dict[str, tuple]) -> list[Path]:
    """metrics.json, metrics.csv, tables.md, the figures and report.html.

    ``figures``: name -> ``(file name, PNG)`` or ``(file name, PNG, provenance extras)``; each is written
    with its sidecar and linked from tables.md (Markdown images) and shown in report.html.
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
    links = "".join(f"### {name}\n\n![{name}]({entry[0]})\n\n" for name, entry in figures.items())
    text = f"# {title}\n\n{campaign.get('description', '')}\n\n{tables_md}\n{links}{made}\n"
    written.append(write_text_atomic(run_dir / "tables.md", text, overwrite=True))
    pngs = {}
    for name, (file_name, png, *extra) in figures.items():
        pngs[name] = write_figure(run_dir / file_name, png, {**provenance, **(extra[0] if extra else {}), "figure": name})
        written += [run_dir / file_name, run_dir / f"{file_name}.json"]
    page = html_report(title, tables_md, pngs, footer=made)
    written.append(write_text_atomic(run_dir / "report.html", page, overwrite=True))
    return written


def campaign_name(run_dir: Path) -> str:
    order = run_dir / "campaign.json"
    return json.loads(order.read_text()).get("name", run_dir.name) if order.exists() else run_dir.name


def build_report(run_dir: str | Path, progress: Progress | None = None) -> list[Path]:
    """Write metrics.json, metrics.csv, tables.md, figure_*.png and report.html into ``run_dir``.

    The figures: Fig. 4.8-style panels per simulation, and per group the wave PSF (log scale), its
    MTF against the diffraction limit and a through-focus strip (:mod:`vissim.validation.optics_figures`).
    ``progress(stage, done, total)`` after each figure and the files (:mod:`vissim.progress`).
    """
    run_dir = Path(run_dir)
    results = load_results(run_dir)
    rows = metrics_rows(results)
    figures = {}
    advance = counter(progress, "report", len(ORDER) + 3)
    for simulation in ORDER:
        png = _figure(results, run_dir, simulation, "render")
        if png is not None:
            figures[f"{simulation} simulation on the no-lens render"] = (f"figure_{simulation}.png", png)
        advance()
    png = _figure(results, run_dir, "wave", "synthetic", wave_bench=True)
    if png is not None:
        name = "wave simulation on the synthetic chart against the wave bench"
        figures[name] = (f"figure_wave_{WAVE_BENCH}.png", png)
    advance()
    try:  # per group: the PSF (log), its MTF, through focus; the rest of the report does not depend on them
        optics = optics_figures(results, run_dir, reflectance_norm)
    except (KeyError, OSError, ValueError, VissimInputError) as error:
        log.warning("report: the optics figures were skipped (%s: %s)", type(error).__name__, error)
        optics = {}
    for name, (file_name, fig, extra) in optics.items():
        figures[name] = (file_name, png_bytes(fig), extra)
    advance()
    written = write_report_files(run_dir, title=f"vissim validation: {campaign_name(run_dir)}",
                                 metrics={"items": results, "rows": json_rows(rows)}, rows=rows,
                                 tables_md=markdown_tables(results), figures=figures)
    advance()
    log.info("report of %d items written to %s", len(results), run_dir)
    return written
