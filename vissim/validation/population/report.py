"""A population run's files: each eye's numbers, their quantiles, the gap table and the MTF fan chart.

* ``eyes.csv``: one row per eye and condition (`vissim.optics.eyes.measured.population.EyeResult`).
* ``quantiles.json``: per condition, the 5/25/50/75/95 % quantiles across the eyes.
* ``gap.md``: the population's MTF beside the Navarro schematic eye's and the published human fits
  (`vissim.optics.eyes.measured.published`), each with its conditions: orders included, correction, light,
  and whether scatter is in it (double-pass measurements include it; wavefronts do not).
* ``figure_mtf.png``: per condition, the population's median MTF with its 25-75 % and 5-95 % bands, the
  schematic eye's and the published curves that share its conditions.
* ``figure_astigmatism.png`` (three or more fields on the horizontal meridian): the cylinder, 2√(J0² + J45²),
  against field: the population's median and quartiles beside every schematic eye's, each over the pupil seen
  along the chief ray.

Every file is written atomically with the run's provenance (`write_population_run`).
"""

from __future__ import annotations

import csv
import functools
import io
from pathlib import Path

import numpy as np

from vissim.atomic import refuse_existing, write_json_atomic, write_text_atomic
from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.measured_eye import BASE_EYE_MODEL
from vissim.optics.eyes.measured.population import QUANTILES, population_quantiles, schematic_mtf
from vissim.optics.eyes.measured.published import (ARTAL_NAVARRO_1994, NAVARRO_1993, NAVARRO_1993_PUPIL_MM,
                                                   WATSON_2013_PUPILS_MM, artal_navarro_1994_mtf, navarro_1993_mtf,
                                                   watson_2013_mtf)

__all__ = ["write_population_run", "gap_table_md", "published_curves", "population_report", "summary_lines"]

SCHEMATIC = BASE_EYE_MODEL  # the schematic eye set beside the measured ones: the one they are built on


def _schematic_curve(condition, frequencies) -> np.ndarray:
    """The schematic eye's MTF under ``condition`` (`schematic_mtf`), traced once for the gap table and the fan."""
    return _schematic_curve_cached(condition, tuple(float(f) for f in frequencies))


@functools.lru_cache(maxsize=32)
def _schematic_curve_cached(condition, frequencies: tuple) -> np.ndarray:
    from vissim.optics.eyes.models import eye_model

    curve = schematic_mtf(eye_model(SCHEMATIC), condition, frequencies)
    curve.setflags(write=False)
    return curve


def published_curves(condition, frequencies) -> dict:
    """{label: MTF} of the published fits whose conditions ``condition`` matches (pupil, field; module doc)."""
    curves = {}
    if condition.correction != "sphero-cylinder":  # every fit is of eyes with their refraction corrected
        return curves
    pupil, (x, y) = condition.pupil_mm, condition.field_deg
    at_fovea = x == 0.0 and y == 0.0
    low, high = WATSON_2013_PUPILS_MM
    if at_fovea and low <= pupil <= high:
        curves["Watson 2013 (wavefronts, orders >= 3, 555 nm)"] = watson_2013_mtf(frequencies, pupil)
    if at_fovea and pupil in ARTAL_NAVARRO_1994:
        curves["Artal & Navarro 1994 (double-pass: scatter in)"] = artal_navarro_1994_mtf(frequencies, pupil)
    eccentricity = float(np.hypot(x, y))
    if pupil == NAVARRO_1993_PUPIL_MM and eccentricity in NAVARRO_1993 and eccentricity > 0:
        curves["Navarro et al. 1993 (double-pass: scatter in)"] = navarro_1993_mtf(frequencies, eccentricity)
    return curves


def _eye_rows(results, frequencies) -> list[dict]:
    """One row per eye and condition: ``eyes.csv``'s, and (the condition as its configuration) the campaign's."""
    rows = []
    for r in results:
        c = r.condition
        rows.append({"eye": r.eye.name, "condition": c.label, "pupil_mm": c.pupil_mm, "field_x_deg": c.field_deg[0],
                     "field_y_deg": c.field_deg[1], "wavelength_nm": c.wavelength_nm, "correction": str(c.correction),
                     "strehl": r.strehl, "m_diopters": r.m_diopters, "j0_diopters": r.j0_diopters,
                     "j45_diopters": r.j45_diopters, "higher_order_rms_um": r.higher_order_rms_um,
                     **{f"mtf_{f:g}_cyc_per_deg": float(v) for f, v in zip(frequencies, r.mtf)}})
    return rows


