"""The eye bench's part of the report: its rows, its Markdown tables and its terminal summary."""

from __future__ import annotations

import math

from vissim.optics.eyes.measured.measured_eye import is_measured_name
from vissim.optics.rx.prescription import Prescription
from vissim.validation.engine.metrics import PSNR, SSIM, added_metrics, floor_column, metric_float
from vissim.validation.engine.protocol import ReportParts
from vissim.validation.eye.item import SELF_CHECK_MARGIN_DB
from vissim.validation.eye.simulate import COSTS, SIMULATIONS

__all__ = ["eye_report", "summary_lines", "configuration_label"]

WORDS = {
    "traced_rays": "ray trace (self-check)",
    "reduced_geometric": "reduced eye, ray optics",
    "reduced_wave": "reduced eye, wave optics",
    "thesis": "thesis setup",
    "schematic": "the eye's wavefront, ray optics",
    "schematic_wave": "the eye's wavefront, wave optics",
}
INTRO = (
    "Each configuration is a letter seen by an eye, rendered twice with different seeds. "
    "A simulation is scored by its PSNR against the render minus the PSNR of the two renders against "
    "each other (the noise floor): a simulation that matches the render to its noise scores about +3 dB, "
    "one below 0 dB differs from the render by more than the render's own noise. Ray-optics simulations "
    "are scored against the render itself; the ray-optics simulation of the eye's wavefront (a schematic eye's "
    "traced one) is the wavefront that the wave simulation diffracts, so it checks that wavefront, its vergences and its "
    "field dependence against the render directly (one-wavelength light only). Wave-optics simulations "
    "are scored against the render blurred by the pupil's diffraction (the render has none). That reference "
    "is ray optics blurred by diffraction, not wave optics: with spherical aberration the two are best "
    "focused about a third of the primary spherical aberration apart (0.05-0.08 D for a 3-4 mm pupil), so "
    "near focus even an exact wave simulation of the traced eye stays below it (measured on the traced "
    "wavefront alone, without a render: 31.6 dB at 3 mm and 34.4 dB at 4 mm, against a letter); with a "
    "dioptre or more of defocus, or off axis, the gap is small against the blur.\n\n")
MEASURED_INTRO = (
    "A measured eye (named by its dataset, subject and eye) is rendered as its base eye, Navarro 1985, with a "
    "phase plane at its entrance pupil that gives it the measured wavefront at the chart's field; its "
    "simulations use that wavefront (the data's, over the data's pupil). The two pupils differ off axis: the "
    "render's is the base eye's entrance pupil, a circle normal to the optical axis, the simulations' the "
    "data's circle normal to the measuring beam, so at 20 and 30 degrees the rendered pupil is 6 % and 13 % "
    "narrower across the field's meridian. The self-check traces the rendered eye and its phase plane, so it "
    "is not affected.\n\n")


def configuration_label(c: dict) -> str:
    light = "photopic" if c["spectrum"] == "photopic" else f"{c['wavelength_nm']:g} nm"
    lens = "" if c["lens"] is None else f", lens {c['lens'][0]:+g}" + (
        f" {c['lens'][1]:+g} x {c['lens'][2]:g}" if c["lens"][1] else "") + " D"
    field = c["field_deg"]
    eye = "" if c.get("rx") is None else f"eye Rx {Prescription(**c['rx']).format_exact()} at {c['vertex_mm']:g} mm, "
    if is_measured_name(c.get("model")):
        eye = f"{c['model']}, chart at {c['chart_distance_m']:g} m, " + eye
    return (f"{eye}{c['pupil_mm']:g} mm, {c['accommodation_diopters']:g} D acc., field {field[0]:g},{field[1]:g} deg, "
            f"{light}{lens}")


def _rows(results: list[dict]) -> list[dict]:
    rows = []
    for result in results:
        c = result["configuration"]
        for row in result["rows"]:
            rows.append({"configuration": c["name"], "setup": configuration_label(c), "simulation": row["simulation"],
                         "reference": row["reference"], PSNR.name: row[PSNR.name], SSIM.name: row[SSIM.name],
                         floor_column(PSNR): result["noise_floor"][PSNR.name],
                         "over_floor_db": row["over_floor_db"],
                         **{m.name: metric_float(row.get(m.name)) for m in added_metrics()}})
    return rows


