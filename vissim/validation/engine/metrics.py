"""The metrics a campaign scores with, each registered once: its name, unit, better direction and function.

A metric's ``name`` is its key everywhere: the field of a comparison
(`vissim.imaging.metrics.Comparison`, kept in each item's ``result.json``), the column of the
report's rows (``metrics.csv``) and, prefixed by ``noise_floor_``, the column of its noise floor.
The bench kinds, their tables and the reports read names, headings and digits from here.  Each kind
keeps its columns of vissim's own three metrics (PSNR, SSIM, mean absolute difference) in the
order its reports have always had; a metric registered beyond them (`added_metrics`) is scored in
every item and added to every kind's rows.  A new metric is one file defining its `Metric` and one
`register_metric` line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from vissim.errors import VissimInputError

if TYPE_CHECKING:  # loading a campaign file reads metric names; it needs no scikit-image
    from vissim.imaging.metrics import Comparison

__all__ = ["Metric", "METRICS", "register_metric", "metric", "PSNR", "SSIM", "MEAN_ABS_DIFF", "floor_column",
           "metric_float", "json_number", "added_metrics", "added_scores"]


@dataclass(frozen=True)
class Metric:
    """One image metric: ``value(comparison, mask)`` over the pixels of ``mask`` (None: the whole image)."""

    name: str  # the key of the comparison field, the row column and the result record, e.g. "psnr_db"
    label: str  # in table headings, e.g. "PSNR"
    unit: str  # "dB"; "" for a unitless metric
    higher_is_better: bool
    digits: int  # decimals in the report's tables
    value: Callable[[Comparison, np.ndarray | None], float]

    def heading(self) -> str:
        """``PSNR (dB)``; a unitless metric's label alone."""
        return f"{self.label} ({self.unit})" if self.unit else self.label


#: name -> Metric, in registration order (filled by `register_metric` only).
METRICS: dict[str, Metric] = {}


def register_metric(new: Metric) -> Metric:
    """Add ``new`` to `METRICS`; a second metric of one name is refused."""
    if new.name in METRICS:
        raise VissimInputError(f"a metric named {new.name!r} is registered already")
    METRICS[new.name] = new
    return new


def metric(name: str) -> Metric:
    """The registered metric called ``name``; an unknown name is an input error listing the known ones."""
    if name not in METRICS:
        raise VissimInputError(f"unknown metric {name!r}; known: {', '.join(METRICS)}")
    return METRICS[name]


def floor_column(m: Metric) -> str:
    """The column of ``m``'s noise floor (the two seeds' renders compared): ``noise_floor_psnr_db``."""
    return f"noise_floor_{m.name}"


def metric_float(value) -> float:
    """A metric as kept in JSON back to a float: ``"inf"`` is infinite, None unknown (NaN)."""
    if value is None:
        return math.nan
    return math.inf if value == "inf" else float(value)


def json_number(value: float) -> float | str | None:
    """A metric for JSON: an infinite value as ``"inf"``, NaN as None (`metric_float` reads it back)."""
    if math.isnan(value):
        return None
    return value if math.isfinite(value) else ("inf" if value > 0 else "-inf")


def added_metrics() -> tuple[Metric, ...]:
    """The metrics registered beyond vissim's own three, in registration order."""
    return tuple(m for m in METRICS.values() if m not in _OWN)


def added_scores(comparison: Comparison, mask: np.ndarray | None = None) -> dict:
    """``{name: value}`` of every `added_metrics` metric of ``comparison`` over ``mask``, JSON-ready."""
    return {m.name: json_number(m.value(comparison, mask)) for m in added_metrics()}


def _psnr(comparison: Comparison, mask: np.ndarray | None) -> float:
    if mask is None:
        return comparison.psnr_db  # `vissim.imaging.metrics.psnr_db`
    mse = float(comparison.squared_error_map[mask].mean())
    # Over a mask with Python's log10, as the depth campaign's committed report was made: `psnr_db` (numpy's
    # log10) differs in the last bit in 6 of its 247 region values, and its metrics.csv is kept byte-identical.
    # Re-baseline that report to make this `psnr_db(mse, comparison.data_range)`.
    return math.inf if mse == 0.0 else 10.0 * math.log10(comparison.data_range**2 / mse)


def _ssim(comparison: Comparison, mask: np.ndarray | None) -> float:
    return comparison.ssim if mask is None else float(comparison.ssim_map[mask].mean())


def _mean_abs_diff(comparison: Comparison, mask: np.ndarray | None) -> float:
    return comparison.mean_abs_diff if mask is None else float(comparison.abs_diff_map[mask].mean())


PSNR = register_metric(Metric("psnr_db", "PSNR", "dB", True, 2, _psnr))
SSIM = register_metric(Metric("ssim", "SSIM", "", True, 4, _ssim))
MEAN_ABS_DIFF = register_metric(Metric("mean_abs_diff", "mean AD", "", False, 4, _mean_abs_diff))
_OWN = (PSNR, SSIM, MEAN_ABS_DIFF)