def _eyes_csv(results, frequencies) -> str:
    rows = _eye_rows(results, frequencies)
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return out.getvalue()


def gap_table_md(results, conditions, frequencies) -> str:
    """The gap table (module doc): one block per condition, one row per source, one column per frequency."""
    summary = population_quantiles(results)
    head = "| source | " + " | ".join(f"{f:g} c/deg" for f in frequencies) + " |"
    rule = "|---|" + "---|" * len(frequencies)
    lines = ["# Measured eyes beside schematic eyes and published human MTFs", "",
             "MTFs computed from wavefronts hold no scatter; double-pass MTFs include it, so they lie lower at the "
             "same optics. Population: median [25-75 %] across its eyes.", ""]
    for condition in conditions:
        table = summary.get(condition.label)
        if table is None or "mtf" not in table:
            continue
        lines += [f"## {condition.label} ({table['count']} eyes)", "", head, rule]
        low, mid, high = (table["mtf"][QUANTILES.index(q)] for q in (0.25, 0.5, 0.75))
        cells = [f"{m:.3f} [{a:.3f}-{b:.3f}]" for a, m, b in zip(low, mid, high)]
        lines.append("| population (wavefronts) | " + " | ".join(cells) + " |")
        schematic = _schematic_curve(condition, frequencies)
        lines.append(f"| {SCHEMATIC} schematic eye (traced) | " + " | ".join(f"{v:.3f}" for v in schematic) + " |")
        for label, curve in published_curves(condition, frequencies).items():
            lines.append(f"| {label} | " + " | ".join(f"{v:.3f}" for v in curve) + " |")
        lines.append("")
    return "\n".join(lines)


def _fan_chart(results, conditions, frequencies) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot

    from vissim.validation.engine.figures import png_bytes

    summary = population_quantiles(results)
    shown = [c for c in conditions if c.label in summary and "mtf" in summary[c.label]]
    fig, axes = pyplot.subplots(1, len(shown), figsize=(4.6 * len(shown), 3.8), squeeze=False)
    for ax, condition in zip(axes[0], shown):
        mtf = summary[condition.label]["mtf"]
        ax.fill_between(frequencies, mtf[0], mtf[4], color="tab:blue", alpha=0.15, label="population 5-95 %")
        ax.fill_between(frequencies, mtf[1], mtf[3], color="tab:blue", alpha=0.35, label="25-75 %")
        ax.plot(frequencies, mtf[2], color="tab:blue", lw=2, label="median")
        ax.plot(frequencies, _schematic_curve(condition, frequencies), color="k", lw=1.2, label=SCHEMATIC)
        for (label, curve), style in zip(published_curves(condition, frequencies).items(), ("--", ":", "-.")):
            ax.plot(frequencies, curve, style, color="tab:red", label=label)
        ax.set_title(f"{condition.label}\n({summary[condition.label]['count']} eyes)", fontsize=8)
        ax.set_xlabel("cycles/deg")
        ax.set_ylabel("MTF")
        ax.set_ylim(0, 1)
        ax.legend(fontsize=6)
    fig.tight_layout()
    return png_bytes(fig)


def _meridian(conditions) -> list:
    """The horizontal-meridian conditions sharing the first one's pupil, light and correction, by field x."""
    if not conditions:
        return []
    first = conditions[0]
    same = [c for c in conditions if c.field_deg[1] == 0.0 and
            (c.pupil_mm, c.wavelength_nm, c.correction) == (first.pupil_mm, first.wavelength_nm, first.correction)]
    return sorted(same, key=lambda c: c.field_deg[0])


def _cylinder(j0: float, j45: float) -> float:
    """The cylinder's magnitude, dioptres: 2 √(J0² + J45²) (Thibos et al. 1997)."""
    return 2.0 * float(np.hypot(j0, j45))


