"""The depth bench's report: metric rows per region, Markdown tables and a figure per simulation.

Read from the finished items' ``result.json`` and images; `vissim.validation.engine.report`
writes the files.  Every region is reported
beside its noise floor (the two seeds of the render compared over the same pixels): a
perfect, noise-free simulation scores 3 dB above the floor's PSNR.  Occlusion bands are a row
of their own, so boundary errors are shown, not averaged away.
"""

from __future__ import annotations

import logging
import math
import textwrap
from pathlib import Path

import numpy as np

from vissim.imageio import read_image
from vissim.progress import counter
from vissim.validation.engine.figures import Figure, display_norm, png_bytes, pyplot, radiance_colorbar
from vissim.validation.engine.protocol import ReportParts
from vissim.validation.engine.metrics import (MEAN_ABS_DIFF, PSNR, SSIM, added_metrics, floor_column,
                                              metric_float)
from vissim.validation.engine.report import format_number as _fmt
from vissim.validation.engine.summary import PERFECT_MARGIN_DB

__all__ = ["depth_rows", "depth_tables", "depth_report", "summary_lines"]

log = logging.getLogger(__name__)

FIGURE_ROWS = 8


def depth_rows(results: list[dict]) -> list[dict]:
    """One flat row per (configuration, simulation, region)."""
    rows = []
    for result in results:
        config = result["configuration"]
        for comp in result["comparisons"]:
            for region, metrics in comp["regions"].items():
                floor = comp["noise_floor"][region]
                psnr, floor_psnr = metric_float(metrics[PSNR.name]), metric_float(floor[PSNR.name])
                rows.append({
                    "configuration": config["name"],
                    "observer": config["viewer_label"],
                    "simulation": comp["simulation"],
                    "region": region,
                    "n_px": metrics["n_px"],
                    PSNR.name: psnr,
                    floor_column(PSNR): floor_psnr,
                    "psnr_minus_floor_db": psnr - floor_psnr if math.isfinite(psnr) and math.isfinite(floor_psnr)
                    else math.nan,
                    SSIM.name: metric_float(metrics[SSIM.name]),
                    floor_column(SSIM): metric_float(floor[SSIM.name]),
                    MEAN_ABS_DIFF.name: metric_float(metrics[MEAN_ABS_DIFF.name]),
                    **{m.name: metric_float(metrics.get(m.name)) for m in added_metrics()},
                    "n_layers": comp["depth_blur"]["n_layers"],
                    "key": result["key"],
                })
    return rows


SUMMARY_REGIONS = ("all", "boundary", "frame")


