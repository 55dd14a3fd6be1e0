"""What a report page says so that a reader needs neither the code nor another page: its terms defined on the
page (`how_to_read`), the scores' arithmetic (`perfect_score_db`, `own_error_fraction`) and how the page was
built (`how_built`).

`GLOSSARY` holds every term a validation report may use, each with the words that show it is used; `how_to_read`
writes the "How to read this page" section with the definitions of the terms the rest of the page uses, so a page
never uses a term it does not define (tests/validation/test_report_reads.py checks every report kind's page).
"""

from __future__ import annotations

import math
import re

__all__ = ["GLOSSARY", "how_to_read", "terms_used", "how_built", "perfect_score_db", "own_error_fraction",
           "ONE_GREY_LEVEL_PSNR_DB", "PERFECT_MARGIN_DB"]

#: What a perfect, noise-free simulation scores over the noise floor on average: the floor's two
#: renders hold the noise twice (MSE 2 sigma^2), a comparison with one render once (sigma^2).
PERFECT_MARGIN_DB = 10.0 * math.log10(2.0)
#: The PSNR of an image whose RMS difference from its reference is one grey level of an 8-bit display (1/255 of
#: white): a difference no display shows.  The score of a configuration with no blur to simulate.
ONE_GREY_LEVEL_PSNR_DB = 20.0 * math.log10(255.0)

#: term -> (the words that show the page uses it (regular expressions, case-insensitive), its definition).
GLOSSARY: dict[str, tuple[tuple[str, ...], str]] = {
    "render": ((r"\brenders?\b", r"\brendered\b"),
               "the ground truth: the scene (chart, trial lens, camera or eye) rendered by physically based ray "
               "tracing (Mitsuba 3), independently of vissim's blur simulations. Ray tracing has no diffraction."),
    "spp": ((r"\bspp\b", r"samples per pixel"),
            "samples per pixel of a render: its rays per pixel. The render's Monte-Carlo noise falls as 1/√spp."),
    "noise floor": ((r"noise floor", r"\bfloor\b"),
                    "the PSNR of the two renders of one configuration (different random seeds) against each other: "
                    "how alike two equally good renders are. A simulation cannot be checked more finely than this."),
    "PSNR": ((r"\bPSNR\b",),
             "peak signal-to-noise ratio, 10·log10(1 / mean squared difference) in dB for images from 0 (black) to "
             "1 (white). +10 dB is a tenth of the squared difference. A PSNR alone depends on the letter and the "
             "noise; read it against the noise floor."),
    "dB over the floor": ((r"over (the )?(noise )?floor", r"minus the (noise )?floor", r"dB over"),
                          "a simulation's score: its PSNR against the render minus the noise floor. 0 dB: the "
                          f"simulation differs from the render as much as a second render does. +{PERFECT_MARGIN_DB:.2f} dB: a perfect, "
                          "noise-free simulation (see below). Below 0 dB the simulation itself differs from the "
                          "render."),
    "SSIM": ((r"\bSSIM\b",),
             "structural similarity (Wang et al. 2004; 1 = identical), computed against the noisy render, so even a "
             "perfect simulation stays below 1; read it against the two renders' own SSIM."),
    "self-check": ((r"self-check",),
                   "the geometric self-check: vissim's own ray trace of the same optics (numpy, not Mitsuba), blurred "
                   "into the chart and scored against the render. It tests the bench and the scoring, not an eye "
                   "model: it must reach the noise floor."),
    "ray optics": ((r"ray optics", r"\bgeometric\b", r"ray trace"),
                   "geometric optics: light as rays, a point blurred into the patch the rays hit; no diffraction. "
                   "The renders are ray optics."),
    "wave optics": ((r"wave optics", r"\bwave\b"),
                    "physical optics: the pupil's wavefront diffracted into the point-spread function (PSF), so a "
                    "perfect eye still blurs by its pupil's diffraction. Wave-optics simulations are scored against "
                    "the render blurred by the pupil's diffraction."),
    "PSF": ((r"\bPSFs?\b", r"point-spread"),
            "point-spread function: the image of a point; a simulation convolves the chart with it."),
    "diffraction": ((r"diffract",),
                    "the blur a finite pupil gives even a perfect optical system (its Airy pattern)."),
    "MTF": ((r"\bMTFs?\b",),
            "modulation transfer function: the contrast an optical system keeps of a sinusoidal grating, by its "
            "spatial frequency (1 = all, 0 = none); here of the simulated eye's PSF, the pixel's own blur taken out."),
    "cycles per degree": ((r"cycles per degree", r"\bcpd\b", r"c/deg"),
                          "spatial frequency: grating periods per degree of visual angle (30 cpd: the finest "
                          "grating 20/20 letters hold)."),
    "Strehl ratio": ((r"Strehl",),
                     "the PSF's peak relative to a perfect (diffraction-limited) pupil's of the same size: 1 perfect, "
                     "about 0.8 and above 'diffraction-limited'; at the light's focus wavelength."),
    "LogMAR": ((r"LogMAR",),
               "log10 of the minimum angle of resolution in arcmin: a letter of LogMAR L is 5 × 10^L arcmin tall "
               "(LogMAR 0: 5 arcmin, 20/20; LogMAR 1: 50 arcmin, 20/200)."),
    "prescription": ((r"\bRx\b", r"\bDS\b", r" x \d", r"prescription", r"trial lens"),
                     "sphere, cylinder × axis in dioptres, always written in minus cylinder with the sign of the "
                     "sphere shown (+1.00 -1.00 x 180); the axis in degrees, TABO. DS: a sphere alone. A trial "
                     "lens's power is written the same way."),
    "reduced eye": ((r"reduced eye",),
                    "a one-surface model eye: its refraction and pupil from the schematic eye, the trial lens and "
                    "chart as vergences at the cornea, Thibos's chromatic eye for white light; no higher-order "
                    "aberrations, no field dependence."),
    "schematic eye": ((r"schematic eye", r"Navarro"),
                      "a model eye of real surfaces (here Navarro 1985: cornea, lens, media with dispersion), ray "
                      "traced; its wavefront holds its higher-order aberrations and their change across the field."),
    "the eye's wavefront": ((r"eye's wavefront",),
                            "the schematic eye's traced wavefront at the chart's field and each wavelength, with the "
                            "lens and the chart's vergence: vissim's full eye simulation (blur_eye)."),
    "thesis method": ((r"thesis method", r"\bthesis\b"),
                      "the method of the thesis this project re-implements, errors included (docs/ERRATA.md): a "
                      "lens's power taken as P/(1 − dP) with the chart at infinity, no spectacle magnification, "
                      "one wavelength, wave optics. Kept to show what those errors cost."),
    "photopic light": ((r"photopic",),
                       "white light weighted by the eye's daylight sensitivity V(λ), 380-780 nm; focused at 555 nm."),
    "entrance pupil": ((r"entrance pupil",),
                       "the pupil as seen from outside the eye: the iris magnified by the cornea (about 13 % "
                       "larger). Pupil sizes in configuration names are the iris's."),
    "synthetic chart": ((r"synthetic",),
                        "the chart drawn by vissim (the letter rasterised), the other input a simulation can blur "
                        "besides the render without a lens."),
    "wave bench": ((r"wave bench",),
                   "a second, noise-free truth: the chart through the trial lenses' traced wavefront in wave optics "
                   "(no render, no noise floor)."),
}


