"""The report's sections on the traced lenses: the wave bench, each residual's cause, the geometric self-check.

The wave bench is noise-free (`vissim.validation.dslr.wave_bench`): its rows have no noise
floor, so they are summarised as absolute PSNR, never as "PSNR minus the floor", and kept out
of the tables against the render.  The geometric self-check (simulation ``traced_rays``) is
compared with the render and summarised, like the simulations, as PSNR minus the noise floor.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from vissim.validation.engine.metrics import MEAN_ABS_DIFF, PSNR, floor_column
from vissim.validation.engine.summary import NO_LENS, margin, value_span
from vissim.validation.dslr.wave_bench import TRACED_RAYS, WAVE_BENCH_NOTE

__all__ = ["is_wave_bench_row", "self_check_table", "wave_bench_tables", "SELF_CHECK_MARGIN_DB"]


def is_wave_bench_row(row: dict) -> bool:
    return row["reference"] == WAVE_BENCH_NOTE


#: The geometric self-check passes at PSNR at least this far over the noise floor (dB).
SELF_CHECK_MARGIN_DB = 2.0


def _margins(rows: list[dict], simulation: str) -> dict[str, list[tuple[float, str]]]:
    """(PSNR minus the floor, configuration) of ``simulation`` on the synthetic chart, per group."""
    groups: dict[str, list[tuple[float, str]]] = {}
    for r in rows:
        if r["simulation"] == simulation and r["input"] == "synthetic" and not is_wave_bench_row(r):
            groups.setdefault(r["group"], []).append((margin(r), r["configuration"]))
    return groups


def self_check_table(rows: list[dict]) -> str:
    """Markdown: the geometric self-check per group (median, lowest and where), configurations without lenses apart."""
    if not any(r["simulation"] == TRACED_RAYS for r in rows):
        return ""
    with_lenses = [r for r in rows if r["lenses"] != NO_LENS]
    traced, geometric = _margins(with_lenses, TRACED_RAYS), _margins(with_lenses, "geometric")
    header = ["group (configurations with lenses)", "self-check, median", "self-check, lowest", "lowest at",
              "ray optics on the drawn chart, median", "ray optics on the drawn chart, lowest"]
    out = [
        "### Summary: the geometric self-check, traced rays against the render (dB)\n",
        ("The self-check: the lens trace's ray optics (the ray PSF of the trial lenses' traced wavefront at the "
         "d line, where the glass has the index Mitsuba renders) applied to the synthetic chart and compared with the render "
         "(`traced_rays` in metrics.csv), "
         "aligned on the fine grid like the geometric simulation beside it. PSNR minus the render noise floor: "
         f"+3 dB is perfect, 0 dB the floor; a configuration passes at >= +{SELF_CHECK_MARGIN_DB:g} dB. "
         "Configurations without lenses are listed apart, below.\n"),
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for group, values in traced.items():
        lowest = min(values)
        other = [m for m, _ in geometric.get(group, [])]
        out.append("| " + " | ".join([
            f"{group} ({len(values)})", f"{np.median([m for m, _ in values]):+.2f}", f"{lowest[0]:+.2f}", lowest[1],
            f"{np.median(other):+.2f}" if other else "—", f"{min(other):+.2f}" if other else "—"]) + " |")
    bare = [r for r in rows if r["lenses"] == NO_LENS and r["simulation"] == TRACED_RAYS]
    if bare:
        margins = [margin(r) for r in bare]
        out += ["", (f"Without lenses ({len(bare)}): {value_span(margins, '+.1f')} dB over the floor "
                     f"({value_span([r[PSNR.name] for r in bare], '.1f')} dB against "
                     f"{value_span([r[floor_column(PSNR)] for r in bare], '.1f')} dB). With no lens the trace's PSF is a "
                     "point and nothing is traced: the synthetic chart is compared with the render's chart texture, "
                     "two rasterisations of one letter (the geometric simulation of the synthetic chart scores the "
                     "same).")]
        if min(margins) < SELF_CHECK_MARGIN_DB:
            out[-1] += (f" They differ by {value_span([r[MEAN_ABS_DIFF.name] for r in bare], '.1e')} on average, which a "
                        "lens's blur and the Monte-Carlo noise hide; without a lens two renders with different seeds "
                        "agree far better than that, so the floor exposes the rasterisation, not the trace.")
    return "\n".join(out) + "\n"


def _cell(values: list[float], digits: int = 1) -> str:
    finite = [v for v in values if not math.isnan(v)]
    if not finite:
        return "—"
    value = float(np.median(finite))
    return "∞" if math.isinf(value) else f"{value:.{digits}f}"


def _diopters(value: float) -> str:
    return f"{value:+.4f}" if abs(value) >= 1e-3 else f"{value:+.1e}"


def _largest(values: list[float]) -> float:
    """The value of largest magnitude, signed."""
    return max(values, key=abs) if values else 0.0


#: The residuals table's columns after the group: what each group's residual is made of.
RESIDUAL_COLUMNS = ["wave / wave bench, lowest (dB)", "median (dB)", "the residual's cause",
                    "glass index at the wavelength minus the rendered", "dispersion: traced power minus the d line's (D)",
                    "traced minus simulated power (D)", "vergence approximation (D)", "spherical aberration, largest c(4,0) (nm)",
                    "not in the residual: trial-lens thickness, in both (D)",
                    "not in the residual: obliquity, in neither (nm RMS)"]


def _group_row(group: str, psnrs: list[float], budgets: list[dict]) -> str:
    """One row of the residuals table: a group's lowest and median PSNR, causes, and the largest of each part."""
    causes = Counter(b["cause"] for b in budgets)
    lowest = min(psnrs) if psnrs else math.nan
    cells = [
        f"{group} ({len(budgets)})", f"{lowest:.1f}", _cell(psnrs),
        ", ".join(f"{cause} ({n})" for cause, n in causes.most_common()),
        f"{_largest([d for b in budgets for d in b['index_difference']]):+.4f}",
        _diopters(_largest([b["dispersion_diopters"] for b in budgets])),
        _diopters(_largest([b["power_difference_diopters"] for b in budgets])),
        _diopters(_largest([b["vergence_approximation_diopters"] for b in budgets])),
        f"{1e3 * max(abs(b['spherical_aberration_um']) for b in budgets):.2g}",
        _diopters(_largest([b["thickness_diopters"] for b in budgets])),
        f"{1e3 * max(b['obliquity_rms_um'] for b in budgets):.2g}",
    ]
    return "| " + " | ".join(cells) + " |"