def _astigmatism_chart(results, meridian) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot

    from vissim.optics.eyes.measured.population import schematic_refraction
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.models import EYE_MODELS
    from vissim.validation.engine.figures import png_bytes

    x = np.array([c.field_deg[0] for c in meridian])
    bands = np.array([np.quantile([_cylinder(r.j0_diopters, r.j45_diopters) for r in results if r.condition == c],
                                  (0.25, 0.5, 0.75)) for c in meridian])
    fig, ax = pyplot.subplots(figsize=(6.4, 4.2))
    ax.fill_between(x, bands[:, 0], bands[:, 2], color="tab:blue", alpha=0.3, label="measured eyes 25-75 %")
    ax.plot(x, bands[:, 1], color="tab:blue", lw=2, label="measured eyes, median")
    for model in EYE_MODELS:
        try:
            values = [_cylinder(*schematic_refraction(eye_model(model), c)[1:]) for c in meridian]
        except VissimInputError:  # a field the model's rays do not reach
            continue
        ax.plot(x, values, lw=1, label=model)
    c = meridian[0]
    ax.set_title(f"Astigmatism across the horizontal field: {c.pupil_mm:g} mm, {c.wavelength_nm:g} nm, the pupil "
                 "seen along the chief ray", fontsize=8)
    ax.set_xlabel("field x, deg (examiner's right)")
    ax.set_ylabel("cylinder, D")
    ax.legend(fontsize=6)
    fig.tight_layout()
    return png_bytes(fig)


MOSAIC_EYES = 16  # the letter mosaic's eyes: evenly spaced in rank of Strehl ratio


