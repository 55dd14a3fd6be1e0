"""The one report builder: metrics (JSON, CSV), tables, figures and HTML of a run folder of any bench kind.

Everything is rebuilt from the finished items' ``result.json`` files and images, so
``vissim report RUN`` regenerates a report without rendering anything.  The bench kind
(`vissim.validation.engine.protocol.BenchKind.report`) gives the rows, tables and figures; this
module writes them, each with its provenance.
"""

from __future__ import annotations

import csv
import json
import logging
import math
from pathlib import Path

from vissim.atomic import atomic_output, write_json_atomic, write_text_atomic
from vissim.imageio import write_png_bytes
from vissim.progress import Progress
from vissim.provenance import make_provenance
from vissim.validation.engine.figures import Figure
from vissim.validation.engine.html_page import html_report
from vissim.validation.engine.reading import how_built
from vissim.validation.engine.records import Item, Row
from vissim.validation.engine.registry import DEFAULT_KIND, bench_kind

__all__ = ["load_results", "read_record", "write_report", "write_report_files", "format_number", "json_rows",
           "Figure"]

log = logging.getLogger(__name__)


def read_record(run_dir: Path) -> dict:
    """The run folder's ``campaign.json`` (empty when absent: a folder of items only)."""
    order = Path(run_dir) / "campaign.json"
    return json.loads(order.read_text()) if order.exists() else {}


def load_results(run_dir: str | Path, record: dict | None = None) -> list[Item]:
    """The finished items of a run, in campaign order (``record``: its ``campaign.json``, read if not given).

    Items of another campaign left in the folder are not this run's and are left out.  A
    configuration's name and group are no part of its item's key: a reused item takes the
    campaign's current ones.
    """
    run_dir = Path(run_dir)
    record = read_record(run_dir) if record is None else record
    order = record.get("items") or []
    results = {}
    for path in sorted((run_dir / "items").glob("*/result.json")):
        result = json.loads(path.read_text())
        results[result["key"]] = result
    if not order:
        return [Item.from_json(results[k]) for k in sorted(results)]
    stale = set(results) - set(order)
    if stale:  # items of another campaign (or of an older simulator) left in the folder: not this run's
        log.info("ignoring %d finished items in %s that are not in its campaign", len(stale), run_dir / "items")
    labels = {key: c for key, c in zip(order, record.get("configurations") or []) if isinstance(c, dict)}
    for key, result in results.items():
        if isinstance(result.get("configuration"), dict):
            for field in ("name", "group"):
                if labels.get(key, {}).get(field):
                    result["configuration"][field] = labels[key][field]
    return [Item.from_json(results[k]) for k in order if k in results]


def json_rows(rows: tuple[Row, ...]) -> list[dict]:
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


def write_figure(path: Path, png: bytes, provenance: dict) -> None:
    """A figure's PNG (RGB, as `vissim.validation.engine.figures.png_bytes` encodes it) written as it is, atomically,
    with its provenance sidecar."""
    write_png_bytes(path, png, provenance=provenance, overwrite=True)


def write_report_files(run_dir: Path, record: dict, *, title: str, metrics: dict, rows: tuple[Row, ...], tables_md: str,
                       figures: dict[str, Figure]) -> list[Path]:
    """metrics.json, metrics.csv, tables.md, the figures and report.html.

    ``figures``: name -> `Figure` (file name, PNG, alt text, provenance extras); each is written
    with its sidecar and linked from tables.md (a Markdown image with its alt text) and shown in
    report.html.
    """
    campaign = record
    provenance = report_provenance(run_dir, campaign, metrics["items"])
    written = [write_json_atomic(run_dir / "metrics.json", {**metrics, "provenance": provenance}, overwrite=True)]
    with atomic_output(run_dir / "metrics.csv", overwrite=True) as tmp:
        with open(tmp, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else ["configuration"])
            writer.writeheader()
            writer.writerows(rows)
    written.append(run_dir / "metrics.csv")
    source = campaign.get("source", "an unknown campaign file")
    made = (f"Made by vissim {provenance['vissim_version']} on {provenance['created_utc']} from {source}; "
            "every number in metrics.csv beside this page.")
    built = how_built(f"vissim validate {source} -o runs/{Path(str(source)).stem}", campaign, provenance)
    links = "".join(f"### {name}\n\n![{_markdown_alt(f.alt)}]({f.file_name})\n\n" for name, f in figures.items())
    description = campaign.get("description", "")
    text = f"# {title}\n\n{description}\n\n{tables_md}\n{links}{built}{made}\n"
    written.append(write_text_atomic(run_dir / "tables.md", text, overwrite=True))
    for name, figure in figures.items():  # the file holds the figure's bytes as they are: the page shows them
        write_figure(run_dir / figure.file_name, figure.png,
                     {**provenance, **figure.extra, "figure": name, "alt": figure.alt})
        written += [run_dir / figure.file_name, run_dir / f"{figure.file_name}.json"]
    page = html_report(title, tables_md + "\n" + built, figures, footer=made, description=description)
    written.append(write_text_atomic(run_dir / "report.html", page, overwrite=True))
    return written


def _markdown_alt(text: str) -> str:
    """Alt text inside ``![...]``: no brackets or line breaks."""
    return " ".join(text.replace("[", "(").replace("]", ")").split())


def write_report(run_dir: str | Path, progress: Progress | None = None,
                 record: dict | None = None) -> tuple[list[Path], list[str]]:
    """Write a run folder's report: metrics.json, metrics.csv, tables.md, its figures and report.html.

    The run's bench kind gives the rows, tables and figures (``progress(stage, done, total)``
    after each of its steps and the files, `vissim.progress`).  Returns the files written and
    the terminal summary's lines.
    """
    run_dir = Path(run_dir)
    record = read_record(run_dir) if record is None else record
    kind = bench_kind(record.get("kind", DEFAULT_KIND))
    results = load_results(run_dir, record)
    parts = kind.report(results, run_dir, record, progress)
    written = write_report_files(run_dir, record, title=parts.title,
                                 metrics={"items": [r.as_json() for r in results], "rows": json_rows(parts.rows)},
                                 rows=parts.rows, tables_md=parts.tables_md, figures=parts.figures)
    if progress is not None:
        progress("report", 1, 1)
    log.info("report of %d items written to %s", len(results), run_dir)
    return written, kind.summary_lines(parts.rows)