"""Populations of measured eyes: many eyes under the same conditions, each eye's optics and the spread of them.

A population is a set of measured eyes (`select_eyes`: all of a dataset's eyes, a list, or those whose foveal
spherical equivalent lies within a range) crossed with conditions (`PopulationCondition`: pupil, field,
wavelength and a correction state). For each eye and condition `evaluate_population` gives the MTF at chosen
frequencies, the Strehl ratio, the eye's own refraction (M, J0, J45 over the pupil) and the RMS of its orders
3 and up; `population_quantiles` summarises them across the eyes.

* **Correction states**: ``"uncorrected"`` (the eye as measured, tilt aside); ``"sphero-cylinder"``: the
  best spectacle correction in the minimum-RMS sense, orders 0-2 removed (what a sphero-cylinder can correct),
  the higher orders left; ``"accommodating"``: uncorrected, but the eye accommodates up to
  ``accommodation_amplitude_diopters`` to cancel its own hyperopia (its spherical equivalent M over the pupil
  at the fovea, when positive: a hyperope focuses a far target, a myope cannot; off axis the eye keeps the
  accommodation its fovea chose); accommodation taken as a change of power at the entrance
  pupil only (the lens's own change of aberrations left out; the data were measured relaxed); or a
  `Prescription`: those spectacles worn ``vertex_mm`` in front of the cornea, their vergence at the entrance
  pupil taken from the eye's second-order terms.
* **One trace per light, field and pupil**: the base eye is traced once for each, shared by every eye and
  correction, and every eye's front is made from it (`measured_eye.measured_trace`), the same front as
  `vissim.optics.eyes.psf_wavefront.eye_wavefront` gives for that eye alone (tested).
* **MTF**: `vissim.optics.eyes.report.eye_mtf`: radial (ring mean) at the fovea; off axis, the mean of the
  tangential and sagittal MTFs.
* An eye with no measurement at a condition's field is skipped for that condition (its name is logged).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import itertools
import logging
import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import accommodation_diopters, eye_pupil_diameter_mm, eye_wavelength_nm, finite_number
from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import (DEFAULT_SPECTACLE_VERTEX_MM, PHOTOPIC_FOCUS_NM, POPULATION_CORRECTION,
                                         POPULATION_CORRECTIONS, POPULATION_FIELD_DEG)
from vissim.optics.eyes.measured.datasets import UnmeasuredFieldError, load_dataset
from vissim.optics.eyes.measured.measured_eye import BASE_EYE_MODEL, MeasuredWavefront, measured_trace
from vissim.optics.eyes.models import SchematicEye, eye_model
from vissim.optics.eyes.refraction import minimum_rms_prescription, transfer_prescription
from vissim.optics.eyes.report import eye_mtf
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.psf.compute import strehl_ratio
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.runtime.threads import map_on_threads, single_threaded_blas
from vissim.optics.rx.prescription import Prescription

__all__ = ["CORRECTIONS", "PopulationCondition", "EyeResult", "select_eyes", "population_conditions", "parse_correction", "evaluate_population",
           "population_quantiles", "schematic_mtf", "schematic_refraction", "seen_image", "QUANTILES",
           "CHUNK_EYES"]

log = logging.getLogger(__name__)

#: The correction states besides spectacles given as a `Prescription` (module doc).
CORRECTIONS = POPULATION_CORRECTIONS
#: Eyes per task when a population is spread over processes or a Dask cluster.
CHUNK_EYES = 20
#: The quantiles `population_quantiles` reports by default.
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


@dataclass(frozen=True)
class PopulationCondition:
    """One condition every eye of a population is evaluated under (module doc)."""

    pupil_mm: float
    field_deg: tuple[float, float] = POPULATION_FIELD_DEG
    correction: str | Prescription = POPULATION_CORRECTION
    wavelength_nm: float = PHOTOPIC_FOCUS_NM  # V(λ)'s peak
    vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM  # a given Rx's lens, in front of the cornea
    accommodation_amplitude_diopters: float = 0.0  # how far an "accommodating" eye can accommodate

    def __post_init__(self) -> None:
        if not isinstance(self.correction, Prescription) and self.correction not in CORRECTIONS:
            raise VissimInputError(f"a population's correction is one of {', '.join(CORRECTIONS)} or a "
                                   f"Prescription (spectacles worn), got {self.correction!r}")
        amplitude = accommodation_diopters(self.accommodation_amplitude_diopters, "an accommodation amplitude")
        if (self.correction == "accommodating") != (amplitude > 0.0) or amplitude < 0.0:
            raise VissimInputError(f"the accommodating correction needs an accommodation amplitude > 0 D, and no other "
                                   f"correction takes one; got {amplitude:g} D with {self.correction!r}")
        object.__setattr__(self, "accommodation_amplitude_diopters", amplitude)
        # any finite vertex: a lens at the pupil (minus its depth) is the accommodating eye's oracle; the command
        # line and campaign files hold a user's to `VERTEX_DISTANCE_RANGE_MM`
        object.__setattr__(self, "vertex_mm", finite_number(self.vertex_mm, "a population's vertex distance", "mm"))
        object.__setattr__(self, "pupil_mm", eye_pupil_diameter_mm(self.pupil_mm, "a population's pupil"))
        object.__setattr__(self, "wavelength_nm", eye_wavelength_nm(self.wavelength_nm))  # the base eye is traced
        field = tuple(finite_number(v, "a population's field angle", "deg") for v in self.field_deg)
        if len(field) != 2:
            raise VissimInputError(f"a population's field is (x, y) in degrees, got {self.field_deg!r}")
        object.__setattr__(self, "field_deg", field)

    @property
    def label(self) -> str:
        x, y = self.field_deg
        worn = (f"wearing {self.correction.format()} at {self.vertex_mm:g} mm"
                if isinstance(self.correction, Prescription) else self.correction)
        if self.correction == "accommodating":
            worn = f"accommodating up to {self.accommodation_amplitude_diopters:g} D"
        return f"{self.pupil_mm:g} mm, field {x:g},{y:g} deg, {self.wavelength_nm:g} nm, {worn}"

    def as_json(self) -> dict:
        correction = self.correction
        if isinstance(correction, Prescription):
            correction = {"sphere_diopters": correction.sphere_diopters,
                          "cylinder_diopters": correction.cylinder_diopters, "axis_deg": correction.axis_deg}
        return {"pupil_mm": self.pupil_mm, "field_deg": list(self.field_deg), "correction": correction,
                "wavelength_nm": self.wavelength_nm, "vertex_mm": self.vertex_mm,
                **({"accommodation_amplitude_diopters": self.accommodation_amplitude_diopters}
                   if self.accommodation_amplitude_diopters else {})}

    @classmethod
    def from_json(cls, record: dict) -> PopulationCondition:
        """The condition `as_json` wrote."""
        correction = record["correction"]
        return cls(record["pupil_mm"], tuple(record["field_deg"]),
                   Prescription(**correction) if isinstance(correction, dict) else correction,
                   record["wavelength_nm"], record["vertex_mm"], record.get("accommodation_amplitude_diopters", 0.0))


@dataclass(frozen=True)
class EyeResult:
    """One eye under one condition: MTF (at the population's frequencies), Strehl ratio, the eye's own
    refraction over the pupil (minimum RMS, dioptres) and the RMS of orders 3 and up (µm)."""

    eye: MeasuredWavefront
    condition: PopulationCondition
    mtf: np.ndarray
    strehl: float
    m_diopters: float
    j0_diopters: float
    j45_diopters: float
    higher_order_rms_um: float

    def as_json(self) -> dict:
        return {"dataset": self.eye.dataset, "subject": self.eye.subject, "eye": self.eye.eye,
                "condition": self.condition.as_json(), "mtf": self.mtf.tolist(), "strehl": self.strehl,
                "m_diopters": self.m_diopters, "j0_diopters": self.j0_diopters, "j45_diopters": self.j45_diopters,
                "higher_order_rms_um": self.higher_order_rms_um}

    @classmethod
    def from_json(cls, record: dict) -> EyeResult:
        """The result `as_json` wrote (its numbers exactly: JSON keeps a float's every digit)."""
        return cls(MeasuredWavefront(record["dataset"], record["subject"], record["eye"]),
                   PopulationCondition.from_json(record["condition"]), np.asarray(record["mtf"], dtype=float),
                   record["strehl"], record["m_diopters"], record["j0_diopters"], record["j45_diopters"],
                   record["higher_order_rms_um"])


def select_eyes(dataset: str, *, subjects=None, eyes=None, foveal_se_within_diopters=None,
                se_pupil_mm: float | None = None,
                se_wavelength_nm: float = PHOTOPIC_FOCUS_NM) -> tuple[MeasuredWavefront, ...]:
    """The measured eyes of ``dataset``: all, or the ``subjects`` (numbers) and ``eyes`` (``"right"``,
    ``"left"``) given, and of those the ones whose foveal spherical equivalent (minimum RMS over
    ``se_pupil_mm``, default the data's pupil, in ``se_wavelength_nm`` light) lies within
    ``foveal_se_within_diopters`` (low, high)."""
    data = load_dataset(dataset)
    se_pupil_mm = data.pupil_mm if se_pupil_mm is None else se_pupil_mm
    chosen_subjects = data.subjects if subjects is None else tuple(int(s) for s in subjects)
    chosen_eyes = data.eyes if eyes is None else tuple(eyes)
    for what, chosen in (("subject", chosen_subjects), ("eye", chosen_eyes)):
        if len(set(chosen)) != len(chosen):  # an eye counted twice would weigh twice in every quantile
            raise VissimInputError(f"a population names each {what} once, got {list(chosen)!r}")
    found = tuple(MeasuredWavefront(dataset, s, e) for s in chosen_subjects for e in chosen_eyes)
    if foveal_se_within_diopters is None:
        return found
    low, high = (float(v) for v in foveal_se_within_diopters)
    if not low <= high:
        raise VissimInputError(f"a spherical-equivalent range runs low to high, got {low:g} to {high:g} D")
    condition = PopulationCondition(se_pupil_mm, (0.0, 0.0), "uncorrected", se_wavelength_nm)
    kept = {r.eye for r in evaluate_population(found, [condition], ()) if low <= r.m_diopters <= high}
    return tuple(eye for eye in found if eye in kept)


def parse_correction(text: str) -> str | Prescription:
    """A correction state (`CORRECTIONS`) as written, or the spectacles worn written as a prescription."""
    from vissim.optics.rx.prescription import prescription_from

    if text in CORRECTIONS:
        return text
    try:
        return prescription_from(text)
    except VissimInputError:
        raise VissimInputError(f"a correction is {' or '.join(CORRECTIONS)} or the spectacles worn (a prescription, "
                               f"e.g. '-1.00 -0.50 x 90'), got {text!r}") from None


def population_conditions(pupils_mm, fields_deg, corrections, *, wavelength_nm: float = PHOTOPIC_FOCUS_NM,
                          vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM,
                          accommodation_amplitude_diopters: float = 0.0) -> list[PopulationCondition]:
    """Every combination of pupil, field and correction (pupils outer), in one light and vertex; an amplitude goes
    to the accommodating correction only, and must come with it. A condition given twice is refused (its eyes
    would count twice)."""
    amplitude = float(accommodation_amplitude_diopters)
    if amplitude and "accommodating" not in corrections:
        raise VissimInputError(f"an accommodation amplitude ({amplitude:g} D) goes with the accommodating "
                               "correction only")
    conditions = [PopulationCondition(p, tuple(f), c, wavelength_nm, vertex_mm,
                                      amplitude if c == "accommodating" else 0.0)
                  for p, f, c in itertools.product(pupils_mm, fields_deg, corrections)]
    labels = [c.label for c in conditions]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise VissimInputError(f"the condition {twice[0]!r} is given twice (a pupil, field or correction repeated)")
    return conditions


@functools.lru_cache(maxsize=64)
def _base_trace(wavelength_nm: float, field_deg: tuple, pupil_mm: float):
    """The base eye traced once per light, field and pupil: every eye of a population, every correction, and
    the defocus reference of every condition in that light share it."""
    return trace_eye_wavefront(eye_model(BASE_EYE_MODEL), wavelength_nm, field_deg, pupil_mm=pupil_mm)


def _front(eye: MeasuredWavefront, condition: PopulationCondition):
    """The eye's orders 2 and up under ``condition`` (µm over its pupil), its slopes-to-angle map, and its
    entrance pupil's distance behind the cornea (mm)."""
    at = (condition.field_deg, condition.pupil_mm)
    traced = measured_trace(_base_trace(condition.wavelength_nm, *at), eye, _base_trace(eye.defocus_wavelength_nm, *at))
    own = {k: v for k, v in traced.zernike_um.items() if k[0] >= 2}
    return (Wavefront(own, traced.entrance_pupil_mm, condition.wavelength_nm), traced.field_map,
            traced.entrance_pupil_position_mm)


def _corrected(front: Wavefront, condition: PopulationCondition, pupil_position_mm: float,
               foveal_m_diopters: float = 0.0) -> Wavefront:
    """What the eye sees through its correction (module doc): orders 2 and up uncorrected, 3 and up with its
    best sphero-cylinder; wearing a given Rx, the lens's vergence at the pupil (`transfer_prescription`,
    ``vertex_mm`` plus the pupil's depth; its paraxial power, oblique lens astigmatism aside) taken from the
    eye's second-order terms."""
    nm, pupil = condition.wavelength_nm, front.pupil_diameter_mm
    lowest = 2 if condition.correction in ("uncorrected", "accommodating") else 3
    kept = {k: v for k, v in front.coefficients_um.items() if k[0] >= lowest}
    at_pupil = None
    if isinstance(condition.correction, Prescription):
        at_pupil = transfer_prescription(condition.correction, -(condition.vertex_mm + pupil_position_mm))
    elif condition.correction == "accommodating":  # a plus lens at the pupil, up to the amplitude
        at_pupil = Prescription(float(np.clip(foveal_m_diopters, 0.0, condition.accommodation_amplitude_diopters)))
    if at_pupil is not None:
        lens = Wavefront.from_prescription(at_pupil, pupil).coefficients_um
        for key, value in front.coefficients_um.items():
            if key[0] == 2:
                kept[key] = value - lens.get(key, 0.0)
    return Wavefront(kept, pupil, nm)


def _seen_mtf(seen: Wavefront, field_map, condition: PopulationCondition, frequencies, name: str) -> np.ndarray:
    """The MTF (module doc) of the corrected front ``seen``, in visual angle (``field_map``)."""
    nm = condition.wavelength_nm
    curves = eye_mtf(SpectralWavefront((nm,), (seen,), nm, name, field_map), nm, frequencies, condition.field_deg)
    return np.mean([curves[k] for k in curves], axis=0)


def schematic_mtf(optics: SchematicEye, condition: PopulationCondition, frequencies_cyc_per_deg) -> np.ndarray:
    """The MTF of the schematic eye ``optics`` (its entrance pupil the condition's) under ``condition``, as a
    population's eyes are taken (module doc), for the same comparison."""
    from vissim.optics.eyes.eye import build_eye
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye
    from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront

    eye = build_eye(optics, pupil_diameter_mm=condition.pupil_mm)
    nm = condition.wavelength_nm
    spectral = eye_spectral_wavefront(eye, wavelengths_nm=[nm], field_deg=condition.field_deg)
    foveal = 0.0 if condition.correction != "accommodating" else _spherical_equivalent(
        eye_spectral_wavefront(eye, wavelengths_nm=[nm]).fronts[0])
    seen = _corrected(spectral.fronts[0], condition, entrance_pupil_position_mm(mean_meridian_eye(eye.optics), nm),
                      foveal)
    return _seen_mtf(seen, spectral.field_map, condition, np.asarray(frequencies_cyc_per_deg, dtype=float),
                     optics.name)


def schematic_refraction(optics: SchematicEye, condition: PopulationCondition) -> tuple[float, float, float]:
    """(M, J0, J45), dioptres, of the schematic eye ``optics`` under ``condition``, as a population's eyes are
    taken: minimum RMS over the pupil seen along the chief ray (the measured data's pupil), in its plane."""
    from vissim.optics.eyes.refraction import along_chief_ray

    trace = trace_eye_wavefront(optics, condition.wavelength_nm, condition.field_deg, pupil_mm=condition.pupil_mm)
    own = minimum_rms_prescription(trace.zernike_um, trace.entrance_pupil_mm)
    return tuple(float(v) for v in along_chief_ray(own, trace.chief_direction, 0.0).power_vector())


def seen_image(eye: MeasuredWavefront, condition: PopulationCondition, image, arcmin_per_px: float) -> np.ndarray:
    """``image`` (linear light, square pixels of ``arcmin_per_px``, in visual angle) as ``eye`` sees it under
    ``condition``: the wave PSF of the orders its correction leaves, in visual angle, applied with the image's
    edges continued; the PSF's field holds its blur (a kernel is never cut)."""
    from vissim.optics.blur.convolve import blur_image
    from vissim.optics.psf.compute import compute_psf
    from vissim.optics.psf.field_size import suggested_size_px

    pixels = np.asarray(image, dtype=np.float64)
    front, field_map, position = _front(eye, condition)
    kept = _corrected(front, condition, position)
    nm = condition.wavelength_nm
    mapped = SpectralWavefront((nm,), (kept,), nm, eye.name, field_map)
    size = suggested_size_px(mapped, arcmin_per_px, wavelength_nm=nm, minimum_px=max(pixels.shape))
    psf = compute_psf(mapped, wavelength_nm=nm, arcmin_per_px=arcmin_per_px, size_px=size)
    margin = [((size - n) // 2 + 1, (size - n) // 2 + 1) for n in pixels.shape]
    seen = blur_image(np.pad(pixels, margin, mode="edge"), psf, arcmin_per_px=arcmin_per_px, padding="edge")
    return seen[margin[0][0]:margin[0][0] + pixels.shape[0], margin[1][0]:margin[1][0] + pixels.shape[1]]


def _spherical_equivalent(front: Wavefront) -> float:
    return float(minimum_rms_prescription(dict(front.coefficients_um), front.pupil_diameter_mm).power_vector()[0])


def _foveal_m(eye: MeasuredWavefront, condition: PopulationCondition, front: Wavefront) -> float:
    """The eye's M at the fovea in the condition's pupil and light (``front``: its front at the condition's field):
    what an accommodating eye answers to."""
    if condition.correction != "accommodating":
        return 0.0
    if condition.field_deg != (0.0, 0.0):
        front = _front(eye, dataclasses.replace(condition, field_deg=(0.0, 0.0)))[0]
    return _spherical_equivalent(front)


def _result(eye: MeasuredWavefront, condition: PopulationCondition, frequencies) -> EyeResult:
    front, field_map, position = _front(eye, condition)
    pupil = front.pupil_diameter_mm
    m, j0, j45 = minimum_rms_prescription(dict(front.coefficients_um), pupil).power_vector()
    higher = {k: v for k, v in front.coefficients_um.items() if k[0] >= 3}
    seen = _corrected(front, condition, position, _foveal_m(eye, condition, front))
    mtf = _seen_mtf(seen, field_map, condition, frequencies, eye.name) if len(frequencies) else np.zeros(0)
    rms = math.sqrt(sum(v * v for v in higher.values()))
    return EyeResult(eye, condition, mtf, float(strehl_ratio(seen, wavelength_nm=condition.wavelength_nm)),
                     float(m), float(j0), float(j45), rms)


def _evaluate_chunk(condition: PopulationCondition, identities: tuple, frequencies: np.ndarray,
                    one_thread: bool = False):
    """(results, names skipped) of the eyes ``identities`` ((dataset, subject, eye) each) under ``condition``;
    a task's whole input: each process reads the package's data itself (`load_dataset`, once per process).
    ``one_thread``: OpenBLAS on one thread, as a worker beside others must be (a population on 2 cores in 2
    processes: 29 s with BLAS's own threads, 17 s without)."""
    results, skipped = [], []
    with single_threaded_blas() if one_thread else contextlib.nullcontext():
        for dataset, subject, side in identities:
            eye = MeasuredWavefront(dataset, subject, side)
            try:
                results.append(_result(eye, condition, frequencies))
            except UnmeasuredFieldError:
                skipped.append(eye.name)
    return results, skipped


def evaluate_population(eyes, conditions, frequencies_cyc_per_deg=(), *, workers: int = 1, client=None,
                        chunk_eyes: int = CHUNK_EYES) -> list[EyeResult]:
    """Every eye of ``eyes`` (`MeasuredWavefront`) under every condition of ``conditions``, in that order
    (conditions outer); an eye not measured at a condition's field is skipped (logged).

    The work is split into tasks of ``chunk_eyes`` eyes under one condition, each named by its eyes' identities
    only (no data travels): run here (``workers=1``, on this process's threads), in ``workers`` processes, or on a
    Dask ``client``
    (`dask.distributed.Client`, or anything with its ``map`` and ``gather``). The numbers do not depend on where."""
    frequencies = np.asarray(frequencies_cyc_per_deg, dtype=float)
    conditions = list(conditions)
    identities = [(e.dataset, e.subject, e.eye) for e in eyes]
    tasks = [(c, tuple(identities[i:i + chunk_eyes])) for c in conditions
             for i in range(0, len(identities), chunk_eyes)]
    if client is not None:
        futures = client.map(_evaluate_chunk, [t[0] for t in tasks], [t[1] for t in tasks],
                             [frequencies] * len(tasks), [True] * len(tasks), pure=False)
        done = client.gather(futures)
    elif workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=workers) as pool:
            done = list(pool.map(_evaluate_chunk, [t[0] for t in tasks], [t[1] for t in tasks],
                                 [frequencies] * len(tasks), [True] * len(tasks)))
    else:  # on this process's cores, OpenBLAS on one thread as in the workers: the same round-off everywhere
        done = map_on_threads(lambda task: _evaluate_chunk(task[0], task[1], frequencies, True), tasks)
    results = []
    for condition in conditions:
        skipped = []
        for (task_condition, _), (found, missed) in zip(tasks, done):
            if task_condition == condition:
                results.extend(found)
                skipped.extend(missed)
        if skipped:
            log.info("%s: %d eye(s) not measured there, skipped: %s", condition.label, len(skipped),
                     ", ".join(skipped))
    return results


def population_quantiles(results, quantiles=QUANTILES) -> dict:
    """{condition label: {quantity: array (one row per quantile; MTF: quantile x frequency)}} across the eyes."""
    summary: dict = {}
    for condition in dict.fromkeys(r.condition for r in results):
        rows = [r for r in results if r.condition == condition]
        table = {"count": len(rows)}
        for name in ("strehl", "m_diopters", "j0_diopters", "j45_diopters", "higher_order_rms_um"):
            table[name] = np.quantile([getattr(r, name) for r in rows], quantiles)
        if rows and rows[0].mtf.size:
            table["mtf"] = np.quantile(np.stack([r.mtf for r in rows]), quantiles, axis=0)
        summary[condition.label] = table
    return summary