def summary_table(results: list[dict]) -> str:
    """Configurations x simulations: PSNR minus the noise floor (dB) in all, boundary, frame and the worst interior."""
    rows = depth_rows(results)
    sims = list(dict.fromkeys(r["simulation"] for r in rows))
    header = ["configuration"] + [f"{sim}: {region}" for sim in sims for region in (*SUMMARY_REGIONS, "interiors (min)")]
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for result in results:
        mine = [r for r in rows if r["key"] == result["key"]]
        cells = [result["configuration"]["name"]]
        for sim in sims:
            by_region = {r["region"]: r for r in mine if r["simulation"] == sim}
            for region in SUMMARY_REGIONS:
                row = by_region.get(region)
                cells.append(_fmt(row["psnr_minus_floor_db"], 1) if row and row["n_px"] else "—")
            interior = [r["psnr_minus_floor_db"] for name, r in by_region.items()
                        if name not in (*SUMMARY_REGIONS, "sky") and math.isfinite(r["psnr_minus_floor_db"])]
            cells.append(_fmt(min(interior), 1) if interior else "—")
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def depth_tables(results: list[dict]) -> str:
    """A summary (margins over the floor), then per configuration a table of regions x (simulation PSNR,
    floor, margin, SSIM, mean |difference|)."""
    if not results:
        return "No finished items.\n"
    rows = depth_rows(results)
    out = ["### Summary: PSNR minus the noise floor (dB; +3 is a perfect, noise-free simulation)\n",
           summary_table(results),
           "`layered`: each panel rendered alone (radiance and coverage), composited per pupil ray "
           "(vissim.optics.depth.layered); `rgbd`: one all-in-focus image and its depth map "
           "(vissim.optics.depth.depth_map.blur_depth). Both simulate from inputs rendered beyond the frame by the "
           "scene's largest blur radius, cropped afterwards. `interiors (min)`: the worst panel interior "
           "(the sky, noise-free in the render, is left out).\n"]
    for result in results:
        name = result["configuration"]["name"]
        mine = [r for r in rows if r["key"] == result["key"]]
        sims = list(dict.fromkeys(r["simulation"] for r in mine))
        out.append(f"### {name}\n")
        blur = ", ".join(f"{p['name']} {_fmt(max(p['blur_diameter_arcmin']), 1)}'" for p in result["panels"])
        eye = result["equivalent_eye"]
        out.append(f"{result['configuration']['viewer_label']}; simulated as the eye {eye['prescription']} "
                   f"(pupil {eye['pupil_diameter_mm']:g} mm, A {eye['accommodation_diopters']:g} D); "
                   f"predicted blur diameters: {blur}.\n")
        if result.get("frame_margin_px"):
            out.append(f"Simulated from inputs {result['frame_margin_px']} px beyond each side of the frame.\n")
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
                cells += [_fmt(r[PSNR.name], 2), _fmt(r[floor_column(PSNR)], 2), _fmt(r["psnr_minus_floor_db"], 2),
                          _fmt(r[SSIM.name], 4), _fmt(r[floor_column(SSIM)], 4), _fmt(r[MEAN_ABS_DIFF.name], 4)]
            out.append("| " + " | ".join(cells) + " |")
        out.append("")
    out.append(
        "Regions: panel interiors are at least one blur radius (plus a margin) from any depth discontinuity and "
        "from the frame; `boundary` is the band around depth discontinuities (occlusion edges, panels against "
        "the sky), where the render mixes light from both sides and a layered simulation is least exact; `frame` "
        "is the border strip where the render sees beyond the image and the simulation pads it; `all` is the "
        "whole image. `geometric ...` is compared with the render, `wave ...` with the render convolved with the "
        "aperture's diffraction (Mitsuba renders none). The floor compares the two seeds' renders over the same "
        f"pixels: a perfect, noise-free simulation scores 10·log10(2) = +{PERFECT_MARGIN_DB:.2f} dB above it on "
        "average, not at most: each region's floor and score are measured once, over its own pixels, so where the "
        "first render's noise happens to be weaker than the second's a perfect simulation scores more, and the "
        "fewer the noisy pixels, the larger the swing.\n")
    return "\n".join(out)


def _panels_label(result: dict) -> str:
    """The panels' letters, LogMAR and distances: 'D at 0.4 m, Z at 0.9144 m; LogMAR 0.5'."""
    panels = [p for p in result.get("panels", []) if "letters" in p]  # absent from older results
    if not panels:
        return ""
    where = [f"{p['letters']} at {p['distance_left_m']:g}" + (
        "" if p["distance_left_m"] == p["distance_right_m"] else f"-{p['distance_right_m']:g}") + " m" for p in panels]
    logmars = sorted({p["logmar"] for p in panels})
    if len(logmars) == 1:
        return f"{', '.join(where)}; LogMAR {logmars[0]:.1f}"
    return ", ".join(f"{w} (LogMAR {p['logmar']:.1f})" for w, p in zip(where, panels))


def _region_names(result: dict) -> list[str]:
    """Names of the region labels 0, 1, 2... (``label_image`` of vissim.validation.depth.masks)."""
    return ["frame", "boundary"] + [r for r in result["masks"]["regions"] if r not in ("boundary", "frame")]


