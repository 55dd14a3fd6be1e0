"""The report's optics figures: the wave PSF (log scale), its MTF against the diffraction limit, through focus.

One configuration stands for each group (a sweep, or one item): of those with lenses, the one of
median defocus.  The PSF and MTF panels show the PSF its wave simulation of the synthetic chart
used, as the item saved it (``psf`` in ``result.json``: the image and its sampling, pupil and
wavelength), with `vissim.mtf` and `vissim.diffraction_mtf`.  The through-focus strip needs
PSFs no item computed: they are made with `vissim.compute_psf` from the numbers the item
recorded (the camera's power matrix and pupil of the ``wave`` comparison, the campaign's
wavelength and sampling), with the sphere stepped, and blur the item's synthetic chart at the
campaign's sampling.  Spectacle magnification is left out (the PSF has none; the simulation
magnifies the image before blurring).  ``vissim report RUN`` redraws them from a run folder.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from vissim.imageio import read_image
from vissim.optics.blur.convolve import blur_image
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import PSF, compute_psf, suggested_size_px
from vissim.optics.psf.metrics import (diffraction_cutoff_cyc_per_deg, diffraction_mtf,
                                       frequencies_cyc_per_deg, mtf,
                                       radius_of_encircled_energy_arcmin, ring_means)
from vissim.optics.pupil.wavefront import Wavefront
from vissim.validation.dslr.schema import lens_label_of, trial_lens_phrase
from vissim.validation.engine.figures import (PanelLayout, colorbar_beside, display_norm, radiance_colorbar, scale_bar,
                                              titled_panel_grid)
from vissim.validation.engine.summary import NO_LENS

__all__ = ["OpticsCase", "optics_cases", "case_psf", "sampling_label", "psf_panel", "mtf_curves", "psf_figure_of",
           "mtf_figure_of", "through_focus_figure_of", "optics_figure", "OPTICS_FIGURES", "recorded_psf",
           "THROUGH_FOCUS_STEPS_D", "LOG_PSF_DECADES"]


#: Sphere steps of the through-focus strip around each configuration's camera prescription, D.
THROUGH_FOCUS_STEPS_D = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: The log-PSF panels show this many decades below the peak.
LOG_PSF_DECADES = 5
#: The MTF is computed from the PSF zero-padded to this many times its field (finer frequency steps).
MTF_PADDING = 4
#: The PSF panels show the square holding this fraction of the energy, widened by a quarter.
SHOWN_ENERGY = 0.995


@dataclass(frozen=True)
class OpticsCase:
    """One group's configuration and the optics its wave simulation used."""

    group: str
    configuration: str
    prescription: Prescription  # the camera's equivalent correcting lens (minus cylinder)
    pupil_diameter_mm: float
    wavelength_nm: float
    arcmin_per_px: float  # the campaign's (the through-focus strip's) sampling
    psf_arcmin_per_px: float  # the sampling of the simulation of the synthetic chart
    synthetic: Path | None  # the item's synthetic chart at the campaign's sampling
    trial_lenses: str = ""  # the lenses in the holder (their label), which give the camera ``prescription``
    psf_file: Path | None = None  # the PSF the item's wave simulation used, as it saved it (None: an older item)

    def as_json(self) -> dict:
        return {"group": self.group, "configuration": self.configuration, "trial_lenses": self.trial_lenses,
                "camera_prescription": self.prescription.format(4), "pupil_diameter_mm": self.pupil_diameter_mm,
                "wavelength_nm": self.wavelength_nm, "psf_arcmin_per_px": self.psf_arcmin_per_px,
                "through_focus_arcmin_per_px": self.arcmin_per_px,
                "through_focus_steps_diopters": list(THROUGH_FOCUS_STEPS_D)}


def _largest_defocus(prescription: Prescription) -> float:
    return float(np.max(np.abs(np.linalg.eigvalsh(np.asarray(prescription.power_matrix(), dtype=float)))))


