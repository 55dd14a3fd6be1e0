"""Fitting a bench capture: the setup from an image's provenance, the campaign's entry point, the comparison with theory.

`fit_capture` is what a campaign item calls with (image, reference, sampling, pupil,
bench): it fits with the magnification tied to the bench (`BenchLensModel`)
and returns the `RxFit` record.  `compare_with_theory` puts the
fit beside vergence theory and Table 4.2 for the lenses that were on the bench, and says when
the fit and theory disagree beyond the fit's interval.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from vissim.bench.dslr.bench import DslrBench
from vissim.errors import VissimInputError
from vissim.fit.result import RxFit
from vissim.fit.rx_fit import fit_rx
from vissim.optics.rx.prescription import LensPower
from vissim.optics.rx.trial_lens import TrialLens, thesis_table_4_2_lens_power
from vissim.units import m_to_mm

__all__ = ["bench_from_provenance", "rendered_bench", "fit_capture", "compare_with_theory", "fit_bench_item"]

#: Bench fields read from a render's provenance (``inputs.bench`` of ``vissim render bench``).
_BENCH_FIELDS = ("focal_length_mm", "f_number", "focus_distance_mm", "chart_distance_mm", "vertex_distance_mm",
                 "lens_gap_mm", "refractive_index", "clear_aperture_mm", "arcmin_per_px", "size_px")


def _bench_table(provenance: Any) -> dict | None:
    inputs = provenance.get("inputs") if isinstance(provenance, dict) else None
    if not isinstance(inputs, dict):
        return None
    table = inputs.get("bench")
    if isinstance(table, dict) and "f_number" in table:
        return table
    spec = inputs.get("render")  # a campaign render: its RenderSpec
    if isinstance(spec, dict) and "f_number" in spec and "chart_distance_m" in spec:
        return {"focal_length_mm": spec["focal_length_mm"], "f_number": spec["f_number"],
                "focus_distance_mm": m_to_mm(spec["chart_distance_m"]), "chart_distance_mm": m_to_mm(spec["chart_distance_m"]),
                "vertex_distance_mm": spec["vertex_distance_mm"], "arcmin_per_px": spec["arcmin_per_px"],
                "size_px": spec["tile_px"]}
    return None


def bench_from_provenance(provenance: Any) -> DslrBench | None:
    """The bench an image was rendered on, without its lenses (the fit must not read them), or None."""
    table = _bench_table(provenance)
    if table is None:
        return None
    kwargs = {k: table[k] for k in _BENCH_FIELDS if table.get(k) is not None}
    if "size_px" in kwargs:
        kwargs["size_px"] = tuple(kwargs["size_px"])
    try:
        return DslrBench(**kwargs)
    except (TypeError, VissimInputError) as exc:
        raise VissimInputError(f"the image's provenance records a bench vissim cannot rebuild: {exc}") from None


def rendered_bench(provenance: Any) -> DslrBench | None:
    """The bench a render records *with* its trial lenses (to compare a fit with theory), or None.

    Only ``vissim render bench``'s record (``inputs.bench.lenses``) has them; None when there are
    none, or they cannot be rebuilt.  The fit itself never sees them (`bench_from_provenance`).
    """
    bench = bench_from_provenance(provenance)
    table = _bench_table(provenance)
    lenses = table.get("lenses") if table else None
    if bench is None or not isinstance(lenses, list) or not lenses:
        return None
    keys = ("sphere_diopters", "cylinder_diopters", "axis_deg")
    try:
        thin = tuple(TrialLens(*(float(lens[k]) for k in keys)) for lens in lenses)
        return dataclasses.replace(bench, lenses=thin)
    except (TypeError, KeyError, ValueError, VissimInputError):
        return None


def fit_capture(image: np.ndarray, reference: np.ndarray, *, arcmin_per_px: float, pupil_diameter_mm: float,
                bench: DslrBench | None, mode: str = "geometric", **options: Any) -> RxFit:
    """Fit one bench capture against its no-lens reference; the campaign's entry point.

    ``bench`` gives the magnification tie (its lenses are ignored); without it the fit uses no
    magnification and reports the sign undetermined.  ``mode`` is ``"geometric"`` for Mitsuba
    renders (no diffraction), ``"wave"`` for real captures.  ``options`` go to `fit_rx`.
    """
    return fit_rx(image, reference, arcmin_per_px=arcmin_per_px, pupil_diameter_mm=pupil_diameter_mm, mode=mode,
                  magnification="bench" if bench is not None else "none", bench=bench, **options)


def compare_with_theory(fit: RxFit, bench_with_lenses: DslrBench) -> dict:
    """The fit beside vergence theory (the lenses as rendered) and Table 4.2, with a verdict per component.

    ``agrees`` is True when each power-vector component of theory lies in the fit's 95 % interval.
    """
    setup = bench_with_lenses.viewing_setup()
    no_lens = dataclasses.replace(bench_with_lenses, lenses=()).viewing_setup()
    added = np.asarray(setup.defocus_matrix_diopters) - np.asarray(no_lens.defocus_matrix_diopters)
    theory = LensPower.from_power_matrix(added)
    lenses, vertex_mm = bench_with_lenses.lenses, bench_with_lenses.vertex_distance_mm
    table = thesis_table_4_2_lens_power(lenses, vertex_mm).minus_cylinder() if lenses else None
    record = fit.as_json()
    out: dict[str, Any] = {
        "trial_lenses": [str(lens.marked_power) for lens in lenses],
        "vergence_theory": str(theory.minus_cylinder().format(4)),
        "vergence_theory_power_vector": list(theory.power_vector()),
        "table_4_2": None if table is None else table.format(4),
        "fit_status": record["status"],
        "fitted": None,
        "agrees": None,
        "errors_diopters": None,
    }
    if record["status"] != "ok":
        return out
    interval = record["interval_95"]
    keys = ("M_diopters", "J0_diopters", "J45_diopters")
    fitted = tuple(record["power_vector"][k] for k in keys)
    inside = [interval[k][0] <= t <= interval[k][1] for k, t in zip(keys, theory.power_vector())]
    fitted_rx = LensPower.from_power_vector(*fitted).minus_cylinder()
    out["fitted"] = (fitted_rx.format(4) if record["axis_determined"] else
                     f"{fitted_rx.sphere_diopters:+.4f} {fitted_rx.cylinder_diopters:+.4f} (axis undetermined)")
    out["errors_diopters"] = {k: f - t for k, f, t in zip(keys, fitted, theory.power_vector())}
    out["agrees"] = all(inside)
    if not all(inside):
        out["disagreement"] = ("vergence theory lies outside the fit's 95 % interval in "
                               + ", ".join(k.split("_")[0] for k, ok in zip(keys, inside) if not ok))
    if math.isfinite(record["residual_psnr_db"]):
        out["residual_psnr_db"] = record["residual_psnr_db"]
    return out


def fit_bench_item(image: np.ndarray, reference: np.ndarray, bench_with_lenses: DslrBench, *, arcmin_per_px: float,
                   photograph: bool = False) -> dict:
    """A campaign item's fit: ``image`` (the capture through the lenses) against ``reference`` (no lens).

    Geometric optics for a render (Mitsuba renders no diffraction), wave optics for a
    ``photograph``.  Returns ``{"comparison": compare_with_theory(...), "fit": the fit's record}``;
    a fit that raises (bad input) is recorded as failed with its message, not raised: one
    configuration's capture must not stop a campaign.
    """
    try:
        fit = fit_capture(image, reference, arcmin_per_px=arcmin_per_px,
                          pupil_diameter_mm=bench_with_lenses.entrance_pupil_diameter_mm, bench=bench_with_lenses,
                          mode="wave" if photograph else "geometric")
    except VissimInputError as exc:
        return {"comparison": {"fit_status": "failed", "reason": str(exc)}, "fit": None}
    record = fit.as_json()
    comparison = compare_with_theory(fit, bench_with_lenses)
    comparison["reason"] = record["reason"]
    return {"comparison": comparison, "fit": record}
