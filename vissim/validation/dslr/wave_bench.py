"""The wave bench as a campaign truth, and the numbers that say why a simulation differs from it.

Per configuration (``wave_truth = true`` in ``[campaign]``) the item computes the bench's wave
truth (`vissim.bench.wave_truth.wave_truth`): the configuration's chart through the
trial lenses' traced wave PSF, magnified and pixel-integrated. Choices:

* **One wavelength, the campaign's** ``wavelength_nm``, **traced through the dispersive glass**
  (spectacle crown, `vissim.optics.rx.glass`). The simulations diffract at that wavelength
  too, but take the lenses' power from vergence theory at the rendered index (1.523, the d
  line's). At 550 nm the glass is 0.0023 denser and a +2 D lens adds 0.37 % more; that
  *dispersion* is a physical difference the truth has and the simulations lack, so it shows in
  the residual and is measured, not hidden.
* **The synthetic chart's layout**: the same `ChartSpec` the bench renders,
  on the tile's grid (``tile_px`` at ``arcmin_per_px``) refined by the synthetic chart's
  oversampling. So only simulations of the synthetic chart are compared with it: a simulation
  of the no-lens render carries that render's Monte-Carlo noise, which a noise-free truth
  would measure instead of the optics.
* **No registration**: truth and simulation are laid out on one grid from one chart. A
  registration would hide an error of the traced magnification or image position (and its
  spline shift alone costs more than the 60 dB aimed at).
* **No noise floor**: the truth is deterministic.

`residual_budget` explains the wave simulation's residual by named physical differences,
each as a number: dispersion (the trace at ``wavelength_nm`` against the trace at the d line),
the vergence approximation (the d-line trace against the simulation's paraxial power),
spherical aberration (the traced terms of radial order >= 3, which vergence theory has none
of), and, as checks that they are *not* in the residual, the trial lenses' thickness (both
have it) and obliquity (neither has it: both use the frame centre's wavefront). The largest
RMS wavefront part is the residual's named cause.

`traced_ray_image` is the **geometric self-check** (simulation kind `TRACED_RAYS`):
the same trace's ray optics (the PSF of its ray landing points) applied to the synthetic
chart, at the d line, where the glass has the index Mitsuba renders (the render has no
dispersion).  It is compared with the render, like the geometric simulations, and must sit at
its noise floor (>= +2 dB over it): then the lens trace and the renderer vouch for each other.
"""

from __future__ import annotations

import math

import numpy as np

from vissim.bench.dslr.traced_wavefront import (
    ShiftInvariance,
    frame_field_points_deg,
    trace_bench_wavefront,
)
from vissim.bench.dslr.bench import DslrBench
from vissim.bench.dslr.wave_truth import WaveTruth, image_through_traced_lenses, wave_truth
from vissim.charts import Chart, ChartSpec, single_letter_spec
from vissim.optics.rx.glass import D_LINE_NM, glass_like_crown
from vissim.optics.rx.prescription import LensPower
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import TrialLensSetup
from vissim.units import mm_to_m
from vissim.validation.dslr.schema import CampaignSettings, Configuration

__all__ = [
    "CAUSES",
    "TRACED_RAYS",
    "WAVE_BENCH",
    "WAVE_BENCH_NOTE",
    "compute_wave_bench",
    "residual_budget",
    "traced_ray_image",
    "traced_rays_setup",
    "wave_bench_chart",
]

#: A comparison's ``reference_kind`` (and the item image ``wave_truth``) for the wave bench.
WAVE_BENCH = "wave_bench"
#: The simulation kind of the geometric self-check: the trace's ray optics, against the render.
TRACED_RAYS = "traced_rays"
#: The ``reference`` column of metrics rows against it.
WAVE_BENCH_NOTE = "wave bench (traced lenses, noise-free)"
#: The named causes a residual can have (``none``: nothing left but rounding).
CAUSES = ("dispersion", "vergence approximation", "spherical aberration", "none")
#: Below this RMS (µm) a wavefront difference is rounding, not a cause.
NEGLIGIBLE_RMS_UM = 1e-6


def wave_bench_chart(configuration: Configuration, settings: CampaignSettings) -> ChartSpec:
    """The chart the bench renders for ``configuration`` (`vissim.validation.dslr.renders.render_spec`'s)."""
    return single_letter_spec(configuration.letter, configuration.logmar, viewing_distance_m=settings.chart_distance_m,
                              polarity=configuration.polarity)


def compute_wave_bench(bench: DslrBench, fine_chart: Chart, settings: CampaignSettings, oversample: int) -> WaveTruth:
    """The wave truth of ``bench`` at the campaign's wavelength, ``oversample`` x finer: ``fine_chart``, the bench's
    chart (`wave_bench_chart`) rendered on that grid (the item's synthetic chart)."""
    return wave_truth(bench, fine_chart, wavelengths_nm=(settings.wavelength_nm,), oversample=oversample)


def traced_ray_image(bench: DslrBench, fine: np.ndarray, oversample: int) -> np.ndarray:
    """``fine`` (the synthetic chart, ``oversample`` x finer) through the traced lenses' ray PSF at the d line.

    Magnified by the bench's spectacle magnification and integrated onto the camera's pixels,
    as the wave truth (`image_through_traced_lenses`).
    """
    return image_through_traced_lenses(bench, fine, oversample=oversample, wavelengths_nm=(D_LINE_NM,),
                                       mode="geometric").pixels


