"""A virtual subject in the ATV tube: the retinal image of one phone pixel and its threshold.

Optics (thesis §5.4): the phone sits in the focal plane of an 8 D (125 mm) collimating lens, so
one pixel (iPhone 5: 326 ppi, 77.9 µm) is a source at infinity subtending 77.9 µm / 125 mm =
0.623 mrad = 2.14 arcmin.  A trial lens of power P at ``trial_lens_vertex_mm`` (d) in front of the
eye adds the vergence ``P / (1 - d P)`` at the eye -- exact here, the source being at infinity
(ERRATA item 4 concerns finite distances).  What the eye then focuses, and through which pupil,
is `vissim.optics.rx.viewing_setup.ViewingSetup.atv_observer`.  The eye's correction (a `Prescription`, at the
eye's principal plane) minus that vergence minus the accommodation exerted is the *residual*
correction still needed; its wavefront gives the Fourier PSF (`vissim.optics.psf.compute.compute_psf`,
wave optics, monochromatic at ``wavelength_nm``), which is convolved with the pixel's square.

Accommodation: under cycloplegia none.  Otherwise the eye adds plus power to minimise the blur,
``A = clip(M_residual_before, 0, amplitude)`` (M the spherical equivalent), so it can clear
hyperopic defocus -- from the eye or from minus trial lenses -- but never myopic defocus.  An
optional ``proximal_accommodation_diopters`` (instrument myopia) is exerted even when it blurs.

Detection: complete spatial summation (Ricco's law) inside a disc of ``summation_diameter_arcmin``
centred on the spot's centroid; the threshold *luminance* is inversely proportional to the
fraction of the pixel's flux inside it.  The default 10 arcmin diameter is a round value of the
order of foveal Ricco diameters reported for photopic and mesopic backgrounds (Barlow 1958,
J Physiol 141:337; Davila & Geisler 1991, Vision Res 31:1369; the dependence on background and
eccentricity is reviewed by Tuten et al. 2018, J Vis 18(8):6) -- a model parameter, not a
measurement of any subject.  Luminance becomes a display code value through a gamma of 2.2
(ERRATA item 9: the thesis's [0, 1] intensity is a code value): ``code = code_full * f^(-1/gamma)``
with ``code_full`` the threshold when all the flux is inside the disc.  The simulated observer
answers by a Weibull psychometric function of luminance (exponent ``psychometric_slope``), i.e.
exponent ``gamma * slope`` in code values (`vissim.atv.procedure.PsychometricFunction`).

The retinal-image function is pluggable (``retinal_image=``): anything mapping a
`SpotRequest` to a `RetinalSpot`, e.g. a ray-traced spot of the whole tube.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.atv.analysis import CurveAnalysis, analyse_curve
from vissim.atv.data import THESIS_TRIAL_LENSES_DIOPTERS
from vissim.atv.procedure import (ProcedureConfig, PsychometricFunction, SimulatedObserver, ThresholdResult,
                                  run_procedure)
from vissim.bench.atv.tube import ATV_TRIAL_LENS_DISTANCE_MM, IPHONE5_PPI, AtvTube, pixel_pitch_mm
from vissim.checks import finite_number, positive_number
from vissim.checks import vertex_distance_mm as check_vertex_mm
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.checks import eye_pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import thesis_table_4_2_power
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import diopters_to_mm, rad_to_arcmin

scipy_signal = lazy_module("scipy.signal")

__all__ = ["AtvApparatus", "DetectionModel", "RetinalSpot", "SpotRequest", "VirtualExperiment",
           "VirtualSubject", "VirtualTrial", "fourier_retinal_image", "run_virtual_experiment",
           "summation_fraction"]

log = logging.getLogger(__name__)

IPHONE5_PIXEL_PITCH_MM = pixel_pitch_mm(IPHONE5_PPI)  # 326 ppi (thesis §5.4), the bench's value
ATV_COLLIMATOR_FOCAL_LENGTH_MM = diopters_to_mm(AtvTube().lens_power_diopters)  # the 8 D lens: 125 mm


@dataclass(frozen=True)
class VirtualSubject:
    """An eye: its correcting lens, pupil, accommodation amplitude and whether it is cyclopleged."""

    prescription: Prescription
    pupil_diameter_mm: float
    accommodation_amplitude_diopters: float = 0.0
    cycloplegia: bool = True
    proximal_accommodation_diopters: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.prescription, Prescription):
            raise TypeError(f"prescription must be a Prescription (the correcting lens), got {type(self.prescription).__name__}")
        check_pupil_mm(self.pupil_diameter_mm)
        for name in ("accommodation_amplitude_diopters", "proximal_accommodation_diopters"):
            value = finite_number(getattr(self, name), name.replace("_diopters", "").replace("_", " "), "D")
            if value < 0:
                raise VissimInputError(f"{name.replace('_diopters', '').replace('_', ' ')} must be >= 0 D, got {value:g} D")

    def accommodation_diopters(self, trial_vergence_diopters: float) -> float:
        """Accommodation exerted with a trial lens adding ``trial_vergence_diopters`` at the eye."""
        if self.cycloplegia:
            return 0.0
        need = self.prescription.spherical_equivalent_diopters - trial_vergence_diopters
        return float(np.clip(max(need, self.proximal_accommodation_diopters), 0.0, self.accommodation_amplitude_diopters))


@dataclass(frozen=True)
class AtvApparatus:
    pixel_pitch_mm: float = IPHONE5_PIXEL_PITCH_MM
    collimator_focal_length_mm: float = ATV_COLLIMATOR_FOCAL_LENGTH_MM
    trial_lens_vertex_mm: float = ATV_TRIAL_LENS_DISTANCE_MM  # the bench's slot (one value for both)
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM
    display_gamma: float = 2.2

    def __post_init__(self) -> None:
        positive_number(self.pixel_pitch_mm, "pixel pitch", "mm")
        positive_number(self.collimator_focal_length_mm, "collimator focal length", "mm")
        check_vertex_mm(self.trial_lens_vertex_mm, "trial lens vertex distance")
        check_wavelength_nm(self.wavelength_nm)
        if not 0.1 <= positive_number(self.display_gamma, "display gamma", "(exponent)") <= 10.0:
            raise VissimInputError(f"display gamma must be within 0.1-10 (displays are near 2.2), got {self.display_gamma:g}")

    @property
    def source_size_arcmin(self) -> float:
        """Angular size of one pixel seen through the collimator."""
        return rad_to_arcmin(self.pixel_pitch_mm / self.collimator_focal_length_mm)

    def trial_vergence_diopters(self, trial_lens_diopters: float) -> float:
        """Vergence a trial lens adds at the eye for a source at infinity, P / (1 - dP)."""
        return thesis_table_4_2_power(trial_lens_diopters, self.trial_lens_vertex_mm)


@dataclass(frozen=True)
class DetectionModel:
    summation_diameter_arcmin: float = 10.0
    threshold_code_full_capture: float = 0.06
    psychometric_slope: float = 4.0  # Weibull exponent in luminance
    guess_rate: float = 0.0
    lapse_rate: float = 0.0

    def __post_init__(self) -> None:
        positive_number(self.summation_diameter_arcmin, "summation diameter", "arcmin")
        code = positive_number(self.threshold_code_full_capture, "full-capture threshold", "display code value")
        if code > 1.0:
            raise VissimInputError(f"full-capture threshold must be <= 1 (display code value), got {code:g}")
        positive_number(self.psychometric_slope, "psychometric slope", "(Weibull exponent)", allow_inf=True)

    def threshold_code(self, fraction: float, display_gamma: float) -> float:
        """Code value at which luminance x ``fraction`` equals the full-capture threshold."""
        if fraction <= 0:
            return math.inf
        return self.threshold_code_full_capture * fraction ** (-1.0 / display_gamma)


@dataclass(frozen=True)
class SpotRequest:
    """Everything a retinal-image model may need for one trial."""

    subject: VirtualSubject
    apparatus: AtvApparatus
    trial_lens_diopters: float
    trial_vergence_diopters: float
    accommodation_diopters: float
    residual: Prescription  # the correction still needed at the eye
    field_arcmin: float  # the image must cover at least a disc of this diameter


@dataclass(frozen=True, eq=False)
class RetinalSpot:
    """Image of the pixel in visual-field angle: ``data`` sums to 1 over the field, origin at [N//2, N//2].

    ``energy_in_field`` is the fraction of the pixel's flux the field holds.
    """

    data: np.ndarray
    arcmin_per_px: float
    energy_in_field: float = 1.0

    def __post_init__(self) -> None:
        data = np.asarray(self.data, dtype=float)
        if data.ndim != 2 or data.shape[0] != data.shape[1] or not np.all(np.isfinite(data)) or data.sum() <= 0:
            raise VissimInputError(f"a retinal spot must be a finite square 2-D image with positive sum, got shape {data.shape}")
        positive_number(self.arcmin_per_px, "spot sampling", "arcmin per pixel")
        object.__setattr__(self, "data", data / data.sum())


RetinalImageFn = Callable[[SpotRequest], RetinalSpot]


def _box_kernel(width_px: float) -> np.ndarray:
    """A centred square of ``width_px`` pixels with fractional edge coverage, unit sum."""
    half = width_px / 2.0
    m = int(math.ceil(half))
    c = np.arange(-m, m + 1)
    cover = np.clip(np.minimum(c + 0.5, half) - np.maximum(c - 0.5, -half), 0.0, None)
    kernel = np.outer(cover, cover)
    return kernel / kernel.sum()


def fourier_retinal_image(request: SpotRequest, *, arcmin_per_px: float = 0.25) -> RetinalSpot:
    """Wave-optics PSF of the residual defocus convolved with the pixel's square (default model)."""
    pupil = request.subject.pupil_diameter_mm
    wavefront = Wavefront.from_prescription(request.residual, pupil)
    source_px = request.apparatus.source_size_arcmin / arcmin_per_px
    size = suggested_size_px(wavefront, arcmin_per_px, wavelength_nm=request.apparatus.wavelength_nm)
    size = max(size + int(math.ceil(source_px)) + 2, int(math.ceil(request.field_arcmin / arcmin_per_px)) + 3)
    size += 1 - size % 2
    psf = compute_psf(wavefront, arcmin_per_px=arcmin_per_px, size_px=size, wavelength_nm=request.apparatus.wavelength_nm, mode="wave")
    image = scipy_signal.fftconvolve(psf.data, _box_kernel(source_px), mode="same")
    return RetinalSpot(np.maximum(image, 0.0), arcmin_per_px, psf.energy_in_field)


def summation_fraction(spot: RetinalSpot, diameter_arcmin: float, *, supersample: int = 4) -> float:
    """Fraction of the pixel's flux inside a disc of ``diameter_arcmin`` centred on the spot's centroid."""
    n = spot.data.shape[0]
    offsets = (np.arange(n) - n // 2) * spot.arcmin_per_px
    cy = float(np.sum(spot.data.sum(axis=1) * offsets))
    cx = float(np.sum(spot.data.sum(axis=0) * offsets))
    sub = (np.arange(supersample) + 0.5) / supersample - 0.5
    radius = diameter_arcmin / 2.0
    inside = np.zeros_like(spot.data)
    for dy in sub:
        for dx in sub:
            yy = offsets[:, None] + dy * spot.arcmin_per_px - cy
            xx = offsets[None, :] + dx * spot.arcmin_per_px - cx
            inside += (yy * yy + xx * xx) <= radius * radius
    inside /= supersample * supersample
    return float(np.sum(spot.data * inside)) * spot.energy_in_field


@dataclass(frozen=True)
class VirtualTrial:
    trial_lens_diopters: float
    trial_vergence_diopters: float
    accommodation_diopters: float
    residual_se_diopters: float
    summation_fraction: float
    model_threshold_code: float
    result: ThresholdResult

    @property
    def minimum_visible_code(self) -> float:
        return self.result.threshold_code

    def as_json(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "result"} | {
            "model_threshold_code": self.model_threshold_code if math.isfinite(self.model_threshold_code) else None,
            "minimum_visible_code": self.minimum_visible_code,
            "never_seen": self.result.never_seen,
            "presentations": len(self.result.presentations),
        }


@dataclass(frozen=True, eq=False)
class VirtualExperiment:
    subject: VirtualSubject
    apparatus: AtvApparatus
    detection: DetectionModel
    trials: tuple[VirtualTrial, ...]
    seed: int | None
    retinal_image_model: str = field(default="fourier")

    @property
    def lens_diopters(self) -> tuple[float, ...]:
        return tuple(t.trial_lens_diopters for t in self.trials)

    @property
    def minimum_visible_code(self) -> tuple[float, ...]:
        return tuple(t.minimum_visible_code for t in self.trials)

    @property
    def condition(self) -> str:
        return "cycloplegia" if self.subject.cycloplegia else "accommodation_free"

    def analysis(self, level: float = 0.95, window_diopters: float | None = None) -> CurveAnalysis:
        """The same quadratic analysis as the real data; SE = the subject's prescription's SE."""
        return analyse_curve(
            self.lens_diopters, self.minimum_visible_code,
            measured_se_diopters=self.subject.prescription.spherical_equivalent_diopters,
            subject_id="virtual", eye="", condition=self.condition, level=level, window_diopters=window_diopters,
        )

    def as_json(self) -> dict:
        s, a, d = self.subject, self.apparatus, self.detection
        return {
            "subject": {**asdict(s), "prescription": s.prescription.format()},
            "apparatus": asdict(a) | {"source_size_arcmin": a.source_size_arcmin},
            "detection": asdict(d) | {"psychometric": "Weibull in luminance, F(threshold) = 1/2"},
            "retinal_image_model": self.retinal_image_model,
            "seed": self.seed,
            "trials": [t.as_json() for t in self.trials],
        }


def run_virtual_experiment(
    subject: VirtualSubject,
    *,
    lenses_diopters: Sequence[float] = THESIS_TRIAL_LENSES_DIOPTERS,
    apparatus: AtvApparatus | None = None,
    detection: DetectionModel | None = None,
    procedure: ProcedureConfig | None = None,
    seed: int | None = 0,
    retinal_image: RetinalImageFn = fourier_retinal_image,
) -> VirtualExperiment:
    """Run the threshold procedure with a simulated observer at every trial lens."""
    apparatus = apparatus or AtvApparatus()
    detection = detection or DetectionModel()
    if not lenses_diopters:
        raise VissimInputError("no trial lenses given (D)")
    seeds = np.random.SeedSequence(seed).spawn(len(lenses_diopters))
    rx = subject.prescription
    trials = []
    for lens, child in zip(lenses_diopters, seeds):
        lens = finite_number(lens, "trial lens power", "D")
        vergence = apparatus.trial_vergence_diopters(lens)
        accommodation = subject.accommodation_diopters(vergence)
        setup = ViewingSetup.atv_observer(rx, subject.pupil_diameter_mm, accommodation, lens,
                                          apparatus.trial_lens_vertex_mm, wavelength_nm=apparatus.wavelength_nm)
        residual = setup.camera_prescription
        request = SpotRequest(subject, apparatus, lens, vergence, accommodation, residual, detection.summation_diameter_arcmin)
        fraction = summation_fraction(retinal_image(request), detection.summation_diameter_arcmin)
        threshold = detection.threshold_code(fraction, apparatus.display_gamma)
        psychometric = PsychometricFunction(threshold if math.isfinite(threshold) else 1e6,
                                            slope=detection.psychometric_slope * apparatus.display_gamma,
                                            guess_rate=detection.guess_rate, lapse_rate=detection.lapse_rate)
        observer_seed, procedure_seed = (int(s) for s in child.generate_state(2))
        result = run_procedure(SimulatedObserver(psychometric, seed=observer_seed), procedure, seed=procedure_seed)
        if result.never_seen:
            log.warning("trial lens %+.2f D: the pixel was never seen (model threshold %.3g code)", lens, threshold)
        trials.append(VirtualTrial(lens, vergence, accommodation, residual.spherical_equivalent_diopters, fraction, threshold, result))
    name = getattr(retinal_image, "__name__", type(retinal_image).__name__)
    return VirtualExperiment(subject, apparatus, detection, tuple(trials), seed, "fourier" if retinal_image is fourier_retinal_image else name)
