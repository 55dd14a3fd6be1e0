"""The report's prescription-fit table (``fit_rx = true``): per configuration, the fit beside theory.

One row per configuration with trial lenses: the lenses, the power vergence theory says they
add at the camera (the lenses as rendered), the thesis's Table 4.2 power, the fitted power
with its 95 % interval (half-widths in M, J0, J45) and the verdict: where vergence theory lies
outside the interval the row says so (`vissim.fit.capture.compare_with_theory`).
"""

from __future__ import annotations

from vissim.validation.dslr.schema import lens_label_of

__all__ = ["fit_table"]

_KEYS = ("M_diopters", "J0_diopters", "J45_diopters")


def _per_key(values: dict | None, fmt) -> str:
    """``fmt`` of M / J0 / J45 joined by " / ", or "—" without values."""
    return " / ".join(fmt(values[k]) for k in _KEYS) if values else "—"


def _verdict(comparison: dict) -> str:
    status = comparison.get("fit_status")
    if status != "ok":
        reason = comparison.get("reason")
        return f"fit {status}" + (f": {reason}" if reason else "")
    if comparison.get("agrees"):
        return "agrees (theory inside the interval)"
    return "**disagrees**: " + comparison.get("disagreement", "vergence theory outside the interval")


def fit_table(results: list[dict]) -> str:
    """The markdown table, or "" when no item has a fit."""
    rows = [r for r in results if r.get("fit_rx")]
    if not rows:
        return ""
    out = ["### Prescription fit of each capture (`fit_rx`)\n",
           "| configuration | trial lens | vergence theory | Table 4.2 | fitted | 95 % half-width M / J0 / J45 (D) "
           "| fit − theory M / J0 / J45 (D) | verdict |",
           "|---|---|---|---|---|---|---|---|"]
    for result in rows:
        comparison = result["fit_rx"]["comparison"]
        record = result["fit_rx"].get("fit") or {}
        half_widths = _per_key(record.get("interval_95"), lambda lo_hi: f"{0.5 * (lo_hi[1] - lo_hi[0]):.3f}")
        errors = _per_key(comparison.get("errors_diopters"), lambda error: f"{error:+.3f}")
        name = result["configuration"]["name"]
        lenses = lens_label_of(result)
        out.append(f"| {name} | {lenses} | {comparison.get('vergence_theory', '—')} | "
                   f"{comparison.get('table_4_2') or '—'} | {comparison.get('fitted') or '—'} | "
                   f"{half_widths} | {errors} | {_verdict(comparison)} |")
    out.append("")
    out.append("The fit turns the no-lens render (or capture) into the capture through the lenses "
               "(`vissim fit-rx`: geometric optics for a render, wave optics for a photograph) with the "
               "magnification tied to the bench; the power is the sphero-cylinder added at the camera. "
               "Vergence theory is that power for the lenses as rendered (crown glass, their thickness); "
               "Table 4.2 is the thesis's vertex-corrected power. The interval is the fit's noise (the "
               "residual's spatial correlation included) and the stated model error, added in quadrature.\n")
    return "\n".join(out)