def _letter_mosaic(results, condition) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot

    from vissim.charts import optotype_tile
    from vissim.optics.eyes.defaults import (DEFAULT_CHART_DISTANCE_M, DEFAULT_LETTER, POPULATION_ARCMIN_PER_PX,
                                             POPULATION_LETTER_LOGMAR, POPULATION_LETTER_SIZE_PX)
    from vissim.optics.eyes.measured.population import seen_image
    from vissim.validation.engine.figures import png_bytes

    size = POPULATION_LETTER_SIZE_PX
    letter = optotype_tile(DEFAULT_LETTER, POPULATION_LETTER_LOGMAR, arcmin_per_px=POPULATION_ARCMIN_PER_PX,
                           size_px=(size, size), viewing_distance_m=DEFAULT_CHART_DISTANCE_M,
                           snap_to_pixels=False).pixels

    ranked = sorted((r for r in results if r.condition == condition), key=lambda r: r.strehl)
    picks = [ranked[i] for i in sorted(set(np.linspace(0, len(ranked) - 1, MOSAIC_EYES).round().astype(int)))]
    side = int(np.ceil(np.sqrt(len(picks))))
    fig, axes = pyplot.subplots(side, side, figsize=(1.9 * side, 2.05 * side), squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, r in zip(axes.flat, picks):
        seen = seen_image(r.eye, condition, letter, POPULATION_ARCMIN_PER_PX)
        ax.imshow(seen, cmap="gray", vmin=0, vmax=1)
        ax.set_title(f"{r.eye.subject} {r.eye.eye}: Strehl {r.strehl:.2f}", fontsize=7)
    fig.suptitle(f"{DEFAULT_LETTER} at LogMAR {POPULATION_LETTER_LOGMAR:g} through {len(picks)} of {len(ranked)} eyes, "
                 f"lowest to highest Strehl ratio ({condition.label})", fontsize=8)
    fig.tight_layout()
    return png_bytes(fig)


def _figures(results, conditions, frequencies) -> list:
    """The run's figures (module doc), as `vissim.validation.engine.figures.Figure`s."""
    from vissim.validation.engine.figures import Figure

    figures = [Figure("figure_letters.png", _letter_mosaic(results, results[0].condition),
                      f"a letter seen through 16 of the eyes ({results[0].condition.label})")]
    if len(frequencies):
        figures.append(Figure("figure_mtf.png", _fan_chart(results, conditions, frequencies),
                              "the population's MTF (median, 25-75 % and 5-95 %) beside the schematic eye and the "
                              "published human MTFs"))
    meridian = _meridian(list(conditions))
    if len(meridian) >= 3:
        figures.append(Figure("figure_astigmatism.png", _astigmatism_chart(results, meridian),
                              "cylinder against field: the population's median and quartiles beside every schematic "
                              "eye"))
    return figures


def population_run_files(conditions, frequencies) -> list[str]:
    """The names of the files `write_population_run` writes for ``conditions`` at ``frequencies``: known before any
    eye is evaluated, so that a run folder holding them is refused before the work."""
    names = ["eyes.csv", "quantiles.json", "figure_letters.png"]
    names += ["gap.md", "figure_mtf.png"] if np.asarray(frequencies, dtype=float).size else []
    return names + (["figure_astigmatism.png"] if len(_meridian(list(conditions))) >= 3 else [])


def write_population_run(run_dir: Path, results, conditions, frequencies, provenance: dict, *,
                         overwrite: bool = False) -> list[Path]:
    """The run's files (module doc) in ``run_dir``; each written atomically, the figures with their provenance."""
    from vissim.validation.engine.report import write_figure

    if not results:
        raise VissimInputError("no eye of the population was measured under any condition given")
    run_dir = Path(run_dir)
    frequencies = np.asarray(frequencies, dtype=float)
    summary = {label: {k: np.asarray(v).tolist() if k != "count" else v for k, v in table.items()}
               for label, table in population_quantiles(results).items()}
    names = population_run_files(conditions, frequencies)
    refuse_existing(*(run_dir / name for name in names), overwrite=overwrite)  # before anything is written
    written = [write_text_atomic(run_dir / "eyes.csv", _eyes_csv(results, frequencies), overwrite=overwrite),
               write_json_atomic(run_dir / "quantiles.json", {"quantiles": list(QUANTILES), "frequencies_cyc_per_deg":
                                                              frequencies.tolist(), "conditions": summary,
                                                              "provenance": provenance}, overwrite=overwrite)]
    if frequencies.size:
        written.append(write_text_atomic(run_dir / "gap.md", gap_table_md(results, conditions, frequencies),
                                         overwrite=overwrite))
    for figure in _figures(results, conditions, frequencies):
        write_figure(run_dir / figure.file_name, figure.png, provenance)
        written.append(run_dir / figure.file_name)
    return written


# -- the population as a campaign kind (`vissim.validation.population.kind`) ------------------------------------
def _medians_md(results, conditions) -> str:
    summary = population_quantiles(results)
    lines = ["## Per condition (median [25-75 %] across the eyes)", "",
             "| condition | eyes | Strehl | M D | J0 D | J45 D | higher-order RMS um |", "|---|---|---|---|---|---|---|"]
    middle = [QUANTILES.index(q) for q in (0.5, 0.25, 0.75)]
    for condition in conditions:
        table = summary.get(condition.label)
        if table is None:
            continue
        cells = [f"{table[k][middle[0]]:.3f} [{table[k][middle[1]]:.3f}-{table[k][middle[2]]:.3f}]"
                 for k in ("strehl", "m_diopters", "j0_diopters", "j45_diopters", "higher_order_rms_um")]
        lines.append(f"| {condition.label} | {table['count']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n\n"


def population_report(items, record: dict):
    """The engine's `ReportParts` of a population campaign's finished items (one per condition)."""
    from vissim.optics.eyes.measured.population import EyeResult, PopulationCondition
    from vissim.validation.engine.protocol import ReportParts

    items = list(items)
    conditions = [PopulationCondition.from_json(item["configuration"]) for item in items]
    results = [EyeResult.from_json(r) for item in items for r in item["eyes"]]
    frequencies = np.asarray(record["settings"]["mtf_cyc_per_deg"], dtype=float)
    if not results:
        raise VissimInputError("no eye of the population was measured under any condition given")
    tables = (f"Every eye of the selection ({items[0]['eyes_selected']} eyes of {record['settings']['dataset']}) under "
              "each condition, from its measured wavefront (orders 2 and up: the data's; a correction removes what "
              "it corrects); an eye not measured at a condition's field is left out of it. M, J0 and J45: the eye's "
              "own refraction over the pupil (minimum RMS).\n\n" + _medians_md(results, conditions))
    if frequencies.size:
        tables += gap_table_md(results, conditions, frequencies).split("\n", 1)[1]
    figures = {figure.file_name: figure for figure in _figures(results, conditions, frequencies)}
    rows = [{"configuration": row.pop("condition"), **row} for row in _eye_rows(results, frequencies)]
    return ReportParts("measured-eye population", rows, tables, figures)


def summary_lines(rows) -> list[str]:
    """A line per condition: its eyes and their median Strehl ratio."""
    lines = []
    for label in dict.fromkeys(r["configuration"] for r in rows):
        strehl = [r["strehl"] for r in rows if r["configuration"] == label]
        lines.append(f"{label}: {len(strehl)} eyes, median Strehl ratio {float(np.median(strehl)):.3f}")
    return lines

