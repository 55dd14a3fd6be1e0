"""The Fourier-side simulations a campaign compares with the bench (pure numpy, no Mitsuba).

Six simulations (`SIMULATION_PARTS`), each applicable to any linear-light input image (the
bench's no-lens render, as the thesis did, or the synthetic chart).  Every simulation starts
from the bench's own `ViewingSetup` (the one its scene is built from,
`vissim.bench.dslr.DslrBench.viewing_setup`).

``wave``
    Physically matched: the power the trial lenses add at the camera's principal plane for
    the chart's real distance (vergence / ray-transfer matrices), the camera's entrance pupil
    (focal length / f-number), the lenses' spectacle magnification, wave optics.
``geometric``
    The same wavefront, ray optics (no diffraction): isolates diffraction.
``thesis``
    The thesis's setup: Table 4.2's P / (1 - dP) per meridian (object at infinity), the
    f-number-matched eye pupil of Table 4.1 (2.7 mm at f/5), no magnification, wave optics.
    (The thesis's printed Eq. 4.7 drops C; its results show it used C, and so do we.)
``thesis_power``, ``thesis_pupil``, ``no_magnification``
    The matched geometric simulation with just one of the thesis's choices put back (ERRATA
    items 4, 3 and 5), compared with the render: each erratum's effect is a measured number.

Mitsuba renders no diffraction, so a ``wave`` or ``thesis`` result is compared with the
render convolved with the bench aperture's diffraction PSF
(`vissim.validation.engine.truth.add_bench_diffraction`),
and a ``geometric`` result with the render as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from vissim.optics.blur.convolve import blur_image
from vissim.optics.blur.resample import block_mean, magnify
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.validation.engine.truth import cached_psf
from vissim.optics.rx.trial_lens import TrialLens
from vissim.validation.dslr.schema import CampaignSettings, Configuration

__all__ = ["SimulationSetup", "simulation_setup", "simulate"]

#: kind -> (the thesis's choices put back, optics).  Each choice is one field of the bench's
#: `ViewingSetup` replaced: "pupil" (ERRATA item 3), "power"
#: (item 4), "magnification" (item 5).  The three ``thesis_*``/``no_*`` kinds each put back ONE
#: of them into the matched *geometric* simulation and are compared with the render itself,
#: which geometric optics matches to the noise limit: each erratum's cost is then measured
#: against an exact reference.  (Against "render + diffraction" a wave simulation is limited by
#: that reference, which is not wave optics; see the README.)
SIMULATION_PARTS = {
    "wave": ((), "wave"),
    "geometric": ((), "geometric"),
    "thesis": (("power", "pupil", "magnification"), "wave"),
    "thesis_power": (("power",), "geometric"),  # ERRATA 4 alone
    "thesis_pupil": (("pupil",), "geometric"),  # ERRATA 3 alone
    "no_magnification": (("magnification",), "geometric"),  # ERRATA 5 alone
}


@dataclass(frozen=True)
class SimulationSetup:
    """What one simulation assumes: a `ViewingSetup` and the optics it is blurred with."""

    kind: str
    setup: ViewingSetup
    mode: str  # "wave" or "geometric"

    def as_json(self) -> dict:
        return {
            "kind": self.kind,
            "camera_prescription": self.setup.camera_prescription.format(4),
            "camera_power_matrix_diopters": [list(r) for r in self.setup.camera_prescription.power_matrix()],
            "pupil_diameter_mm": self.setup.pupil_diameter_mm,
            "magnification_matrix": [list(r) for r in self.setup.magnification_matrix],
            "zernike_um": {f"{n},{m}": c for (n, m), c in sorted(self.setup.wavefront.coefficients_um.items())},
            "wavelength_nm": self.setup.wavelength_nm,
            "mode": self.mode,
        }


def simulation_setup(kind: str, bench: ViewingSetup, lenses: tuple[TrialLens, ...], configuration: Configuration,
                     settings: CampaignSettings) -> SimulationSetup:
    """The setup simulation ``kind`` uses: the bench's own (``bench``), with its thesis choices put back.

    ``lenses`` are the bench's trial lenses (for Table 4.2's power).
    """
    if kind not in SIMULATION_PARTS:
        raise ValueError(f"unknown simulation {kind!r}")
    choices, mode = SIMULATION_PARTS[kind]
    setup = bench
    if "power" in choices:
        setup = setup.with_table_4_2_power(lenses, settings.vertex_distance_mm)
    if "pupil" in choices:
        setup = setup.with_thesis_pupil(configuration.f_number)
    if "magnification" in choices:
        setup = setup.without_magnification()
    return SimulationSetup(kind, setup, mode)


def simulate(setup: SimulationSetup, image: np.ndarray, settings: CampaignSettings, *, oversample: int = 1) -> np.ndarray:
    """Apply a simulation to a linear-light, pixel-integrated image.

    ``image`` is sampled at the campaign's arcmin/px divided by ``oversample``; with
    ``oversample > 1`` the simulation runs at that finer sampling and the result is integrated
    onto the campaign's pixels (block means), so sharp edges are magnified and blurred without
    resampling an under-sampled image.  The bench's no-lens render can only be used as it is
    (``oversample=1``), as the thesis used its photographs.
    """
    step = settings.arcmin_per_px / oversample
    magnified = magnify(image, setup.setup.magnification_matrix)
    psf = cached_psf(setup.setup, step, setup.mode)
    out = blur_image(magnified, psf, arcmin_per_px=step, padding="edge")
    return block_mean(out, oversample)


