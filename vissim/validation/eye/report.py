"""The eye bench's part of the report: its rows, its Markdown tables and its terminal summary."""

from __future__ import annotations

import logging
import math
from pathlib import Path

from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.measured_eye import is_measured_name
from vissim.optics.rx.prescription import Prescription
from vissim.validation.engine.figures import Figure
from vissim.validation.engine.metrics import PSNR, SSIM, added_metrics, floor_column, metric_float
from vissim.validation.engine.protocol import ReportParts
from vissim.validation.engine.reading import PERFECT_MARGIN_DB, how_to_read, own_error_fraction, perfect_score_db
from vissim.validation.engine.report import format_number
from vissim.validation.engine.tiles import TILE_ZOOM, tile_strip
from vissim.validation.eye.item import SELF_CHECK_MARGIN_DB, self_check_passes
from vissim.validation.eye.simulate import COSTS, SIMULATIONS

log = logging.getLogger(__name__)

__all__ = ["eye_report", "summary_lines", "configuration_label", "self_check_passes", "MTF_FREQUENCIES_CPD"]

WORDS = {
    "traced_rays": "ray trace (self-check)",
    "reduced_geometric": "reduced eye, ray optics",
    "reduced_wave": "reduced eye, wave optics",
    "thesis": "thesis method",
    "schematic": "the eye's wavefront, ray optics",
    "schematic_wave": "the eye's wavefront, wave optics",
}
INTRO = (
    "Each configuration is a Sloan letter at 6 m seen by the Navarro (1985) schematic eye, rendered twice with "
    "different seeds, and simulated by each of vissim's eye models. Ray-optics simulations "
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


#: The simulated eye's MTF is given at these spatial frequencies (cycles per degree): a LogMAR 1.0 letter's strokes
#: are 3 cpd, LogMAR 0.5's about 10, and 30 cpd is the finest a 20/20 letter holds.
MTF_FREQUENCIES_CPD = (5.0, 15.0, 30.0)
#: A difference tile's full scale, relative radiance (white 1): ±0.1 white is black or white in the tile.
DIFFERENCE_RANGE = 0.1
#: The command that makes this page's run (the committed report's: `vissim validate` of its campaign file).
LIMITATIONS = (
    "### Known limitations\n\n"
    "* The wave-optics reference is the render blurred by the pupil's in-focus diffraction, not a wave-optics "
    "render: near focus with spherical aberration the two differ (the first paragraph), so there a wave-optics score "
    "below +3 dB does not mean the simulation is wrong.\n"
    "* Photopic light is rendered at fewer wavelengths than it is simulated at, and its renders are noisier (a "
    "lower noise floor); the ray-optics simulation of the eye's wavefront is not made for it (13 ray PSFs take "
    "about a minute an item).\n"
    "* Each score is measured once, on one 64 × 64 tile: scores of a perfect simulation scatter by a few tenths of a "
    "dB around their expected value (the self-check's spread below shows how much).\n\n")


def configuration_label(c: dict) -> str:
    """A configuration's eye and setup in words: pupil, accommodation, field, light, trial lens (minus cylinder)."""
    light = "photopic light" if c["spectrum"] == "photopic" else f"{c['wavelength_nm']:g} nm light"
    lens = "no lens" if c["lens"] is None else f"trial lens {Prescription(*c['lens']).minus_cylinder().format()}"
    x, y = c["field_deg"]
    field = "on axis" if (x, y) == (0, 0) else (f"{x:g}° field" if y == 0 else f"field {x:g}°, {y:g}° (x, y)")
    eye = ""
    if c.get("rx") is not None:
        eye = (f"eye Rx {Prescription(**c['rx']).minus_cylinder().format_exact()} "
               f"(at a {c['vertex_mm']:g} mm spectacle plane), ")
    if is_measured_name(c.get("model")):
        eye = f"{c['model']}, chart at {c['chart_distance_m']:g} m, " + eye
    return f"{eye}{c['pupil_mm']:g} mm pupil, {c['accommodation_diopters']:g} D accommodation, {field}, {light}, {lens}"


def letter_label(c: dict) -> str:
    """The chart's letter: Sloan letter, LogMAR and its height (5 x 10^LogMAR arcmin)."""
    return f"Sloan {c['letter']}, LogMAR {c['logmar']:g} ({5.0 * 10.0 ** c['logmar']:.3g} arcmin tall)"


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


def _check_row(result: dict) -> dict:
    return next(x for x in result["rows"] if x["simulation"] == "traced_rays")


def _self_check_table(results: list[dict]) -> str:
    scores = [_check_row(r)["over_floor_db"] for r in results]
    mean = sum(scores) / len(scores)
    spread = math.sqrt(sum((s - mean) ** 2 for s in scores) / max(1, len(scores) - 1))
    error = own_error_fraction(SELF_CHECK_MARGIN_DB)
    lines = [
        "### Geometric self-check: the bench and the scoring checked by an independent ray trace\n",
        (f"It passes on two criteria. (1) At least +{SELF_CHECK_MARGIN_DB:g} dB over the noise floor. A perfect, "
         f"noise-free simulation scores +{PERFECT_MARGIN_DB:.2f} dB on average (How to read this page); +"
         f"{SELF_CHECK_MARGIN_DB:g} dB allows the simulation an error of its own of at most {100 * error:.0f} % of "
         f"one render's noise power (its RMS at most {math.sqrt(error):.2f} of the noise's). A perfect simulation's "
         f"measured score scatters because each is measured once on one tile: here the {len(scores)} self-checks "
         f"score {min(scores):+.2f} to {max(scores):+.2f} dB (mean {mean:+.2f}, standard deviation {spread:.2f} dB), "
         f"so +{SELF_CHECK_MARGIN_DB:g} dB lies {(PERFECT_MARGIN_DB - SELF_CHECK_MARGIN_DB) / max(spread, 1e-9):.0f} "
         "standard deviations below a perfect score: a real error of that size fails, chance does not. "
         "(2) An SSIM against the render at least the two renders' SSIM with each other. SSIM is computed "
         "against the noisy render, so it is low wherever the render is noisy (photopic light: about 0.6), for a "
         "perfect simulation too; the two renders' own SSIM is the most it can mean, so the simulation must "
         "resemble the render at least as much as a second render does.\n"),
        "| configuration | noise floor PSNR (dB) | ray trace, dB over floor | SSIM, ray trace vs render | "
        "SSIM, render vs render | passes |",
        "|---|---|---|---|---|---|"]
    for r in results:
        row = _check_row(r)
        floor_ssim = metric_float(r["noise_floor"].get(SSIM.name))
        lines.append(f"| {r['configuration']['name']} | {r['noise_floor'][PSNR.name]:.2f} | {row['over_floor_db']:+.2f} | "
                     f"{row[SSIM.name]:.3f} | {format_number(floor_ssim, 3)} | "
                     f"{'yes' if self_check_passes(r) else 'NO'} |")
    return "\n".join(lines) + "\n\n"


def _simulations_table(results: list[dict]) -> str:
    lines = ["### Simulations against the render (dB over the noise floor)\n",
             (f"+{PERFECT_MARGIN_DB:.2f} dB: a perfect simulation; 0 dB: as far from the render as a second render; "
              "below 0 dB the simulation differs from the render. '-': not made (the ray-optics simulation of the "
              "eye's wavefront is made for one-wavelength light only). Wave-optics columns can score far above "
              "+3 dB; the next section says why.\n"),
             "| configuration | " + " | ".join(WORDS[s] for s in SIMULATIONS) + " |",
             "|---|" + "---|" * len(SIMULATIONS)]
    for r in results:
        by = {x["simulation"]: x for x in r["rows"]}
        lines.append(f"| {r['configuration']['name']} | " + " | ".join(
            f"{by[s]['over_floor_db']:+.2f}" if s in by else "-" for s in SIMULATIONS) + " |")
    return "\n".join(lines) + "\n\n"


def _above_three_db(results: list[dict], optics: dict) -> str:
    wave = [(r["configuration"]["name"], x["simulation"], x["over_floor_db"]) for r in results for x in r["rows"]
            if x["simulation"] in SIMULATIONS and x["reference"] != "render"]
    ray = [(r["configuration"]["name"], x["simulation"], x["over_floor_db"]) for r in results for x in r["rows"]
           if x["simulation"] in SIMULATIONS and x["reference"] == "render"]
    text = ["### Why some scores are far above +3 dB\n",
            (f"A perfect simulation scores +{PERFECT_MARGIN_DB:.2f} dB against the render it is compared with only if "
             "that reference holds one render's noise. The ray-optics simulations are compared with the render itself: "
             f"their highest score here is {max(s for _, _, s in ray):+.2f} dB"
             if ray else "")]
    ceilings = {name: o["perfect_wave_db"] for name, o in optics.items() if o and "perfect_wave_db" in o}
    best = max(wave, key=lambda w: w[2]) if wave else None
    line = ((". " if ray else "") +
            "The wave-optics simulations are compared with the render blurred by the pupil's diffraction (the render "
            "has none). That blur averages neighbouring pixels and so removes most of the render's noise: the "
            "reference keeps a fraction Σh² of one render's noise power (h: the diffraction PSF's weights on the "
            "image's pixels; the noise is independent from pixel to pixel), while the noise floor is measured on "
            "the unblurred renders. A perfect wave-optics simulation therefore scores 10·log10(2 / Σh²), not "
            "10·log10(2).")
    if ceilings:
        values = sorted(ceilings.values())
        line += (f" Here that is {values[0]:+.1f} to {values[-1]:+.1f} dB (the column 'a perfect wave simulation' "
                 "in the next table, computed from each configuration's diffraction PSF): the larger the pupil, "
                 "the narrower its diffraction and the less noise it removes.")
    if best is not None:
        name, simulation, score = best
        ceiling = ceilings.get(name)
        line += (f" The highest wave-optics score, {score:+.2f} dB ({name}, {WORDS.get(simulation, simulation)}), "
                 + (f"is within that configuration's {ceiling:+.2f} dB." if ceiling is not None and score <= ceiling + 0.5
                    else f"is against {ceiling:+.2f} dB for a perfect one there." if ceiling is not None else "."))
    text[1] += line
    text.append(" Read a wave-optics score against that configuration's perfect score, not against +3 dB.\n")
    return text[0] + "\n" + text[1] + text[2] + "\n"


def _optics_table(results: list[dict], optics: dict) -> str:
    freqs = " | ".join(f"MTF {f:g}" for f in MTF_FREQUENCIES_CPD)
    lines = ["### The simulated eye's optics beside its score\n",
             ("The schematic eye as simulated (the eye's wavefront, wave optics, in the configuration's light, with its "
              "trial lens and the chart's vergence): its Strehl ratio and its MTF at "
              f"{', '.join(f'{f:g}' for f in MTF_FREQUENCIES_CPD)} cycles per degree (MTF 5 … MTF 30), beside "
              "its score (dB over the floor) and the score a perfect wave-optics simulation has there. Off axis the MTF "
              "differs by direction: a row for the tangential (along the field's meridian) and one for the sagittal. A "
              "low Strehl ratio or MTF says the eye blurs much; it is not a fault of the simulation.\n"),
             f"| configuration | score (dB) | perfect score (dB) | Strehl | {freqs} |",
             "|---|---|---|---|" + "---|" * len(MTF_FREQUENCIES_CPD)]
    for r in results:
        name = r["configuration"]["name"]
        by = {x["simulation"]: x for x in r["rows"]}
        o = optics.get(name) or {}
        score = f"{by['schematic_wave']['over_floor_db']:+.2f}" if "schematic_wave" in by else "-"
        mtf = o.get("mtf") or {"": [math.nan] * len(MTF_FREQUENCIES_CPD)}
        for k, (direction, values) in enumerate(mtf.items()):
            label = name if direction in ("", "radial") else f"{name}, {direction}"
            head = [score, _signed(o.get("perfect_wave_db")), _strehl(o.get("strehl"))] if k == 0 else [
                "″", "″", "″"]
            lines.append(f"| {label} | " + " | ".join(head) + " | "
                         + " | ".join(format_number(float(v), 2) for v in values) + " |")
    return "\n".join(lines) + "\n\n"


def _strehl(value) -> str:
    """A Strehl ratio: 3 decimals, or one significant digit below 0.01 (a defocused eye's 0.0004 is not 0)."""
    if value is None or not math.isfinite(value):
        return "—"
    return f"{value:.3f}" if value >= 0.01 else f"{value:.1g}"


def _signed(value) -> str:
    return "—" if value is None or not math.isfinite(value) else f"{value:+.1f}"


def _costs_table(results: list[dict]) -> str:
    lines = ["### What each reduced-eye assumption costs (dB lost against the render)\n",
             "The schematic eye's wave-optics simulation, with one of the reduced eye's simplifications put in, "
             "scored against the render blurred by the pupil's diffraction: the PSNR it loses. Spherical "
             "aberration: the eye's higher-order "
             "aberrations dropped. Chromatic model: Thibos's chromatic-eye formula instead of the traced "
             "dispersion (photopic light only). Field dependence: the on-axis PSF used off axis. Pupil "
             "definition: the iris's diameter taken as the pupil's (the entrance pupil is the iris magnified "
             "by the cornea). Spectacle magnification: the trial lens's magnification left out. '-': the "
             "assumption does not apply to that configuration.\n",
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
    lines = ["### Configurations\n",
             "Pupil sizes are the iris's (the entrance pupil is about 13 % larger). Accommodation 0 D: the eye "
             "relaxed. Every prescription in minus cylinder.\n",
             "| configuration | eye and setup | letter |", "|---|---|---|"]
    for r in results:
        c = r["configuration"]
        lines.append(f"| {c['name']} | {configuration_label(c)} | {letter_label(c)} |")
    return "\n".join(lines) + "\n\n"


def _verdict(results: list[dict], optics: dict) -> str:
    passed = [r for r in results if self_check_passes(r)]
    lines = ["### Verdict\n"]
    failed = [r["configuration"]["name"] for r in results if not self_check_passes(r)]
    lines.append(f"* Self-check: {len(passed)} of {len(results)} configurations pass"
                 + (f"; failing: {', '.join(failed)}." if failed else
                    " (the bench, its renders and the scoring agree with an independent ray trace)."))
    for simulation in SIMULATIONS[1:]:
        scored = [(x["over_floor_db"], r["configuration"]["name"]) for r in results for x in r["rows"]
                  if x["simulation"] == simulation]
        if not scored:
            continue
        at_floor = sum(s >= 0.0 for s, _ in scored)
        worst = min(scored)
        lines.append(f"* {WORDS[simulation]}: {at_floor} of {len(scored)} at or above the noise floor (0 dB); lowest "
                     f"{worst[0]:+.2f} dB ({worst[1]}).")
    ceilings = [o["perfect_wave_db"] for o in optics.values() if o and "perfect_wave_db" in o]
    if ceilings:
        low, high = f"{min(ceilings):+.1f}", f"{max(ceilings):+.1f}"
        span = low if low == high else f"{low} to {high}"
        lines.append(f"* Read the wave-optics scores against what a perfect one scores here, {span} dB, not "
                     f"+{PERFECT_MARGIN_DB:.2f} dB (Why some scores are far above +3 dB).")
    lines.append("* The reduced eye and the thesis method leave out what the schematic eye has (its higher-order "
                 "aberrations, its field dependence, its entrance pupil); their scores below 0 dB measure those "
                 "omissions, priced one by one in What each reduced-eye assumption costs.")
    return "\n".join(lines) + "\n\n"


def _configuration_of(c: dict):
    """The `EyeConfiguration` a result's configuration record was written from."""
    from dataclasses import fields

    from vissim.validation.eye.schema import EyeConfiguration

    known = {f.name for f in fields(EyeConfiguration)}
    kwargs = {k: v for k, v in c.items() if k in known}
    for key in ("field_deg", "size_px", "lens"):
        if kwargs.get(key) is not None:
            kwargs[key] = tuple(kwargs[key])
    if kwargs.get("rx") is not None:
        kwargs["rx"] = Prescription(**kwargs["rx"])
    kwargs["surfaces"] = tuple(tuple(s) for s in kwargs.get("surfaces") or ())
    return EyeConfiguration(**kwargs)


def eye_optics(c: dict) -> dict:
    """The simulated eye's Strehl ratio, its MTF at `MTF_FREQUENCIES_CPD` ({direction: values}), the diffraction
    PSF of the wave-optics reference and the score a perfect wave-optics simulation has against it
    (`perfect_score_db` of that PSF's Σh²)."""
    import numpy as np

    from vissim.optics.eyes.report import eye_mtf
    from vissim.optics.psf.compute import strehl_ratio
    from vissim.validation.eye.renders import configuration_bench
    from vissim.validation.eye.simulate import EyeScene, diffraction_psf

    bench = configuration_bench(_configuration_of(c))
    view, light = bench.view, bench.light
    psf = diffraction_psf(EyeScene(bench, 1))
    kernel = np.asarray(psf.data, np.float64)
    kernel = kernel / kernel.sum()
    out = {"diffraction_psf": psf, "perfect_wave_db": perfect_score_db(float((kernel ** 2).sum()))}
    if is_measured_name(c.get("model")):
        return out  # its wavefront is the data's, on the phase plane: not the traced eye's below
    front = view.spectral_wavefront(light.wavelengths_nm, focus_nm=light.focus_nm, field_deg=view.field_deg)
    out["mtf"] = eye_mtf(front, list(light.wavelengths_nm), MTF_FREQUENCIES_CPD, field_deg=view.field_deg,
                         weights=list(light.weights))
    if light.focus_nm not in light.wavelengths_nm:  # white light: the Strehl ratio at its focus wavelength
        front = view.spectral_wavefront((light.focus_nm,), focus_nm=light.focus_nm, field_deg=view.field_deg)
    out["strehl"] = strehl_ratio(front, wavelength_nm=light.focus_nm)
    return out


def _all_optics(results: list[dict]) -> dict:
    optics = {}
    for r in results:
        try:
            optics[r["configuration"]["name"]] = eye_optics(r["configuration"])
        except (VissimInputError, ValueError, KeyError, TypeError) as error:
            log.warning("report: the optics of %s were skipped (%s: %s)", r["configuration"]["name"],
                        type(error).__name__, error)
            optics[r["configuration"]["name"]] = {}
    return optics


def _tile(result: dict, run_dir: Path, optics: dict) -> Figure | None:
    """The render, the self-check and its difference, the eye's wavefront in wave optics and its difference from
    the render blurred by diffraction (its reference), as one strip of tiles."""
    import numpy as np

    from vissim.imageio import read_image
    from vissim.optics.blur.convolve import blur_image

    images = result.get("images") or {}
    if "render" not in images or "traced_rays" not in images:
        return None
    load = {name: np.asarray(read_image(run_dir / rel).pixels, np.float64).squeeze() for name, rel in images.items()}
    render, traced = load["render"], load["traced_rays"]
    panels = [render, traced, traced - render]
    labels = ["render", "ray trace\n(self-check)", "difference\n(±0.1 white)"]
    kinds = ["grey", "grey", "difference"]
    wave = load.get("schematic_wave")
    kernel = optics.get("diffraction_psf")
    if wave is not None and kernel is not None:
        step = result["configuration"]["arcmin_per_px"]
        reference = np.asarray(blur_image(render, kernel, arcmin_per_px=step, padding="edge"), np.float64)
        panels += [wave, wave - reference]
        labels += ["eye's wavefront,\nwave optics", "difference from\nrender + diffraction"]
        kinds += ["grey", "difference"]
    by = {x["simulation"]: x for x in result["rows"]}
    name = result["configuration"]["name"]
    alt = (f"{name}: " + "; ".join(labels).replace("\n", " ") + f". Self-check {by['traced_rays']['over_floor_db']:+.2f} dB"
           + (f", eye's wavefront in wave optics {by['schematic_wave']['over_floor_db']:+.2f} dB" if "schematic_wave" in by
              and len(panels) > 3 else "") + " over the noise floor. Differences: mid-grey none, white +0.1, black "
           "-0.1 of the chart's white.")
    return Figure(f"tile_{_slug(name)}.png", tile_strip(panels, kinds, labels, DIFFERENCE_RANGE), alt,
                  {"configuration": name})


def _slug(name: str) -> str:
    import re

    text = re.sub(r"-(?=\d)", "minus", name.replace("°", "deg").replace("+", "plus"))  # a sign, not a hyphen
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower()


def eye_report(results: list[dict], run_dir: Path | None = None, record: dict | None = None) -> ReportParts:
    results = sorted(results, key=lambda r: r["configuration"]["name"])
    measured = any(is_measured_name(r["configuration"].get("model")) for r in results)
    optics = _all_optics(results)
    verdict = _verdict(results, optics)
    body = (INTRO + (MEASURED_INTRO if measured else "") + _setups_table(results)
            + _self_check_table(results) + _simulations_table(results) + _above_three_db(results, optics)
            + _optics_table(results, optics) + _costs_table(results) + LIMITATIONS)
    figures = {}
    if run_dir is not None:
        for r in results:
            figure = _tile(r, Path(run_dir), optics.get(r["configuration"]["name"]) or {})
            if figure is not None:
                figures[f"Render and simulations: {r['configuration']['name']}"] = figure
    if figures:
        body += ("### Render, simulation and difference, per configuration\n\n"
                 "Each strip below, left to right: the render; the self-check's ray trace and its difference from the "
                 "render (render noise only, if the check passes); the eye's wavefront in wave optics and its "
                 "difference from its reference, the render blurred by diffraction. Grey tiles show relative radiance "
                 f"at display gamma; difference tiles are linear, mid-grey for none, white +{DIFFERENCE_RANGE:g} and "
                 f"black -{DIFFERENCE_RANGE:g} of the chart's white. Image pixels are {TILE_ZOOM} × {TILE_ZOOM} "
                 "screen pixels.\n\n")
    scores = ("**Reading a score.** The noise floor's two renders each hold the Monte-Carlo noise σ², so their "
              "squared difference is 2σ². A simulation is compared with one render: a perfect, noise-free one differs "
              f"by σ² and scores 10·log10(2) = +{PERFECT_MARGIN_DB:.2f} dB over the floor, on average. A simulation "
              "with an error e² of its own scores 10·log10(2σ² / (σ² + e²)): 0 dB when e² = σ², below 0 dB when its "
              "error exceeds the render's noise. Scores far above +3 dB occur where the reference holds less than one "
              "render's noise: the wave-optics columns (a section below explains and computes them).\n")
    shown = " ".join(f"{name} {figure.alt}" for name, figure in figures.items())  # the engine appends them
    tables = verdict + how_to_read(verdict + body + shown, scores) + body
    return ReportParts("Schematic-eye validation" if not measured else "Measured-eye validation", _rows(results),
                       tables, figures)


def summary_lines(rows: list[dict]) -> list[str]:
    checks = [r for r in rows if r["simulation"] == "traced_rays"]
    lines = []
    if checks:
        worst = min(checks, key=lambda r: r["over_floor_db"])
        passed = sum(r["over_floor_db"] >= SELF_CHECK_MARGIN_DB for r in checks)
        lines.append(f"geometric self-check: {passed}/{len(checks)} configurations at least "
                     f"+{SELF_CHECK_MARGIN_DB:g} dB over the noise floor (lowest {worst['over_floor_db']:+.2f} dB, "
                     f"{worst['configuration']}); tables.md adds its SSIM criterion")
    for simulation in SIMULATIONS[1:]:
        values = [r["over_floor_db"] for r in rows if r["simulation"] == simulation]
        if values:
            lines.append(f"{WORDS[simulation]}: {sum(values) / len(values):+.2f} dB over the floor on average "
                         f"(lowest {min(values):+.2f} dB)")
    return lines
