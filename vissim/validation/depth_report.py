"""Report of a depth campaign run: metrics (JSON, CSV), Markdown tables, figures, HTML.

Rebuilt from the finished items' ``result.json`` and images (:mod:`vissim.validation.depth_campaign`),
like :mod:`vissim.validation.report` for the single-plane harness.  Every region is reported
beside its noise floor (the two seeds of the render compared over the same pixels): a
perfect, noise-free simulation scores 3 dB above the floor's PSNR.  Occlusion bands are a row
of their own, so boundary errors are shown, not averaged away.
"""

from __future__ import annotations

import io
import json
import logging
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vissim.imageio import read_image, srgb_encode  # noqa: E402
from vissim.validation.report import _num, campaign_name, load_results, write_report_files  # noqa: E402
from vissim.validation.report import format_number as _fmt  # noqa: E402

__all__ = ["current_results", "depth_rows", "depth_tables", "build_depth_report", "depth_summary_lines"]

log = logging.getLogger(__name__)

FIGURE_ROWS = 8


def current_results(run_dir: str | Path) -> list[dict]:
    """The finished items of the campaign last run into ``run_dir`` (items of earlier settings left out)."""
    run_dir = Path(run_dir)
    results = load_results(run_dir)
    order_file = run_dir / "campaign.json"
    if not order_file.exists():
        return results
    keys = set(json.loads(order_file.read_text())["items"])
    return [r for r in results if r["key"] in keys]


def depth_rows(results: list[dict]) -> list[dict]:
    """One flat row per (configuration, simulation, region)."""
    rows = []
    for result in results:
        config = result["configuration"]
        for comp in result["comparisons"]:
            for region, metrics in comp["regions"].items():
                floor = comp["noise_floor"][region]
                psnr, floor_psnr = _num(metrics["psnr_db"]), _num(floor["psnr_db"])
                rows.append({
                    "configuration": config["name"],
                    "observer": config["viewer_label"],
                    "simulation": comp["simulation"],
                    "region": region,
                    "n_px": metrics["n_px"],
                    "psnr_db": psnr,
                    "noise_floor_psnr_db": floor_psnr,
                    "psnr_minus_floor_db": psnr - floor_psnr if math.isfinite(psnr) and math.isfinite(floor_psnr)
                    else math.nan,
                    "ssim": _num(metrics["ssim"]),
                    "noise_floor_ssim": _num(floor["ssim"]),
                    "mean_abs_diff": _num(metrics["mean_abs_diff"]),
                    "n_layers": comp["depth_blur"]["n_layers"],
                    "key": result["key"],
                })
    return rows


def depth_tables(results: list[dict]) -> str:
    """Per configuration: a table of regions x (simulation PSNR, floor, margin, SSIM, mean |difference|)."""
    if not results:
        return "No finished items.\n"
    rows = depth_rows(results)
    out = []
    for result in results:
        name = result["configuration"]["name"]
        mine = [r for r in rows if r["key"] == result["key"]]
        sims = list(dict.fromkeys(r["simulation"] for r in mine))
        out.append(f"### {name}\n")
        blur = ", ".join(f"{p['name']} {_fmt(max(p['blur_diameter_arcmin']), 1)}'" for p in result["panels"])
        eye = result["equivalent_eye"]
        out.append(f"{result['configuration']['viewer_label']}; simulated as the eye {eye['prescription']} "
                   f"(pupil {eye['pupil_diameter_mm']:g} mm, A {eye['accommodation_d']:g} D); "
                   f"predicted blur diameters: {blur}.\n")
        header = ["region", "pixels"]
        for sim in sims:
            header += [f"{sim} PSNR dB", "floor dB", "margin dB", f"{sim} SSIM", "floor SSIM", "mean AD"]
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "---|" * len(header))
        for region in dict.fromkeys(r["region"] for r in mine):
            cells = [region]
            for sim in sims:
                r = next(x for x in mine if x["simulation"] == sim and x["region"] == region)
                if len(cells) == 1:
                    cells.append(str(r["n_px"]))
                cells += [_fmt(r["psnr_db"], 2), _fmt(r["noise_floor_psnr_db"], 2), _fmt(r["psnr_minus_floor_db"], 2),
                          _fmt(r["ssim"], 4), _fmt(r["noise_floor_ssim"], 4), _fmt(r["mean_abs_diff"], 4)]
            out.append("| " + " | ".join(cells) + " |")
        out.append("")
    out.append(
        "Regions: panel interiors are at least one blur radius (plus a margin) from any depth discontinuity and "
        "from the frame; `boundary` is the band around depth discontinuities (occlusion edges, panels against "
        "the sky), where the render mixes light from both sides and a layered simulation is least exact; `frame` "
        "is the border strip where the render sees beyond the image and the simulation pads it; `all` is the "
        "whole image. `geometric` is compared with the render, `wave` with the render convolved with the "
        "aperture's diffraction (Mitsuba renders none). The floor compares the two seeds' renders over the same "
        "pixels: a perfect, noise-free simulation scores +3 dB above it (margin 3.0).\n")
    return "\n".join(out)