def _figure(results: list[dict], run_dir: Path, simulation: str) -> Figure | None:
    """Rows: configurations; columns: render (reference), simulation, |difference|, regions; with colour bars."""
    from matplotlib.colors import BoundaryNorm, ListedColormap, Normalize

    rows = [(r, next((c for c in r["comparisons"] if c["simulation"] == simulation), None)) for r in results]
    rows = [(r, c) for r, c in rows if c is not None][:FIGURE_ROWS]
    if not rows:
        return None
    ads = [read_image(run_dir / c["images"]["abs_diff_map"]).pixels for _, c in rows]
    ad_max = max(0.01, max(float(np.percentile(a, 99.5)) for a in ads))
    fig, axes = pyplot.subplots(len(rows), 4, figsize=(13.0, 2.3 * len(rows) + 1.2), squeeze=False, layout="constrained")
    shown = []
    for i, ((result, comp), ad) in enumerate(zip(rows, ads)):
        truth = read_image(run_dir / result["images"][comp["reference_image"]]).pixels
        sim = read_image(run_dir / comp["images"]["simulation"]).pixels
        regions = read_image(run_dir / result["images"]["regions"]).pixels
        names = _region_names(result)
        names += [f"region {k}" for k in range(len(names), int(regions.max()) + 1)]
        palette = pyplot.get_cmap("tab10" if len(names) <= 10 else "tab20").colors
        panels = [(truth, "gray", display_norm(), "render"),
                  (sim, "gray", display_norm(), f"{simulation} simulation"),
                  (ad, "magma", Normalize(0, ad_max), "|difference|"),
                  (regions, ListedColormap(palette[: len(names)]), BoundaryNorm(np.arange(len(names) + 1) - 0.5,
                                                                                 len(names)), "regions")]
        for j, (img, cmap, norm, label) in enumerate(panels):
            ax = axes[i, j]
            image = ax.imshow(img, cmap=cmap, norm=norm, interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(label, fontsize=9)
                shown.append(image)
        bar = fig.colorbar(image, ax=axes[i, 3], location="right", pad=0.01, aspect=12)
        bar.set_ticks(range(len(names)), labels=names)
        bar.ax.tick_params(labelsize=6)
        interior = [r for r in comp["regions"] if r not in ("boundary", "frame", "all")]
        psnr = ", ".join(f"{r} {_fmt(metric_float(comp['regions'][r][PSNR.name]), 1)}" for r in interior[:3])
        axes[i, 0].set_ylabel(textwrap.fill(result["configuration"]["name"], 28), fontsize=7)
        axes[i, 0].set_xlabel(_panels_label(result), fontsize=7)
        axes[i, 2].set_xlabel(f"PSNR dB: {psnr}; boundary {_fmt(metric_float(comp['regions']['boundary'][PSNR.name]), 1)}",
                              fontsize=7)
    for j in range(3):
        bar = fig.colorbar(shown[j], ax=axes[:, j], location="bottom", shrink=0.9, aspect=30, pad=0.01)
        bar.ax.tick_params(labelsize=7)
        if j < 2:
            radiance_colorbar(bar)
        else:
            bar.set_label("|difference| (relative radiance, linear)", fontsize=8)
    fig.suptitle(f"depth campaign: {simulation} blur_depth against the render", fontsize=10)
    alt = (f"The depth campaign's {simulation} simulation against the render, one row per configuration "
           f"({'; '.join(r['configuration']['name'] for r, _ in rows)}); columns: the render, the simulation, "
           "the absolute difference and the map of regions (frame, occlusion boundary, panels), with each "
           "row's PSNR per region.")
    return Figure("", png_bytes(fig), alt)


def depth_report(results: list[dict], run_dir: Path, record: dict, progress=None) -> ReportParts:
    """The depth report's rows, tables and a figure per simulation (``progress`` after each figure)."""
    rows = depth_rows(results)
    figures = {}
    simulations = list(dict.fromkeys(r["simulation"] for r in rows))
    advance = counter(progress, "figures", len(simulations))
    for simulation in simulations:
        figure = _figure(results, run_dir, simulation)
        if figure is not None:
            name = simulation.replace(" ", "_")
            figures[f"{simulation} simulation against the render"] = figure._replace(file_name=f"figure_depth_{name}.png")
        advance()
    title = f"vissim depth validation: {record.get('name', run_dir.name)}"
    return ReportParts(title, rows, depth_tables(results), figures)

def summary_lines(rows: list[dict]) -> list[str]:
    """A terminal summary: one line per (configuration, simulation, region)."""
    lines = [f"{'configuration':40s} {'simulation':>16s} {'region':>16s} {'PSNR dB':>8s} {'floor dB':>8s} {'SSIM':>7s}"]
    for r in rows:
        lines.append(f"{r['configuration'][:40]:40s} {r['simulation']:>16s} {r['region'][:16]:>16s} "
                     f"{_fmt(r[PSNR.name], 2):>8s} {_fmt(r[floor_column(PSNR)], 2):>8s} {_fmt(r[SSIM.name], 4):>7s}")
    return lines