def traced_rays_setup(bench: DslrBench) -> dict:
    """What the self-check assumes, as a simulation's ``setup`` record: the traced lenses at the d line."""
    traced = trace_bench_wavefront(bench)
    setup = bench.viewing_setup()
    prescription = traced.wavefront.to_prescription()
    return {
        "kind": TRACED_RAYS,
        "camera_prescription": prescription.format(4),
        "camera_power_matrix_diopters": [list(r) for r in prescription.power_matrix()],
        "pupil_diameter_mm": traced.pupil_diameter_mm,
        "magnification_matrix": [list(r) for r in setup.magnification_matrix],
        "mode": "geometric",
        "wavelength_nm": traced.wavelength_nm,
    }


def _principal_diopters(matrix) -> float:
    """The principal value of largest magnitude of a symmetric 2 x 2 power matrix (signed, D)."""
    values = np.linalg.eigvalsh(0.5 * (np.asarray(matrix, float) + np.asarray(matrix, float).T))
    return float(values[np.argmax(np.abs(values))])


def _power_matrix(power: LensPower) -> np.ndarray:
    return np.asarray(power.power_matrix(), dtype=float)


def _rms_um(a: dict, b: dict, orders=range(2, 99)) -> float:
    """RMS of the difference of two OSA coefficient sets (unit-RMS Zernikes) over radial ``orders``."""
    keys = {k for k in set(a) | set(b) if k[0] in orders}
    return math.sqrt(sum((a.get(k, 0.0) - b.get(k, 0.0)) ** 2 for k in keys))


def _thin_lens_power(bench: DslrBench) -> np.ndarray:
    """The lenses' added power in vergence theory as thin lenses (no thickness, no index)."""
    thin = TrialLensSetup(bench.lenses, bench.vertex_distance_mm, mm_to_m(bench.chart_distance_mm), bench.lens_gap_mm)
    setup = ViewingSetup.dslr(bench.focal_length_mm, bench.f_number, mm_to_m(bench.chart_distance_mm), thin)
    return np.asarray(setup.defocus_matrix_diopters, dtype=float)


def residual_budget(bench: DslrBench, simulated: ViewingSetup, wavelength_nm: float) -> dict:
    """Why the wave simulation (``simulated``, the bench's setup it assumes) differs from the wave truth.

    Powers in dioptres as the principal value of largest magnitude of the power-matrix
    difference (signed; a plus value: the truth's lenses add more); wavefront parts as RMS
    over the entrance pupil in µm (module doc).
    """
    traced = trace_bench_wavefront(bench, wavelength_nm=wavelength_nm)
    d_line = traced if wavelength_nm == D_LINE_NM else trace_bench_wavefront(bench)
    corners = [trace_bench_wavefront(bench, field_deg=p, wavelength_nm=wavelength_nm)
               for p in frame_field_points_deg(bench)[1:]]
    obliquity = ShiftInvariance((traced, *corners)).max_difference_rms_um()
    sim_um = dict(simulated.wavefront.coefficients_um)
    traced_um = dict(traced.wavefront.coefficients_um)
    d_line_um = dict(d_line.wavefront.coefficients_um)
    parts = {
        "dispersion": _rms_um(traced_um, d_line_um),
        "vergence approximation": _rms_um(d_line_um, sim_um, orders=(2,)),
        "spherical aberration": _rms_um(traced_um, {}, orders=range(3, 99)),
    }
    cause = max(parts, key=parts.get)
    if parts[cause] < NEGLIGIBLE_RMS_UM:
        cause = "none"
    sim_power = np.asarray(simulated.defocus_matrix_diopters, dtype=float)
    traced_power, d_line_power = _power_matrix(traced.added_power), _power_matrix(d_line.added_power)
    indices = [lens.refractive_index for lens in bench.physical_lenses]
    dispersed = [glass_like_crown(n).index(wavelength_nm) for n in indices]
    return {
        "wavelength_nm": float(wavelength_nm),
        "rendered_index": indices,
        "glass_index": dispersed,
        "index_difference": [a - b for a, b in zip(dispersed, indices)],
        "traced_added_power": traced.added_power.format(5),
        "traced_added_power_d_line": d_line.added_power.format(5),
        "simulated_added_power": LensPower.from_power_matrix(sim_power).minus_cylinder().format(5),
        "power_difference_diopters": _principal_diopters(traced_power - sim_power),
        "dispersion_diopters": _principal_diopters(traced_power - d_line_power),
        "vergence_approximation_diopters": _principal_diopters(d_line_power - sim_power),
        "thickness_diopters": _principal_diopters(sim_power - _thin_lens_power(bench)),
        "spherical_aberration_um": traced_um.get((4, 0), 0.0),
        "higher_order_rms_um": traced.higher_order_rms_um,
        "obliquity_rms_um": obliquity,
        "residual_rms_um": {"total": _rms_um(traced_um, sim_um), **parts},
        "cause": cause,
        "notes": {"thickness": "in both the simulation and the truth (the rendered thick lenses)",
                  "obliquity": "in neither: both use the frame centre's wavefront"},
    }
