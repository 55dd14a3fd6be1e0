"""The report's sections on the traced lenses: the wave bench, each residual's cause, the geometric self-check.

The wave bench is noise-free (`vissim.validation.wave_bench`): its rows have no noise
floor, so they are summarised as absolute PSNR, never as "PSNR minus the floor", and kept out
of the tables against the render.  The geometric self-check (simulation ``traced_rays``) is
compared with the render and summarised, like the simulations, as PSNR minus the noise floor.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from vissim.validation.wave_bench import TRACED_RAYS, WAVE_BENCH_NOTE

__all__ = ["group_of", "is_wave_bench_row", "self_check_table", "wave_bench_tables", "SELF_CHECK_MARGIN_DB"]


def is_wave_bench_row(row: dict) -> bool:
    return row["reference"] == WAVE_BENCH_NOTE


def group_of(configuration_name: str) -> str:
    """A configuration's group: its sweep's name, or the item itself."""
    return configuration_name.split(":")[0]


#: Issue 13's acceptance of the geometric self-check: PSNR at least this far over the noise floor (dB).
SELF_CHECK_MARGIN_DB = 2.0


def _margins(rows: list[dict], simulation: str) -> dict[str, list[tuple[float, str]]]:
    """(PSNR minus the floor, configuration) of ``simulation`` on the synthetic chart, per group."""
    groups: dict[str, list[tuple[float, str]]] = {}
    for r in rows:
        if r["simulation"] == simulation and r["input"] == "synthetic" and not is_wave_bench_row(r):
            margin = r["psnr_db"] - r["noise_floor_psnr_db"]
            groups.setdefault(group_of(r["configuration"]), []).append((margin, r["configuration"]))
    return groups


def self_check_table(rows: list[dict]) -> str:
    """Markdown: the geometric self-check per group (median, lowest and where), configurations without lenses apart."""
    if not any(r["simulation"] == TRACED_RAYS for r in rows):
        return ""
    with_lenses = [r for r in rows if r["lenses"] != "no lens"]
    traced, geometric = _margins(with_lenses, TRACED_RAYS), _margins(with_lenses, "geometric")
    header = ["group (configurations with lenses)", "traced rays, median", "traced rays, lowest", "lowest at",
              "geometric / synthetic, median", "geometric / synthetic, lowest"]
    out = [
        "### Summary: the geometric self-check, traced rays against the render (dB)\n",
        (f"The lens trace's ray optics (`{TRACED_RAYS}`: the ray PSF of the trial lenses' traced wavefront at the "
         "d line, where the glass has the index Mitsuba renders) applied to the synthetic chart and compared with the render, "
         "aligned on the fine grid like the geometric simulation beside it. PSNR minus the render noise floor: "
         f"+3 dB is perfect, 0 dB the floor; issue 13 accepts >= +{SELF_CHECK_MARGIN_DB:g} dB. "
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
    bare = [r for r in rows if r["lenses"] == "no lens" and r["simulation"] == TRACED_RAYS]
    if bare:
        margins = [r["psnr_db"] - r["noise_floor_psnr_db"] for r in bare]
        out += ["", (f"Without lenses ({len(bare)}): {_span(margins, '+.1f')} dB over the floor "
                     f"({_span([r['psnr_db'] for r in bare], '.1f')} dB against "
                     f"{_span([r['noise_floor_psnr_db'] for r in bare], '.1f')} dB). With no lens the trace's PSF is a "
                     "point and nothing is traced: the synthetic chart is compared with the render's chart texture, "
                     "two rasterisations of one letter (the geometric simulation of the synthetic chart scores the "
                     "same).")]
        if min(margins) < SELF_CHECK_MARGIN_DB:
            out[-1] += (f" They differ by {_span([r['mean_abs_diff'] for r in bare], '.1e')} on average, which a "
                        "lens's blur and the Monte-Carlo noise hide; without a lens two renders with different seeds "
                        "agree far better than that, so the floor exposes the rasterisation, not the trace.")
    return "\n".join(out) + "\n"


def _span(values: list[float], spec: str) -> str:
    """``lowest-highest`` (one value if they agree to the format)."""
    low, high = format(min(values), spec), format(max(values), spec)
    return low if low == high else f"{low}…{high}"


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


def _group_line(group: str, psnrs: list[float], budgets: list[dict]) -> str:
    causes = Counter(b["cause"] for b in budgets)
    named = ", ".join(f"{cause} in {n}" for cause, n in causes.most_common())
    wavelength = budgets[0]["wavelength_nm"]
    lowest = min(psnrs) if psnrs else math.nan
    index_gap = _largest([d for b in budgets for d in b["index_difference"]])
    rendered = sorted({n for b in budgets for n in b["rendered_index"]})
    parts = [
        (f"- {group} ({len(budgets)}): wave / wave bench lowest {lowest:.1f} dB, median {_cell(psnrs)} dB; "
         f"the residual's cause: {named}."),
        (f"Dispersion: at {wavelength:g} nm the glass's index is {index_gap:+.4f} from the rendered "
         f"{', '.join(f'{n:g}' for n in rendered) or 'index'}, so the traced power differs from the d line's by up to "
         f"{_diopters(_largest([b['dispersion_diopters'] for b in budgets]))} D; "
         f"traced minus simulated power up to {_diopters(_largest([b['power_difference_diopters'] for b in budgets]))} D."),
        (f"Vergence approximation (d-line trace minus the simulation's paraxial power) up to "
         f"{_diopters(_largest([b['vergence_approximation_diopters'] for b in budgets]))} D; "
         f"spherical aberration |c(4,0)| up to {1e3 * max(abs(b['spherical_aberration_um']) for b in budgets):.2g} nm."),
        (f"Not in the residual: trial-lens thickness {_diopters(_largest([b['thickness_diopters'] for b in budgets]))} D "
         f"(in both), obliquity up to {1e3 * max(b['obliquity_rms_um'] for b in budgets):.2g} nm RMS over the frame "
         f"(in neither)."),
    ]
    return " ".join(parts)


def wave_bench_tables(results: list[dict], rows: list[dict]) -> str:
    """Markdown: the summary per group (a column ``wave / wave bench``), the causes, and a table per configuration."""
    wave_rows = [r for r in rows if is_wave_bench_row(r)]
    if not wave_rows:
        return ""
    simulations = list(dict.fromkeys(r["simulation"] for r in wave_rows))
    psnr = {(r["configuration"], r["simulation"]): r["psnr_db"] for r in wave_rows}
    budgets = {r["configuration"]["name"]: r["wave_bench"] for r in results if r.get("wave_bench")}
    groups: dict[str, list[str]] = {}
    for name in dict.fromkeys(r["configuration"] for r in wave_rows):
        groups.setdefault(group_of(name), []).append(name)
    wavelengths = sorted({b["wavelength_nm"] for b in budgets.values()})
    header = ["group (configurations)", *[f"{s} / wave bench" for s in simulations], "wave / wave bench, lowest",
              "residual's cause"]
    out = [
        "### Summary: PSNR against the wave bench (dB)\n",
        (f"The wave bench is the chart imaged through the trial lenses' traced wavefront by wave optics, traced "
         f"through the dispersive crown glass at {', '.join(f'{w:g}' for w in wavelengths)} nm. It is noise-free, "
         "so there is no noise floor: these are absolute PSNRs (median per group) of the simulations of the "
         "synthetic chart, unregistered. Issue 13 asks for >= 50 dB for wave and aims at 60.\n"),
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for group, names in groups.items():
        cells = [_cell([psnr[(n, s)] for n in names if (n, s) in psnr]) for s in simulations]
        wave = [psnr[(n, "wave")] for n in names if (n, "wave") in psnr]
        causes = Counter(budgets[n]["cause"] for n in names if n in budgets)
        out.append("| " + " | ".join([f"{group} ({len(names)})", *cells, f"{min(wave):.1f}" if wave else "—",
                                      ", ".join(f"{c} ({k})" for c, k in causes.most_common()) or "—"]) + " |")
    out += ["", "### Residuals against the wave bench, explained\n"]
    out.append("Each residual of the wave simulation against the wave bench is named by the largest RMS part of "
               "the wavefront difference: dispersion (the trace at the campaign's wavelength against the trace at "
               "the d line, where the glass has the rendered index), the vergence approximation (the d-line trace "
               "against the simulation's paraxial power) or spherical aberration (the traced terms of order >= 3). "
               "Powers: principal value of largest magnitude of the power-matrix difference, D.\n")
    for group, names in groups.items():
        group_budgets = [budgets[n] for n in names if n in budgets]
        if group_budgets:
            out.append(_group_line(group, [psnr[(n, "wave")] for n in names if (n, "wave") in psnr], group_budgets))
    out.append("")
    columns = ["configuration", *[f"{s} / wave bench" for s in simulations], "traced power", "simulated power",
               "traced − simulated (D)", "dispersion (D)", "vergence approx. (D)", "c(4,0) (nm)",
               "thickness, in both (D)", "obliquity, in neither (nm RMS)", "cause"]
    out += ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for names in groups.values():
        for name in names:
            b = budgets.get(name)
            cells = [_cell([psnr[(name, s)]], 2) if (name, s) in psnr else "—" for s in simulations]
            if b is None:
                cells += ["—"] * 9
            else:
                cells += [b["traced_added_power"], b["simulated_added_power"], _diopters(b["power_difference_diopters"]),
                          _diopters(b["dispersion_diopters"]), _diopters(b["vergence_approximation_diopters"]),
                          f"{1e3 * b['spherical_aberration_um']:.2g}", _diopters(b["thickness_diopters"]),
                          f"{1e3 * b['obliquity_rms_um']:.2g}", b["cause"]]
            out.append("| " + " | ".join([name, *cells]) + " |")
    return "\n".join(out) + "\n"
