"""Thesis-style figures and the Markdown/HTML report of ATV analyses (thesis Figs 5.5-5.8).

Figures (matplotlib Agg): per curve, the measured points (green), the fitted parabola (blue),
its pointwise confidence band (red dashed), the vertex (blue circle, with the Fieller interval
as a horizontal bar) and the measured spherical equivalent (black vertical line), as in
Figs 5.7-5.8; and an overview in the style of Fig. 5.5 (blue with drops, red without; dashed
right eye, solid left; circles at each curve's least measured value; black lines at the SE).
"""

from __future__ import annotations

import html
import logging
import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from vissim.checks import ATV_PARABOLA_WINDOW_DIOPTERS
from vissim.atomic import atomic_output, write_json_atomic, write_text_atomic  # noqa: E402
from vissim.atv.analysis import CONDITION_LABELS, CurveAnalysis  # noqa: E402
from vissim.atv.data import Discrepancy  # noqa: E402
from vissim.imageio import PNG_COMPRESS_LEVEL  # noqa: E402
from vissim.provenance import json_safe  # noqa: E402

__all__ = ["plot_fits", "plot_overview", "summary_rows", "report_pages", "write_report"]

log = logging.getLogger(__name__)

FIGURE_DPI = 80
_EYE_NAME = {"R": "right eye", "L": "left eye"}