#: Terms every page defines: "How this page was built" (`how_built`, written after the rest) uses them.
ALWAYS = ("render", "spp")


def _uses(text: str, patterns: tuple[str, ...]) -> bool:
    return any(re.search(p, text, flags=re.IGNORECASE) for p in patterns)


def terms_used(text: str) -> list[str]:
    """The `GLOSSARY` terms ``text`` uses, in glossary order."""
    return [term for term, (patterns, _) in GLOSSARY.items() if _uses(text, patterns)]


def how_to_read(page: str, scores: str = "") -> str:
    """Markdown: the "How to read this page" section defining every `GLOSSARY` term ``page`` (the rest of the
    page) uses, then ``scores`` (the page's own paragraph on how its scores are read)."""
    used = [term for term in GLOSSARY if term in ALWAYS or term in terms_used(page + scores)]
    lines = ["### How to read this page\n",
             "Every term this page uses, defined here. Every number is in metrics.csv beside this page (one row per "
             "configuration and simulation).\n"]
    lines += [f"* **{term}**: {GLOSSARY[term][1]}" for term in used]
    text = "\n".join(lines) + "\n\n"
    return text + (scores.rstrip() + "\n\n" if scores else "")


def perfect_score_db(noise_power_kept: float = 1.0) -> float:
    """What a perfect, noise-free simulation scores over the noise floor, on average, against a reference that keeps
    ``noise_power_kept`` of one render's noise power (1: the render itself; Σh² for the render convolved with a
    PSF whose pixel weights are h, the noise being independent from pixel to pixel): 10·log10(2 / kept)."""
    return 10.0 * math.log10(2.0 / noise_power_kept)


def own_error_fraction(score_db: float) -> float:
    """A simulation's own squared error as a fraction of one render's noise power (σ²), from its score over the
    floor: the floor's squared difference is 2σ², the simulation's σ² + e², so e²/σ² = 2·10^(−score/10) − 1."""
    return 2.0 * 10.0 ** (-score_db / 10.0) - 1.0


def how_built(command: str, record: dict, provenance: dict, extra: str = "") -> str:
    """Markdown: the section saying how the page was made (command, campaign file, renders, vissim's version, date)
    and what lies beside it."""
    settings = record.get("settings") or {}
    spp, seeds = settings.get("spp"), settings.get("seeds")
    renders = (f" Each configuration was rendered twice, at {spp} spp, with seeds {', '.join(map(str, seeds))}."
               if spp and seeds else "")
    return ("### How this page was built\n\n"
            f"`{command}` wrote it (campaign file {record.get('source', 'unknown')}; `vissim report` of a finished "
            f"run folder writes it again without rendering), with vissim {provenance.get('vissim_version', '?')} on "
            f"{provenance.get('created_utc', '?')}."
            f"{renders} Beside this page: metrics.csv (every number on it) and each figure's provenance (a .json "
            "file of the same name: the campaign, its settings and the renders behind it). "
            "The run folder also holds metrics.json, every item's result.json and images; they are not copied "
            f"here.{(' ' + extra) if extra else ''}\n\n")