def _self_check_table(results: list[dict]) -> str:
    lines = ["### Geometric self-check (ray trace against the render; must be at least "
             f"+{SELF_CHECK_MARGIN_DB:g} dB)\n",
             "| configuration | setup | noise floor PSNR dB | ray trace dB over floor | SSIM | passes |",
             "|---|---|---|---|---|---|"]
    for r in results:
        row = next(x for x in r["rows"] if x["simulation"] == "traced_rays")
        lines.append(f"| {r['configuration']['name']} | {configuration_label(r['configuration'])} | "
                     f"{r['noise_floor'][PSNR.name]:.2f} | {row['over_floor_db']:+.2f} | {row[SSIM.name]:.4f} | "
                     f"{'yes' if row['over_floor_db'] >= SELF_CHECK_MARGIN_DB else 'NO'} |")
    return "\n".join(lines) + "\n\n"


def _simulations_table(results: list[dict]) -> str:
    lines = ["### Simulations against the render (dB over the noise floor)\n",
             "| configuration | " + " | ".join(WORDS[s] for s in SIMULATIONS) + " |",
             "|---|" + "---|" * len(SIMULATIONS)]
    for r in results:
        by = {x["simulation"]: x for x in r["rows"]}
        lines.append(f"| {r['configuration']['name']} | " + " | ".join(
            f"{by[s]['over_floor_db']:+.2f}" if s in by else "-" for s in SIMULATIONS) + " |")
    return "\n".join(lines) + "\n\n"


def _costs_table(results: list[dict]) -> str:
    lines = ["### What each reduced-eye assumption costs (dB lost against the render)\n",
             "The schematic eye's wave-optics simulation, with one of the reduced eye's simplifications put in, "
             "scored against the render blurred by the pupil's diffraction: the PSNR it loses. Spherical "
             "aberration: the eye's higher-order "
             "aberrations dropped. Chromatic model: Thibos's chromatic-eye formula instead of the traced "
             "dispersion (photopic light only). Field dependence: the on-axis PSF used off axis. Pupil "
             "definition: the iris's diameter taken as the pupil's (the entrance pupil is the iris magnified "
             "by the cornea). Spectacle magnification: the trial lens's magnification left out.\n",
             "| assumption | configurations | mean dB lost | smallest | largest |", "|---|---|---|---|---|"]
    for assumption in COSTS:
        values = [r["costs_db"][assumption] for r in results if assumption in r["costs_db"]]
        finite = [v for v in values if math.isfinite(v)]
        if not finite:
            lines.append(f"| {assumption} | 0 | - | - | - |")
            continue
        lines.append(f"| {assumption} | {len(finite)} | {sum(finite) / len(finite):.2f} | {min(finite):.2f} | "
                     f"{max(finite):.2f} |")
    lines.append("\n| configuration | " + " | ".join(COSTS) + " |")
    lines.append("|---|" + "---|" * len(COSTS))
    for r in results:
        lines.append(f"| {r['configuration']['name']} | " + " | ".join(
            f"{r['costs_db'][a]:.2f}" if a in r["costs_db"] else "-" for a in COSTS) + " |")
    return "\n".join(lines) + "\n\n"


def _setups_table(results: list[dict]) -> str:
    lines = ["### Configurations\n", "| configuration | setup | letter |", "|---|---|---|"]
    for r in results:
        c = r["configuration"]
        lines.append(f"| {c['name']} | {configuration_label(c)} | {c['letter']} (logMAR {c['logmar']:g} as printed) |")
    return "\n".join(lines) + "\n\n"


def eye_report(results: list[dict]) -> ReportParts:
    results = sorted(results, key=lambda r: r["configuration"]["name"])
    measured = any(is_measured_name(r["configuration"].get("model")) for r in results)
    tables = (INTRO + (MEASURED_INTRO if measured else "") + _setups_table(results) + _self_check_table(results) + _simulations_table(results)
              + _costs_table(results))
    return ReportParts("eye-bench validation", _rows(results), tables, {})


def summary_lines(rows: list[dict]) -> list[str]:
    checks = [r for r in rows if r["simulation"] == "traced_rays"]
    lines = []
    if checks:
        worst = min(checks, key=lambda r: r["over_floor_db"])
        passed = sum(r["over_floor_db"] >= SELF_CHECK_MARGIN_DB for r in checks)
        lines.append(f"geometric self-check: {passed}/{len(checks)} configurations at least "
                     f"+{SELF_CHECK_MARGIN_DB:g} dB over the noise floor (lowest {worst['over_floor_db']:+.2f} dB, "
                     f"{worst['configuration']})")
    for simulation in SIMULATIONS[1:]:
        values = [r["over_floor_db"] for r in rows if r["simulation"] == simulation]
        if values:
            lines.append(f"{WORDS[simulation]}: {sum(values) / len(values):+.2f} dB over the floor on average "
                         f"(lowest {min(values):+.2f} dB)")
    return lines