def _save(fig, path: Path, overwrite: bool) -> Path:
    fig.tight_layout()
    with atomic_output(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, dpi=FIGURE_DPI, format="png", metadata={"Software": None},
                    pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    plt.close(fig)
    return path


def _draw_fit(ax, analysis: CurveAnalysis) -> None:
    x = np.asarray(analysis.lens_diopters)
    grid = np.linspace(min(x.min(), -5.0), max(x.max(), 5.0), 301)
    lo, hi = analysis.fit.band(grid, analysis.level)
    y = np.asarray(analysis.minimum_visible_code)
    used = np.asarray(analysis.used_in_fit, dtype=bool) if analysis.used_in_fit else np.ones(x.shape, dtype=bool)
    ax.plot(x[used], y[used], "o", color="tab:green", ms=4, label="minimum visible")
    if not used.all():
        ax.plot(x[~used], y[~used], "o", color="tab:green", mfc="none", ms=4, label="not fitted")
    ax.plot(grid, analysis.fit.predict(grid), "-", color="tab:blue", lw=1.5, label="quadratic fit")
    ax.plot(grid, lo, "--", color="tab:red", lw=1, label=f"{100 * analysis.level:.0f} % band (mean)")
    ax.plot(grid, hi, "--", color="tab:red", lw=1)
    if analysis.vertex_diopters is not None:
        v = analysis.vertex_diopters
        y = float(analysis.fit.predict(v))
        ci = analysis.vertex_interval
        if ci.bounded:
            ax.errorbar([v], [y], xerr=[[v - ci.lower_diopters], [ci.upper_diopters - v]], fmt="o", color="tab:blue",
                        mfc="white", ms=6, capsize=3, label=f"vertex {v:+.2f} D (Fieller CI)")
        else:
            ax.plot([v], [y], "o", color="tab:blue", mfc="white", ms=6, label=f"vertex {v:+.2f} D (CI unbounded)")
    if analysis.measured_se_diopters is not None:
        ax.axvline(analysis.measured_se_diopters, color="black", lw=1.2, label=f"SE {analysis.measured_se_diopters:+.3f} D")
    ax.set_xlabel("trial lens power (D)")
    ax.set_ylabel("minimum visible (display code value)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper center")


def plot_fits(
    analyses: Sequence[CurveAnalysis],
    path: str | Path,
    *,
    title: str = "",
    panel_titles: Sequence[str] | None = None,
    overwrite: bool = False,
) -> Path:
    """One panel per curve: rows = conditions, columns = eyes (Figs 5.7-5.8); with
    ``panel_titles``, one row of panels in the given order."""
    if panel_titles is not None:
        cells = [(0, i) for i in range(len(analyses))]
        shape = (1, len(analyses))
        titles = list(panel_titles)
    else:
        conditions = list(dict.fromkeys(a.condition for a in analyses))
        eyes = list(dict.fromkeys(a.eye for a in analyses))
        cells = [(conditions.index(a.condition), eyes.index(a.eye)) for a in analyses]
        shape = (len(conditions), len(eyes))
        titles = [f"{_EYE_NAME.get(a.eye, a.eye)}, {CONDITION_LABELS.get(a.condition, a.condition)}" for a in analyses]
    fig, axes = plt.subplots(*shape, figsize=(4.6 * shape[1], 3.6 * shape[0]), squeeze=False, sharey=True)
    for a, (row, col), panel_title in zip(analyses, cells, titles):
        ax = axes[row, col]
        _draw_fit(ax, a)
        ax.set_title(panel_title, fontsize=9)
    if title:
        fig.suptitle(title, fontsize=11)
    return _save(fig, Path(path), overwrite)


def plot_overview(analyses: Sequence[CurveAnalysis], path: str | Path, *, title: str = "", overwrite: bool = False) -> Path:
    """All curves on one axis in the style of Fig. 5.5."""
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    colours = {"with_drops": "tab:blue", "without_drops": "tab:red"}
    ses = {}
    for a in analyses:
        style = "--" if a.eye == "R" else "-"
        colour = colours.get(a.condition, "tab:gray")
        ax.plot(a.lens_diopters, a.minimum_visible_code, style, color=colour, lw=1.3,
                label=f"{_EYE_NAME.get(a.eye, a.eye)}, {a.condition.replace('_', ' ')}")
        i = int(np.argmin(a.minimum_visible_code))
        ax.plot([a.lens_diopters[i]], [a.minimum_visible_code[i]], "o", color=colour, mfc="none", ms=9)
        if a.measured_se_diopters is not None:
            ses[a.eye] = a.measured_se_diopters
    for eye, se in ses.items():
        ax.axvline(se, color="black", ls="--" if eye == "R" else "-", lw=1)
    ax.set_xlabel("trial lens power (D)")
    ax.set_ylabel("minimum visible (display code value)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=10)
    return _save(fig, Path(path), overwrite)


def _fmt(value, spec: str = "+.2f", none: str = "–") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return none
    return format(value, spec)


def summary_rows(analyses: Sequence[CurveAnalysis]) -> list[dict]:
    """One row of strings per curve, shared by the Markdown and HTML tables."""
    rows = []
    for a in analyses:
        within = a.se_within_interval
        rows.append({
            "subject": a.subject_id,
            "eye": _EYE_NAME.get(a.eye, a.eye),
            "condition": a.condition.replace("_", " "),
            "fit": "all lenses" if a.window_diopters is None else f"±{a.window_diopters:g} D window",
            "points fitted": f"{a.fit.n_points}/{len(a.lens_diopters)}",
            "a (code/D²)": _fmt(a.fit.a, ".4f"),
            "vertex (D)": _fmt(a.vertex_diopters) if a.vertex_diopters is not None else f"none ({_fmt(a.fit.vertex_diopters)} is a maximum)",
            "95 % CI Fieller (D)": a.vertex_interval.describe() if a.vertex_diopters is not None else "–",
            "95 % CI delta (D)": a.vertex_interval_delta.describe() if a.vertex_diopters is not None else "–",
            "SE (D)": _fmt(a.measured_se_diopters, "+.3f"),
            "vertex − SE (D)": _fmt(a.vertex_minus_se_diopters),
            "SE in CI": "–" if within is None else ("yes" if within else "no"),
            "least measured at (D)": _fmt(a.data_minimum_lens_diopters),
        })
    return rows


def _md_table(rows: list[dict]) -> str:
    if not rows:
        return "_(none)_\n"
    keys = list(rows[0])
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(r[k] for k in keys) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def report_pages(
    title: str,
    intro: str,
    analyses: Sequence[CurveAnalysis],
    figures: Sequence[tuple[str, str]],
    discrepancies: Sequence[tuple[str, Discrepancy]] = (),
    notes: Sequence[str] = (),
) -> tuple[str, str]:
    """The report as (Markdown, HTML): the same sections, rows and notes in both."""
    esc = html.escape
    rows = summary_rows(analyses)
    all_notes = [*notes, *(f"{a.label}: {n}" for a in analyses for n in a.notes)]
    disagree = "Where the data disagree with the thesis's own numbers"
    md = [f"# {title}\n", intro.strip() + "\n", "## Fitted vertices\n", _md_table(rows)]
    page = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>{esc(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:72em;margin:auto}table{border-collapse:collapse;font-size:90%}"
        "td,th{border:1px solid #bbb;padding:3px 6px}img{max-width:100%}</style></head><body>",
        f"<h1>{esc(title)}</h1>",
        *(f"<p>{esc(p)}</p>" for p in intro.strip().split("\n\n")),
        "<h2>Fitted vertices</h2>",
    ]
    if rows:
        page.append("<table><tr>" + "".join(f"<th>{esc(k)}</th>" for k in rows[0]) + "</tr>")
        page += ["<tr>" + "".join(f"<td>{esc(v)}</td>" for v in r.values()) + "</tr>" for r in rows]
        page.append("</table>")
    if all_notes:
        md += ["\n## Notes\n", "\n".join(f"- {n}" for n in all_notes) + "\n"]
        page.append("<h2>Notes</h2><ul>" + "".join(f"<li>{esc(n)}</li>" for n in all_notes) + "</ul>")
    if discrepancies:
        md += [f"\n## {disagree}\n",
               "\n".join(f"- subject {sid}, `{d.kind}`: {d.message}" for sid, d in discrepancies) + "\n"]
        page += [f"<h2>{disagree}</h2><ul>", *(f"<li>subject {esc(sid)}, <code>{esc(d.kind)}</code>: {esc(d.message)}"
                                              "</li>" for sid, d in discrepancies), "</ul>"]
    md += ["\n## Figures\n", *(f"![{caption}]({name})\n\n_{caption}_\n" for name, caption in figures)]
    page += ["<h2>Figures</h2>", *(f"<figure><img src='{esc(name)}' alt='{esc(caption)}'><figcaption>{esc(caption)}"
                                   "</figcaption></figure>" for name, caption in figures), "</body></html>"]
    return "\n".join(md), "\n".join(page) + "\n"


def write_report(
    out_dir: str | Path,
    *,
    title: str,
    intro: str,
    analyses: Sequence[CurveAnalysis],
    figures: Sequence[tuple[str, str]],
    discrepancies: Sequence[tuple[str, Discrepancy]] = (),
    notes: Sequence[str] = (),
    record: dict | None = None,
    overwrite: bool = False,
) -> list[Path]:
    """Write ``report.md``, ``report.html`` and (if ``record``) ``analysis.json`` into ``out_dir``."""
    out_dir = Path(out_dir)
    markdown, page = report_pages(title, intro, analyses, figures, discrepancies, notes)
    written = [write_text_atomic(out_dir / "report.md", markdown, overwrite),
               write_text_atomic(out_dir / "report.html", page, overwrite)]
    if record is not None:
        written.append(write_json_atomic(out_dir / "analysis.json", json_safe(record), overwrite))
    return written


ANALYSIS_INTRO = """\
Minimum visible intensity of one phone pixel seen through the ATV tube (thesis Ch. 5, Appendix A),
fitted per eye and condition by ordinary least squares with a parabola in the trial-lens power
(thesis §5.5). With drops: the cycloplegic session; without drops: {pooling}. The band is the
pointwise {level:.0f} % confidence band of the mean curve. The vertex −b/(2a) is the trial lens of the
least threshold; its primary interval is Fieller's (exact for normal, independent, equal-variance
errors; unbounded when the curvature is not significant), the delta-method interval is given for
comparison. SE is S + C/2 of the cycloplegic autorefraction (a correcting lens: the trial lens that
corrects the eye). Intensities are display code values in [0, 1], not luminances (ERRATA item 9).

The intervals assume the parabola is the right curve; the data are closer to a V with a flat floor,
so residuals are correlated along the lens axis and the intervals are optimistic. Rows marked
"±{window} D window" refit only the lenses within that distance of the least measured one (at least
5 lenses): a local parabola around the minimum, less biased by the shape of the flanks (for a
simulated perfect observer the whole-range fit puts the vertex ≈ 0.3 D on the minus side of the
correcting lens; see `vissim atv simulate`). The window is chosen from the data, which the intervals
do not account for. The thesis (§5.5) notes that a single cycloplegic drop only partly stops
accommodation."""


def analyse_directory(
    data_dir: str | Path,
    out_dir: str | Path,
    *,
    strict: bool = False,
    level: float = 0.95,
    average_sessions: bool = True,
    window_diopters: float | None = ATV_PARABOLA_WINDOW_DIOPTERS,
    overwrite: bool = False,
) -> tuple[list[Path], list[CurveAnalysis]]:
    """Load every subject in ``data_dir``, fit, plot and write the report into ``out_dir``."""
    from vissim.atv.analysis import analyse_subject
    from vissim.atv.data import load_directory
    from vissim.provenance import make_provenance

    subjects = load_directory(data_dir, strict=strict)
    out_dir = Path(out_dir)
    written: list[Path] = []
    figures: list[tuple[str, str]] = []
    all_analyses: list[CurveAnalysis] = []
    discrepancies: list[tuple[str, Discrepancy]] = []
    for subject in subjects:
        analyses = analyse_subject(subject, level=level, average_sessions=average_sessions)
        all_analyses += analyses
        if window_diopters is not None:
            all_analyses += analyse_subject(subject, level=level, average_sessions=average_sessions, window_diopters=window_diopters)
        discrepancies += [(subject.subject_id, d) for d in subject.discrepancies]
        if not analyses:
            continue
        fits = f"subject_{subject.subject_id}_fits.png"
        overview = f"subject_{subject.subject_id}_overview.png"
        written.append(plot_fits(analyses, out_dir / fits, title=f"Subject {subject.subject_id}: quadratic fits", overwrite=overwrite))
        written.append(plot_overview(analyses, out_dir / overview, title=f"Subject {subject.subject_id}", overwrite=overwrite))
        figures += [
            (fits, f"Subject {subject.subject_id}: minimum visible vs trial lens, quadratic fit, {100 * level:.0f} % band, vertex with Fieller interval, SE (black)"),
            (overview, f"Subject {subject.subject_id}: blue with drops, red without; dashed right eye, solid left; circles at the least measured value; black lines at the SE"),
        ]
    pooling = "the mean of the sessions without drops at each lens" if average_sessions else "every session's value as its own point"
    record = make_provenance(
        command="atv analyze", data_dir=str(data_dir), level=level, average_sessions=average_sessions, strict=strict,
        window_diopters=window_diopters,
    )
    record["subjects"] = [
        {"subject_id": s.subject_id, "file": str(s.path), "discrepancies": [d.as_json() for d in s.discrepancies]} for s in subjects
    ]
    record["curves"] = [a.as_json() for a in all_analyses]
    written += write_report(
        out_dir, title="Absolute threshold for vision: fitted vertices vs spherical equivalent",
        intro=ANALYSIS_INTRO.format(pooling=pooling, level=100 * level, window=f"{window_diopters:g}" if window_diopters else "W"), analyses=all_analyses, figures=figures,
        discrepancies=discrepancies, record=record, overwrite=overwrite,
    )
    return written, all_analyses


SIMULATION_INTRO = """\
Virtual ATV experiment (vissim.atv.virtual): eye {rx} (correcting lens, SE {se:+.3f} D), pupil
{pupil:g} mm, {accommodation}. One iPhone 5 pixel ({source:.2f} arcmin) through the 8 D collimator;
trial lenses at {vertex:g} mm add P/(1 − dP) at the eye. Retinal image: {model} at {wavelength:g} nm,
convolved with the pixel. Threshold luminance ∝ 1 / (flux fraction inside a {summation:g} arcmin
disc), code value through gamma {gamma:g}; the observer is a Weibull psychometric function
(luminance exponent {slope:g}, guess {guess:g}, lapse {lapse:g}); each threshold is the Listing 5.1
procedure with a bisection phase 2 (seed {seed}). The trial lens that corrects the eye is
{correcting:+.3f} D."""


def write_simulation_report(experiment, out_dir: str | Path, *, window_diopters: float | None = ATV_PARABOLA_WINDOW_DIOPTERS, level: float = 0.95,
                            overwrite: bool = False) -> tuple[list[Path], list[CurveAnalysis]]:
    """Write the figure, ``report.md``/``.html`` and ``simulation.json`` of a `VirtualExperiment`."""
    from vissim.provenance import make_provenance

    out_dir = Path(out_dir)
    subject, apparatus, detection = experiment.subject, experiment.apparatus, experiment.detection
    analyses = [experiment.analysis(level)]
    if window_diopters is not None:
        analyses.append(experiment.analysis(level, window_diopters=window_diopters))
    se = subject.prescription.spherical_equivalent_diopters
    correcting = se / (1.0 + apparatus.trial_lens_vertex_mm * 1e-3 * se)
    accommodation = (
        "cycloplegia (no accommodation)" if subject.cycloplegia
        else f"accommodation free (amplitude {subject.accommodation_amplitude_diopters:g} D, proximal "
             f"{subject.proximal_accommodation_diopters:g} D)"
    )
    intro = SIMULATION_INTRO.format(
        rx=subject.prescription.format(), se=se, pupil=subject.pupil_diameter_mm, accommodation=accommodation,
        source=apparatus.source_size_arcmin, vertex=apparatus.trial_lens_vertex_mm,
        model="the Fourier PSF of the residual defocus" if experiment.retinal_image_model == "fourier" else experiment.retinal_image_model,
        wavelength=apparatus.wavelength_nm, summation=detection.summation_diameter_arcmin, gamma=apparatus.display_gamma,
        slope=detection.psychometric_slope, guess=detection.guess_rate, lapse=detection.lapse_rate, seed=experiment.seed,
        correcting=correcting,
    )
    panel_titles = [f"{accommodation.split(' (')[0]}, fit over {'all lenses' if a.window_diopters is None else f'a ±{a.window_diopters:g} D window'}"
                    for a in analyses]
    written = [plot_fits(analyses, out_dir / "curve.png", title=f"Virtual subject {subject.prescription.format()}",
                         panel_titles=panel_titles, overwrite=overwrite)]
    record = make_provenance(command="atv simulate", experiment=experiment.as_json(), level=level, window_diopters=window_diopters)
    record["correcting_trial_lens_diopters"] = correcting
    record["curves"] = [a.as_json() for a in analyses]
    written += write_report(
        out_dir, title="Virtual ATV experiment", intro=intro, analyses=analyses,
        figures=[("curve.png", "Simulated minimum visible, quadratic fits, band, vertex with Fieller interval, SE (black)")],
        record=record, overwrite=overwrite,
    )
    return written, analyses