def optics_cases(results: list[dict], run_dir: str | Path, campaign: dict) -> list[OpticsCase]:
    """One `OpticsCase` per group, in campaign order: the configuration with lenses of median defocus.

    ``campaign``: the run's ``campaign.json`` record (its settings).
    """
    from vissim.optics.blur.resample import SUBPIXELS_PER_PX
    from vissim.validation.dslr.report_words import group_of

    run_dir = Path(run_dir)
    groups: dict[str, list[OpticsCase]] = {}
    for result in results:
        wave = next((c for c in result["comparisons"] if c["simulation"] == "wave"), None)
        if wave is None:
            continue
        settings = campaign.get("settings") or result["provenance"]["inputs"]["settings"]
        synthetic, psf = result["images"].get("synthetic"), result.get("psf") or {}
        step = float(psf.get("arcmin_per_px", float(settings["arcmin_per_px"]) / SUBPIXELS_PER_PX))
        case = OpticsCase(group_of(result["configuration"]), result["configuration"]["name"],
                          Prescription.from_power_matrix(wave["setup"]["camera_power_matrix_diopters"]),
                          float(wave["setup"]["pupil_diameter_mm"]), float(settings["wavelength_nm"]),
                          float(settings["arcmin_per_px"]), step, run_dir / synthetic if synthetic else None,
                          lens_label_of(result), run_dir / psf["image"] if psf.get("image") else None)
        groups.setdefault(case.group, []).append((result["lens_label"] != NO_LENS, case))
    cases = []
    for members in groups.values():
        with_lenses = [case for has_lens, case in members if has_lens] or [case for _, case in members]
        ranked = sorted(with_lenses, key=lambda c: _largest_defocus(c.prescription))
        cases.append(ranked[(len(ranked) - 1) // 2])
    return cases


def recorded_psf(case: OpticsCase) -> PSF:
    """The wave PSF the item's simulation of the synthetic chart used, read from the item (pixel-integrated);
    computed from the recorded numbers (`case_psf`) for an item that saved none."""
    if case.psf_file is None or not case.psf_file.exists():
        return case_psf(case)
    psf = PSF.from_array(read_image(case.psf_file).pixels, case.psf_arcmin_per_px, wavelength_nm=case.wavelength_nm,
                         pupil_diameter_mm=case.pupil_diameter_mm)
    return replace(psf, mode="wave", pixel="integrate")


def case_psf(case: OpticsCase, arcmin_per_px: float | None = None, sphere_step_diopters: float = 0.0) -> PSF:
    """The wave PSF of ``case`` (pixel-integrated) computed from its recorded numbers, at ``arcmin_per_px``
    (default: the synthetic chart's sampling); the through-focus strip's PSFs, which no item computed.

    ``sphere_step_diopters`` is added to the camera prescription's sphere (the through-focus steps).
    """
    rx = case.prescription
    if sphere_step_diopters:
        rx = Prescription(rx.sphere_diopters + sphere_step_diopters, rx.cylinder_diopters, rx.axis_deg)
    front = Wavefront.from_prescription(rx, case.pupil_diameter_mm)
    step = case.psf_arcmin_per_px if arcmin_per_px is None else arcmin_per_px
    size = suggested_size_px(front, step, wavelength_nm=case.wavelength_nm)
    return compute_psf(front, wavelength_nm=case.wavelength_nm, arcmin_per_px=step, size_px=size, mode="wave",
                       pixel="integrate")


def sampling_label(psf: PSF) -> str:
    """The sampling a PSF panel states: arcmin/px, pupil, wavelength."""
    return (f"{psf.arcmin_per_px:.3g} arcmin/px, {psf.pupil_diameter_mm:.3g} mm pupil, "
            f"{psf.wavelengths_nm[0]:.4g} nm")


def _panel_title(case: OpticsCase) -> str:
    return f"{case.configuration}\n{trial_lens_phrase(case.trial_lenses)} → camera Rx {case.prescription.format(2)}"


#: The optics figures' fixed layouts (`vissim.validation.engine.figures.PanelLayout`), inches: above the panels the
#: figure's title and each panel's two-line title, below them tick labels and a two-line x label, to the left the
#: first panel's y label, to the right of the PSF panels and the strip a colour bar.
PSF_LAYOUT = PanelLayout(2.6, 2.6, left_in=0.6, right_in=1.05, top_in=0.72, bottom_in=0.62, column_gap_in=0.45,
                         row_gap_in=0.0)
MTF_LAYOUT = PanelLayout(2.8, 2.1, left_in=0.55, right_in=0.3, top_in=0.72, bottom_in=0.7, column_gap_in=0.4,
                         row_gap_in=0.0)
THROUGH_FOCUS_LAYOUT = PanelLayout(1.45, 1.7, left_in=0.75, right_in=1.15, top_in=0.8, bottom_in=0.1,
                                   column_gap_in=0.1, row_gap_in=0.2)


def psf_panel(ax, psf: PSF):
    """Draw ``log10(psf / peak)`` over its central square (axes in arcmin, +y up); the image artist."""
    from matplotlib.colors import Normalize

    n, step = psf.data.shape[0], psf.arcmin_per_px
    radius = max(1.25 * radius_of_encircled_energy_arcmin(psf, SHOWN_ENERGY), 8 * step)
    half = min(int(np.ceil(radius / step)), n // 2 - 1)
    c = n // 2
    data = np.asarray(psf.data[c - half:c + half + 1, c - half:c + half + 1], dtype=float)
    edge = (half + 0.5) * step
    shown = ax.imshow(np.log10(np.maximum(data / data.max(), 10.0**-LOG_PSF_DECADES)), cmap="inferno",
                      norm=Normalize(-LOG_PSF_DECADES, 0), extent=(-edge, edge, -edge, edge), origin="upper",
                      interpolation="nearest")
    ax.set_xlabel(f"x (arcmin)\n{sampling_label(psf)}", fontsize=8)
    ax.tick_params(labelsize=7)
    return shown


def psf_figure_of(cases: list[OpticsCase], psfs: list[PSF]):
    """The log-PSF figure (a panel per case) as a matplotlib figure."""
    fig, axes, layout = titled_panel_grid(
        1, len(cases), PSF_LAYOUT, "The wave simulation's PSF on a log scale (the synthetic chart's sampling; "
        "pixel-integrated, origin at the chief ray, +y up)", fontsize=9,
        panel_titles=tuple(_panel_title(case) for case in cases))
    shown = None
    for ax, psf in zip(axes[0], psfs):
        shown = psf_panel(ax, psf)
    axes[0, 0].set_ylabel("y (arcmin)", fontsize=8)
    bar = colorbar_beside(fig, layout, 1, len(cases), shown)
    bar.set_label("log10 PSF / peak", fontsize=8)
    return fig


def mtf_curves(psf: PSF, pad: int = MTF_PADDING) -> dict[str, np.ndarray]:
    """MTF of ``psf`` (the pixel's sinc divided out: the optics alone) from 0 to Nyquist along x, y and averaged over rings; diffraction limit.

    The PSF is zero-padded to ``pad`` times its field first, so the MTF is sampled ``pad`` times
    finer in frequency (a defocused MTF's first zero lies at a few cycles/degree).  Keys:
    ``frequency_cyc_per_deg``, ``horizontal`` (along x), ``vertical`` (along y), ``radial`` (ring means, at each ring's mean frequency ``radial_frequency_cyc_per_deg``), ``diffraction``
    (at ``frequency_cyc_per_deg``), ``radial_diffraction``, ``cutoff_cyc_per_deg``.
    """
    n = psf.data.shape[0]
    before = (pad * n) // 2 - n // 2  # the origin stays at [N//2, N//2]
    padded = replace(psf, data=np.pad(np.asarray(psf.data, dtype=float), (before, pad * n - n - before)))
    spectrum = mtf(padded, remove_pixel=True)  # comparable with the diffraction limit, which has no pixel
    freq = frequencies_cyc_per_deg(padded)
    n = spectrum.shape[0]
    c = n // 2
    radii = np.hypot(freq[:, None], freq[None, :])
    ring_freq, ring_mtf = ring_means(spectrum, radii, freq[c + 1] - freq[c])
    ring_freq, ring_mtf = ring_freq[: n - c], ring_mtf[: n - c]  # rings inside the sampled square (none empty)
    pupil, wavelength = psf.pupil_diameter_mm, psf.wavelengths_nm[0]
    return {
        "frequency_cyc_per_deg": freq[c:],
        "horizontal": spectrum[c, c:],
        "vertical": spectrum[c:, c],
        "radial_frequency_cyc_per_deg": ring_freq,
        "radial": ring_mtf,
        "diffraction": diffraction_mtf(freq[c:], pupil, wavelength),
        "radial_diffraction": diffraction_mtf(ring_freq, pupil, wavelength),
        "cutoff_cyc_per_deg": np.asarray(diffraction_cutoff_cyc_per_deg(pupil, wavelength)),
    }


def mtf_figure_of(cases: list[OpticsCase], psfs: list[PSF]):
    """The MTF figure (a panel per case) as a matplotlib figure."""
    fig, axes, _ = titled_panel_grid(1, len(cases), MTF_LAYOUT, "MTF of the wave simulation's PSF (pixel removed) "
                                     "against the diffraction-limited MTF of its pupil", fontsize=9,
                                     panel_titles=tuple(_panel_title(case) for case in cases))
    for ax, psf in zip(axes[0], psfs):
        curves = mtf_curves(psf)
        freq, cutoff = curves["frequency_cyc_per_deg"], float(curves["cutoff_cyc_per_deg"])
        ax.plot(freq, curves["diffraction"], color="black", lw=1.2, label="diffraction limit")
        ax.plot(curves["radial_frequency_cyc_per_deg"], curves["radial"], color="C0", lw=1.2, label="radial mean")
        ax.plot(freq, curves["horizontal"], color="C1", lw=0.9, ls="--", label="along x (horizontal)")
        ax.plot(freq, curves["vertical"], color="C2", lw=0.9, ls=":", label="along y (vertical)")
        ax.set_xscale("log")
        ax.set_xlim(freq[1], min(1.05 * cutoff, float(freq[-1])))
        ax.set_ylim(0, 1.02)
        ax.set_xlabel(f"cycles/degree (log scale)\n{sampling_label(psf)}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("MTF", fontsize=8)
    axes[0, 0].legend(fontsize=7, loc="upper right")
    return fig


def through_focus_figure_of(cases: list[OpticsCase], image_norm=None):
    """The through-focus strip (a row per case with a synthetic chart, a column per sphere step), or None.

    ``image_norm``: a callable making the images' colour norm (default: relative radiance at display gamma).
    """
    image_norm = image_norm or display_norm
    cases = [c for c in cases if c.synthetic is not None and c.synthetic.exists()]
    if not cases:
        return None
    steps = THROUGH_FOCUS_STEPS_D
    first = cases[0]
    fig, axes, layout = titled_panel_grid(
        len(cases), len(steps), THROUGH_FOCUS_LAYOUT,
        f"Through focus: the synthetic chart through the wave PSF of the camera prescription with its sphere stepped\n"
        f"({first.arcmin_per_px:g} arcmin/px, {first.pupil_diameter_mm:g} mm pupil, {first.wavelength_nm:g} nm, no "
        "spectacle magnification; scale bars in arcmin)", fontsize=9,
        panel_titles=tuple("camera Rx (step 0)" if step == 0 else f"Rx sphere {step:+.2f} D from it" for step in steps),
        row_titles=tuple(f"{case.group}\n{trial_lens_phrase(case.trial_lenses)}\ncamera Rx {case.prescription.format(2)}"
                         for case in cases))
    for i, case in enumerate(cases):
        chart = read_image(case.synthetic).pixels
        for j, step in enumerate(steps):
            psf = case_psf(case, case.arcmin_per_px, step)
            seen = blur_image(chart, psf, arcmin_per_px=case.arcmin_per_px, padding="edge")
            ax = axes[i, j]
            shown = ax.imshow(seen, cmap="gray", norm=image_norm(), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
        scale_bar(axes[i, 0], chart.shape[1], case.arcmin_per_px)
    radiance_colorbar(colorbar_beside(fig, layout, len(cases), len(steps), shown))
    return fig


def _psf_figure(cases: list[OpticsCase], image_norm) -> tuple[object, str]:
    return psf_figure_of(cases, [recorded_psf(case) for case in cases]), (
        f"The wave simulation's point spread function, log10 of PSF over peak down to 1e-{LOG_PSF_DECADES}, axes "
        f"in arcmin, one panel per group: {_panels(cases)}.")


def _mtf_figure(cases: list[OpticsCase], image_norm) -> tuple[object, str]:
    return mtf_figure_of(cases, [recorded_psf(case) for case in cases]), (
        "MTF of the wave simulation's PSF against cycles per degree (log scale), along x, along y and the ring "
        f"mean, with the diffraction-limited MTF of the pupil, one panel per group: {_panels(cases)}.")


def _through_focus_figure(cases: list[OpticsCase], image_norm) -> tuple[object, str] | None:
    strip = through_focus_figure_of(cases, image_norm)
    steps = ", ".join(f"{s:+g} D" for s in THROUGH_FOCUS_STEPS_D)
    return None if strip is None else (strip, (
        f"The synthetic letter blurred by the wave PSF with the camera prescription's sphere stepped by {steps}, "
        f"one row per group ({_panels(cases)}), with an angular scale bar in arcmin."))


def _panels(cases: list[OpticsCase]) -> str:
    return "; ".join(_panel_title(c).replace("\n", ", ") for c in cases)


#: The optics figures, by name: their files and how each is drawn.
OPTICS_FIGURES = {"wave PSF (log scale) per group": ("figure_psf.png", _psf_figure),
                  "MTF against the diffraction limit per group": ("figure_mtf.png", _mtf_figure),
                  "through focus per group": ("figure_through_focus.png", _through_focus_figure)}


def optics_figure(cases: list[OpticsCase], name: str, image_norm=None) -> tuple[str, object, dict, str] | None:
    """One of the report's optics figures (`OPTICS_FIGURES`) of ``cases`` (`optics_cases`): (file name, matplotlib
    figure, provenance extras, alt text), or None (no wave items; no synthetic chart for the through-focus strip).

    ``image_norm`` as in `through_focus_figure_of`.
    """
    if not cases:
        return None
    file_name, draw = OPTICS_FIGURES[name]
    drawn = draw(cases, image_norm)
    return None if drawn is None else (file_name, drawn[0], {"optics": [case.as_json() for case in cases]}, drawn[1])
