"""The report's summary: median PSNR minus the noise floor per group, and what a reader needs to read it.

Two things the numbers alone do not say are explained with this run's own numbers: why a score
can exceed the +3.01 dB a perfect simulation scores on average, and what the configurations
without a lens do to their groups' medians (a second table leaves them out).
"""

from __future__ import annotations

import math

import numpy as np

from vissim.validation.engine.metrics import PSNR, floor_column
from vissim.validation.engine.reading import PERFECT_MARGIN_DB


__all__ = ["PERFECT_MARGIN_DB", "summary_table", "summary_notes", "margin", "NO_LENS", "value_span"]

#: The lens label of a configuration without trial lenses.
NO_LENS = "no lens"


def margin(row: dict) -> float:
    """PSNR minus the noise floor of a metrics row, dB (NaN without a floor)."""
    return row[PSNR.name] - row[floor_column(PSNR)]


def _median_cell(values: list[float]) -> str:
    finite = [v for v in values if not math.isnan(v)]
    if not finite:
        return "—"
    value = float(np.median(finite))
    return "∞" if math.isinf(value) else f"{value:+.1f}"


def _slash(column: tuple[str, str]) -> str:
    return f"{column[0]} / {column[1]}"


def _table(rows: list[dict], columns: list[tuple[str, str]], mark_no_lens: bool, words=_slash) -> list[str]:
    """One row per (simulation, input), one column per group: the medians (a table as wide as the groups)."""
    groups: dict[str, dict] = {}
    bare: dict[str, set] = {}
    for r in rows:
        group = r["group"]
        groups.setdefault(group, {}).setdefault((r["simulation"], r["input"]), []).append(margin(r))
        if r["lenses"] == NO_LENS:
            bare.setdefault(group, set()).add(r["configuration"])
    labels = []
    for group, cells in groups.items():
        n = max(len(v) for v in cells.values())
        label = f"{group} ({n})"
        if mark_no_lens and group in bare:
            label = f"{group} ({n}, {len(bare[group])} without a lens)¹"
        labels.append(label)
    lines = ["| " + " | ".join(["simulation (group: configurations)"] + labels) + " |", "|" + "---|" * (len(labels) + 1)]
    for column in columns:
        lines.append("| " + " | ".join([words(column)] + [_median_cell(cells.get(column, [])) for cells in groups.values()])
                     + " |")
    return lines


def summary_table(rows: list[dict], columns: list[tuple[str, str]], words=_slash) -> str:
    """Markdown: median PSNR minus the noise floor per group (a sweep, or one item), then the notes."""
    lines = [
        "### Summary: median PSNR minus the noise floor (dB)\n",
        ("Each entry is the median, over a group's configurations, of a simulation's PSNR against the bench "
         "minus the bench's noise floor (two renders with different seeds compared with each other). 0 dB: "
         "the simulation differs from the bench as much as two renders differ from each other; "
         f"+{PERFECT_MARGIN_DB:.2f} dB: what a perfect, noise-free simulation scores on average. A row is a "
         "simulation and its input: the bench's no-lens render (as the thesis did), or the chart drawn by vissim; "
         "a column is a group of configurations.\n"),
        *_table(rows, columns, mark_no_lens=True, words=words),
    ]
    if any(r["lenses"] == NO_LENS for r in rows):
        lines += ["", "¹ Includes configurations without a lens; the next table explains them and leaves them out."]
    return "\n".join(lines) + "\n" + summary_notes(rows, columns, words)


def value_span(values: list[float], spec: str) -> str:
    """``lowest…highest`` in ``spec`` (one value if they agree to the format)."""
    low, high = format(min(values), spec), format(max(values), spec)
    return low if low == high else f"{low}…{high}"


def _above_perfect(rows: list[dict], columns: list[tuple[str, str]], words=_slash) -> str:
    """The sentence on the highest margin in the summary's columns, if it is above the perfect simulation's."""
    scored = [(margin(r), r) for r in rows if r["lenses"] != NO_LENS and math.isfinite(margin(r))
              and (r["simulation"], r["input"]) in columns]
    if not scored:
        return ""
    best, row = max(scored, key=lambda s: s[0])
    if best <= PERFECT_MARGIN_DB + 0.005:
        return f" In this run no configuration with lenses scores above +{PERFECT_MARGIN_DB:.2f} dB."
    ratio = 10.0 ** (best / 10.0)
    return (f" This run's highest is {best:+.2f} dB ({row['configuration']}, {words((row['simulation'], row['input']))}): "
            f"there the two renders' squared difference is {ratio:.2f} times the simulation's instead of 2, as if the "
            f"second render held {100 * (ratio - 2):.0f} % more noise energy than the first.")


def summary_notes(rows: list[dict], columns: list[tuple[str, str]], words=_slash) -> str:
    """Markdown: why a score can exceed +3.01 dB; the no-lens configurations and the medians without them."""
    out = [
        "\n### Reading the summary: above +3 dB, and the configurations without a lens\n",
        ("Why a score can exceed +3 dB. The noise floor's two renders each hold the Monte-Carlo noise, so their "
         "mean squared difference is twice one render's noise (2σ²). A simulation is compared with the first "
         f"render only, so a perfect, noise-free one differs by σ² and scores 10·log10(2) = +{PERFECT_MARGIN_DB:.2f} dB "
         "over the floor. That is an average, not a ceiling: the floor and each score are measured once, on one "
         "tile, and the noise lives only in the pixels that see an edge of the blurred letter (a uniform "
         "background has none). Where the first render's noise happens to be weaker than the second's over those "
         "pixels, or the two renders' noise is slightly anticorrelated, a perfect simulation scores more. The fewer "
         "the noisy pixels (small letters, little blur), the larger the swing." + _above_perfect(rows, columns, words) + "\n"),
    ]
    bare = [r for r in rows if r["lenses"] == NO_LENS and (r["simulation"], r["input"]) in columns]
    if not bare:
        return "\n".join(out)
    groups = sorted({r["group"] for r in bare})
    margins = [margin(r) for r in bare if math.isfinite(margin(r))]
    floors = [r[floor_column(PSNR)] for r in bare if math.isfinite(r[floor_column(PSNR)])]
    out.append(
        f"The configurations without a lens ({len({r['configuration'] for r in bare})}, in "
        f"{', '.join(groups)}) count in their groups' medians. With no lens the bench renders a sharp letter: its "
        "two renders differ only in the few pixels on the letter's edges, so the floor is high "
        f"({value_span(floors, '.1f')} dB here), and PSNR minus the floor then measures how the simulation's input "
        "differs from the render (the synthetic chart is a second rasterisation of the letter; the wave simulation "
        "adds a diffraction of its own), not the optics of a lens. Their scores: "
        f"{value_span(margins, '+.1f') if margins else '—'} dB over the floor. A median of two is their mean, so in a "
        "group of two one such row moves the median by half its distance from the other. The table below gives "
        "the medians of these groups over the configurations with lenses only.\n")
    out.append("### Summary of the groups with no-lens configurations, over those with lenses only (dB)\n")
    with_lenses = [r for r in rows if r["lenses"] != NO_LENS and r["group"] in groups]
    out += _table(with_lenses, columns, mark_no_lens=False, words=words) if with_lenses else ["No configuration with lenses."]
    return "\n".join(out) + "\n"