@dataclass(frozen=True)
class _WaveBenchRows:
    """The rows against the wave bench, by (configuration, simulation), with each configuration's budget and group."""

    simulations: list[str]
    psnr: dict[tuple[str, str], float]
    budgets: dict[str, dict]
    groups: dict[str, list[str]]


def _wave_bench_rows(results: list[dict], wave_rows: list[dict]) -> _WaveBenchRows:
    groups: dict[str, list[str]] = {}
    for name, group in dict.fromkeys((r["configuration"], r["group"]) for r in wave_rows):
        groups.setdefault(group, []).append(name)
    return _WaveBenchRows(list(dict.fromkeys(r["simulation"] for r in wave_rows)),
                          {(r["configuration"], r["simulation"]): r[PSNR.name] for r in wave_rows},
                          {r["configuration"]["name"]: r["wave_bench"] for r in results if r.get("wave_bench")}, groups)


def _summary(results: list[dict], w: _WaveBenchRows) -> list[str]:
    """The PSNR per group against the wave bench, and what the configurations without a lens score."""
    wavelengths = sorted({b["wavelength_nm"] for b in w.budgets.values()})
    header = ["group (configurations)", *[f"{s} / wave bench" for s in w.simulations], "wave / wave bench, lowest",
              "residual's cause"]
    out = [
        "### Summary: PSNR against the wave bench (dB)\n",
        (f"The wave bench is the chart imaged through the trial lenses' traced wavefront by wave optics, traced "
         f"through the dispersive crown glass at {', '.join(f'{x:g}' for x in wavelengths)} nm. It is noise-free, "
         "so there is no noise floor: these are absolute PSNRs (median per group) of the simulations of the "
         "synthetic chart, unregistered. The wave simulation passes at >= 50 dB; the aim is 60 dB.\n"),
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for group, names in w.groups.items():
        cells = [_cell([w.psnr[(n, s)] for n in names if (n, s) in w.psnr]) for s in w.simulations]
        wave = [w.psnr[(n, "wave")] for n in names if (n, "wave") in w.psnr]
        causes = Counter(w.budgets[n]["cause"] for n in names if n in w.budgets)
        out.append("| " + " | ".join([f"{group} ({len(names)})", *cells, f"{min(wave):.1f}" if wave else "—",
                                      ", ".join(f"{c} ({k})" for c, k in causes.most_common()) or "—"]) + " |")
    bare = [w.psnr[(n, "wave")] for r in results if r.get("lens_label") == NO_LENS
            for n in [r["configuration"]["name"]] if (n, "wave") in w.psnr]
    if bare:
        out += ["", (f"Configurations without a lens ({len(bare)}) score {value_span(bare, '.1f')} dB here: with nothing "
                     "traced, only the float32 round-off of the two computations is left. They raise their groups' "
                     "medians, not the lowest, which a configuration with lenses sets whenever the group has one.")]
    return out


def _residuals(w: _WaveBenchRows) -> list[str]:
    """Per group, the largest of each part of the residual, and what names it."""
    rendered = sorted({n for b in w.budgets.values() for n in b["rendered_index"]})
    out = ["", "### Residuals against the wave bench, explained\n"]
    out.append("Each residual of the wave simulation against the wave bench is named by the largest RMS part of "
               "the wavefront difference: dispersion (the trace at the campaign's wavelength against the trace at "
               "the d line, where the glass has the rendered index "
               f"{', '.join(f'{n:g}' for n in rendered) or '—'}), the vergence approximation (the d-line trace "
               "against the simulation's paraxial power) or spherical aberration (the traced terms of order >= 3). "
               "Per group, the largest of each part over its configurations. Powers: principal value of largest "
               "magnitude of the power-matrix difference, D. The trial lens's thickness is in both the bench and the "
               "simulation, and the obliquity of the field in neither, so neither is part of the residual.\n")
    out += ["| " + " | ".join(["group (configurations)", *RESIDUAL_COLUMNS]) + " |",
            "|" + "---|" * (len(RESIDUAL_COLUMNS) + 1)]
    for group, names in w.groups.items():
        group_budgets = [w.budgets[n] for n in names if n in w.budgets]
        if group_budgets:
            out.append(_group_row(group, [w.psnr[(n, "wave")] for n in names if (n, "wave") in w.psnr], group_budgets))
    return out


def _per_configuration(w: _WaveBenchRows) -> list[str]:
    """Each configuration's PSNRs and budget."""
    out = ["", "### Each configuration against the wave bench\n"]
    columns = ["configuration", *[f"{s} / wave bench" for s in w.simulations], "trial lens power, traced",
               "trial lens power, simulated",
               "traced − simulated (D)", "dispersion (D)", "vergence approx. (D)", "c(4,0) (nm)",
               "thickness, in both (D)", "obliquity, in neither (nm RMS)", "cause"]
    out += ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for names in w.groups.values():
        for name in names:
            b = w.budgets.get(name)
            cells = [_cell([w.psnr[(name, s)]], 2) if (name, s) in w.psnr else "—" for s in w.simulations]
            if b is None:
                cells += ["—"] * 9
            else:
                cells += [b["traced_added_power"], b["simulated_added_power"], _diopters(b["power_difference_diopters"]),
                          _diopters(b["dispersion_diopters"]), _diopters(b["vergence_approximation_diopters"]),
                          f"{1e3 * b['spherical_aberration_um']:.2g}", _diopters(b["thickness_diopters"]),
                          f"{1e3 * b['obliquity_rms_um']:.2g}", b["cause"]]
            out.append("| " + " | ".join([name, *cells]) + " |")
    return out


def wave_bench_tables(results: list[dict], rows: list[dict]) -> str:
    """Markdown: the summary per group (a column ``wave / wave bench``), the causes, and a table per configuration."""
    wave_rows = [r for r in rows if is_wave_bench_row(r)]
    if not wave_rows:
        return ""
    w = _wave_bench_rows(results, wave_rows)
    return "\n".join([*_summary(results, w), *_residuals(w), *_per_configuration(w)]) + "\n"