def _figure(results: list[dict], run_dir: Path, simulation: str) -> bytes | None:
    """Rows: configurations; columns: render (reference), simulation, |difference|, regions."""
    rows = [(r, next((c for c in r["comparisons"] if c["simulation"] == simulation), None)) for r in results]
    rows = [(r, c) for r, c in rows if c is not None][:FIGURE_ROWS]
    if not rows:
        return None
    ads = [read_image(run_dir / c["images"]["abs_diff_map"]).pixels for _, c in rows]
    ad_max = max(0.01, max(float(np.percentile(a, 99.5)) for a in ads))
    fig, axes = plt.subplots(len(rows), 4, figsize=(12.0, 2.2 * len(rows) + 0.6), squeeze=False)
    for i, ((result, comp), ad) in enumerate(zip(rows, ads)):
        truth = read_image(run_dir / result["images"][comp["reference_image"]]).pixels
        sim = read_image(run_dir / comp["images"]["simulation"]).pixels
        regions = read_image(run_dir / result["images"]["regions"]).pixels
        panels = [(srgb_encode(np.clip(truth, 0, 1)), "gray", 0, 1, "render"),
                  (srgb_encode(np.clip(sim, 0, 1)), "gray", 0, 1, f"{simulation} simulation"),
                  (ad, "magma", 0, ad_max, f"|difference| (0-{ad_max:.3f})"),
                  (regions, "tab10", 0, 9, "regions (0 frame, 1 boundary)")]
        for j, (img, cmap, lo, hi, label) in enumerate(panels):
            ax = axes[i, j]
            ax.imshow(img, cmap=cmap, vmin=lo, vmax=hi, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(label, fontsize=9)
        interior = [r for r in comp["regions"] if r not in ("boundary", "frame", "all")]
        psnr = ", ".join(f"{r} {_fmt(_num(comp['regions'][r]['psnr_db']), 1)}" for r in interior[:3])
        axes[i, 0].set_ylabel(result["configuration"]["name"][:38], fontsize=7)
        axes[i, 2].set_xlabel(f"PSNR dB: {psnr}; boundary {_fmt(_num(comp['regions']['boundary']['psnr_db']), 1)}",
                              fontsize=7)
    fig.suptitle(f"depth campaign: {simulation} blur_depth against the render", fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    plt.close(fig)
    return buffer.getvalue()


def build_depth_report(run_dir: str | Path) -> list[Path]:
    """Write metrics.json, metrics.csv, tables.md, figure_depth_*.png and report.html into ``run_dir``."""
    run_dir = Path(run_dir)
    results = current_results(run_dir)
    rows = depth_rows(results)
    figures = {}
    for simulation in ("geometric", "wave"):
        png = _figure(results, run_dir, simulation)
        if png is not None:
            figures[f"{simulation} simulation against the render"] = (f"figure_depth_{simulation}.png", png)
    written = write_report_files(run_dir, title=f"vissim depth validation: {campaign_name(run_dir)}",
                                 metrics={"items": results, "rows": _json_rows(rows)}, rows=rows,
                                 tables_md=depth_tables(results), figures=figures)
    log.info("depth report of %d items written to %s", len(results), run_dir)
    return written


def _json_rows(rows: list[dict]) -> list[dict]:
    return [{k: (v if not isinstance(v, float) or math.isfinite(v) else ("inf" if v > 0 else None if math.isnan(v)
             else "-inf")) for k, v in row.items()} for row in rows]


def depth_summary_lines(run_dir: str | Path) -> list[str]:
    """A terminal summary: one line per (configuration, simulation, region)."""
    lines = [f"{'configuration':40s} {'simulation':>10s} {'region':>16s} {'PSNR dB':>8s} {'floor dB':>8s} {'SSIM':>7s}"]
    for r in depth_rows(current_results(run_dir)):
        lines.append(f"{r['configuration'][:40]:40s} {r['simulation']:>10s} {r['region'][:16]:>16s} "
                     f"{_fmt(r['psnr_db'], 2):>8s} {_fmt(r['noise_floor_psnr_db'], 2):>8s} {_fmt(r['ssim'], 4):>7s}")
    return lines
