"""One record of a schematic eye at a field point and a wavelength: what ``vissim eye`` prints.

`eye_report` builds the eye (`models.eye_model`, made ametropic by `fixation.ametropic_eye`
when a prescription is given), traces its wavefront over the entrance pupil
(`traced_wavefront.trace_eye_wavefront`), reads its refraction (`refraction.eye_refraction`) and its
MTF, and returns an `EyeReport` whose `EyeReport.as_json` has the keys of
``vissim eye --json``.

* **Wavelength**: the model's reference wavelength unless given (``EyeReport.wavelength_given``).
* **Pupils**: the entrance pupil (``pupil_mm``) or the iris (``iris_mm``); ``entrance_pupil``'s
  ``diameter_mm`` is the **real-ray** entrance pupil on axis (the one the Zernikes are over; the
  given value when the entrance pupil was given), ``paraxial_diameter_mm`` the paraxial image of
  the iris, ``position_mm`` the paraxial entrance pupil behind the corneal vertex.
* **Prescription** (``rx``): the eye that has it, written at the spectacle plane
  ``vertex_distance_mm`` in front of the cornea (12 mm by default), solved at the model's
  reference wavelength (axial length for the spherical equivalent, a toric cornea front for the
  cylinder: `vissim.optics.eyes.ametropia`). With a prescription, or a vertex distance given, the
  refraction is stated at that spectacle plane; otherwise at the corneal vertex. Off axis it is
  over the entrance pupil seen along the chief ray (JSON ``refraction.pupil_definition``; the
  `refraction` module doc).
* **Power, f′, retinal mm per degree**: paraxial, of the mean meridian for a toric eye
  (`paraxial.mean_meridian_eye`). f′ (``image_focal_length_mm``) is the image-space focal length
  n′/P, in the vitreous (`paraxial.image_focal_length_mm`), not the focal length in air 1/P.
* **MTF**: of the wave PSF (`vissim.optics.psf.compute.compute_psf`, diffraction included) of the traced
  wavefront's Zernikes (orders 2-8: piston and tilt only move the PSF) over the entrance pupil,
  at one wavelength, pixel sinc divided out. On axis (field (0, 0)) the radial average; off axis
  ``tangential`` (the spatial frequency along the field's meridian, the direction of (x, y)) and
  ``sagittal`` (perpendicular to it). Frequencies in cycles per degree of visual angle (object
  space; in front of the lenses when there are lenses), and in cycles per mm on the retina through
  the paraxial ``retinal_mm_per_deg`` (through the lenses: `spectacles.system_retinal_mm_per_deg`). Above
  the diffraction cutoff D/λ the MTF is 0.

* **Polychromatic MTF** (``mtf_spectrum``, an `MtfSpectrum`: wavelengths and weights, e.g. the
  photopic spectrum of `vissim.spectra.named_spectrum`): the MTF is then of the weighted sum of each
  wavelength's wave PSF, the eye traced at each wavelength
  (`vissim.optics.eyes.psf_wavefront.traced_spectral_wavefront`: its own defocus and aberrations,
  and its transverse chromatic aberration as tilt relative to the report's wavelength, tilts kept). The
  Zernikes, RMS, refraction, power and pupils stay at the report's one wavelength (the model's
  reference unless given); JSON ``mtf.spectrum`` records both.

* **Lenses in front** (``lenses``: thick `TrialLens` es, object to eye, the last one's back vertex
  ``vertex_distance_mm`` (default 12 mm) in front of the cornea, ``lens_gap_mm`` apart): traced
  surface by surface with the eye (`vissim.optics.eyes.traced_wavefront`). The Zernikes are then over the
  iris's image through the lenses and the cornea, and the refraction is the **over-refraction**: the
  thin lens touching the front of the first lens that would correct what remains, stated at that
  plane (as `spectacles.residual_refraction`'s `SPECTACLE` plane, its paraxial oracle). Thin
  lenses are refused: make them thick first (`vissim.bench.atv.tube.atv_trial_lens`).

* **LCA** (``lca=True``): the eye's chromatic difference of refraction over 400-700 nm
  (`lca.lca_curve`), traced behind the report's iris at its field point, re the report's
  wavelength, beside the paraxial curve, Thibos's chromatic eye and Atchison & Smith 2005; without
  lenses in front (the eye's own).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import EYE_MTF_RANGE_CYC_PER_DEG, finite_number
from vissim.checks import mtf_cyc_per_deg as mtf_cyc_per_deg_in_range
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.psf import metrics as psf_metrics
from vissim.optics.eyes.eye import Eye, checked_eye
from vissim.optics.eyes.lca import LcaCurve, lca_curve
from vissim.optics.eyes.measured.measured_eye import measured_front
from vissim.optics.eyes.paraxial import (image_focal_length_mm, entrance_pupil_diameter_mm,
                                         equivalent_power_diopters, mean_meridian_eye, retinal_mm_per_deg)
from vissim.optics.eyes.psf_wavefront import traced_spectral_wavefront
from vissim.optics.eyes.refraction import BEAM_PLANE, ENTRANCE_PUPIL_PLANE, EyeRefraction, eye_refraction
from vissim.optics.eyes.spectacles import system_entrance_pupil_mm, system_retinal_mm_per_deg
from vissim.units import osa_xy_to_image_colrow
from vissim.optics.eyes.traced_wavefront import EyeWavefront, trace_eye_wavefront
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.psf.field_size import MAX_ENERGY_OUTSIDE, energy_outside_field, size_holding_px
from vissim.optics.pupil.spectral_wavefront import SpectralWavefront, field_map_stretch
from vissim.optics.rx.trial_lens import TrialLensSetup
from vissim.optics.pupil.wavefront import Wavefront

ndimage = lazy_module("scipy.ndimage")

__all__ = ["EyeReport", "MtfSpectrum", "eye_report", "eye_mtf", "MTF_NYQUIST_PER_CUTOFF", "MTF_SIZE_PX"]

#: The PSF's sampling: its Nyquist frequency is this many times the diffraction cutoff D/λ.
MTF_NYQUIST_PER_CUTOFF = 1.25
#: The PSF's side, pixels: the MTF's frequency step is cutoff * 2 * 1.25 / 512, about 0.5 cyc/deg at 3 mm.
#: A PSF that leaves more than `MAX_ENERGY_OUTSIDE` of its energy outside is computed again over the
#: field that holds it (`vissim.optics.psf.field_size.size_holding_px`): slow (tens of seconds) for an 8 mm
#: pupil at 40°.
MTF_SIZE_PX = 512


def _frequencies(values, name: str) -> np.ndarray:
    out = np.array([finite_number(v, name, "cycles") for v in values], dtype=float)
    if np.any(out < 0.0):
        raise VissimInputError(f"{name} must be >= 0, got {float(out[out < 0.0][0]):g}")
    return out


def _within_cutoff(f_mm: np.ndarray, mm_per_deg: float) -> None:
    """Retinal frequencies (cycles/mm) within `EYE_MTF_RANGE_CYC_PER_DEG` once in cycles/deg on this eye's retina."""
    high = EYE_MTF_RANGE_CYC_PER_DEG[1]
    beyond = f_mm[f_mm * mm_per_deg > high]
    if len(beyond):
        raise VissimInputError(f"MTF frequency (per mm) {float(beyond[0]):g} cycles/mm is {float(beyond[0]) * mm_per_deg:g} "
                               f"cycles/deg on this retina ({mm_per_deg:.4g} mm/deg), beyond the {high:.0f} cycles/deg "
                               "cutoff of the widest eye pupil in the shortest light (every eye's MTF is 0 there)")


def _mtf_directions(field_deg) -> dict[str, tuple[float, float] | None]:
    """``{"radial": None}`` on axis; else the tangential and sagittal unit vectors in OSA's (x, y)."""
    fx, fy = field_deg
    norm = math.hypot(fx, fy)
    if norm == 0.0:
        return {"radial": None}
    tx, ty = fx / norm, fy / norm
    return {"tangential": (tx, ty), "sagittal": (-ty, tx)}


def eye_mtf(wavefront: Wavefront, wavelength_nm, frequencies_cyc_per_deg, field_deg=(0.0, 0.0),
            weights=None) -> dict:
    """The MTF of the wave PSF of ``wavefront`` (over its pupil) at ``frequencies_cyc_per_deg``:
    ``{direction: array}``, ``radial`` on axis, ``tangential`` and ``sagittal`` off axis (module doc).
    Polychromatic: ``wavefront`` a `SpectralWavefront`, ``wavelength_nm`` several of its wavelengths and
    ``weights`` their relative weights (default equal); sampled for the shortest wavelength's cutoff."""
    wavelengths = [checked_wavelength_nm(w) for w in np.atleast_1d(wavelength_nm)]
    weights = [1.0] * len(wavelengths) if weights is None else [float(w) for w in weights]
    f = _frequencies(frequencies_cyc_per_deg, "MTF frequency (per degree)")
    cutoff = psf_metrics.diffraction_cutoff_cyc_per_deg(wavefront.pupil_diameter_mm, min(wavelengths))
    step_arcmin = 30.0 / (MTF_NYQUIST_PER_CUTOFF * cutoff)
    size = MTF_SIZE_PX
    diameter = wavefront.pupil_diameter_mm
    if energy_outside_field(wavefront, diameter, wavelengths, weights, step_arcmin, size) > MAX_ENERGY_OUTSIDE:
        size = size_holding_px(wavefront, diameter, wavelengths, weights, step_arcmin, size)  # a cut PSF smooths its OTF
    size = 2 * math.ceil(field_map_stretch(getattr(wavefront, "field_map", None)) * size / 2)  # a mapped front's widening
    psf = compute_psf(wavefront, wavelength_nm=wavelengths, weights=weights, arcmin_per_px=step_arcmin, size_px=size,
                      normalise="total")  # compute_psf's precision: a photopic MTF within 2e-8 of double
    m = psf_metrics.mtf(psf, remove_pixel=True)
    axis = psf_metrics.frequencies_cyc_per_deg(psf)
    df, centre = axis[1] - axis[0], m.shape[0] // 2
    out = {}
    for name, direction in _mtf_directions(field_deg).items():
        if direction is None:
            rows, cols = np.indices(m.shape) - centre
            radius, mean = psf_metrics.ring_means(m, np.hypot(rows, cols) * df, df)
            values = np.interp(f, radius, mean)
        else:  # the field direction, OSA (x, y), as image (col, row) offsets
            d_col, d_row = osa_xy_to_image_colrow(direction[0], direction[1])
            cols, rows = centre + f * d_col / df, centre + f * d_row / df
            values = ndimage.map_coordinates(m, [rows, cols], order=1, mode="nearest")
        out[name] = np.where(f >= cutoff, 0.0, np.minimum(values, 1.0))
    return out


@dataclass(frozen=True)
class MtfSpectrum:
    """The light a polychromatic MTF is of: wavelengths (nm), relative weights, and a name (e.g.
    ``"photopic"``, or ``""`` for wavelengths given one by one)."""

    wavelengths_nm: tuple[float, ...]
    weights: tuple[float, ...]
    name: str = ""

    def __post_init__(self) -> None:
        wavelengths = tuple(checked_wavelength_nm(w) for w in self.wavelengths_nm)
        weights = tuple(finite_number(w, "spectral weight", "relative units") for w in self.weights)
        if not wavelengths or len(weights) != len(wavelengths) or min(weights) < 0 or sum(weights) <= 0:
            raise VissimInputError(f"need one non-negative weight per wavelength, got {list(self.weights)} for "
                                   f"{list(self.wavelengths_nm)} nm")
        if len(set(wavelengths)) != len(wavelengths):
            raise VissimInputError(f"a spectrum's wavelengths must differ, got {list(wavelengths)} nm")
        object.__setattr__(self, "wavelengths_nm", wavelengths)
        object.__setattr__(self, "weights", weights)

    def as_json(self, reference_nm: float) -> dict:
        total = sum(self.weights)
        return {"name": self.name or "wavelengths given", "wavelengths_nm": list(self.wavelengths_nm),
                "weights": [w / total for w in self.weights],
                "zernikes_and_refraction_at_nm": reference_nm, "tca_reference_nm": reference_nm}


@dataclass(frozen=True, eq=False)
class EyeReport:
    """A schematic eye's numbers at one field point and one wavelength (module doc)."""

    model: str
    accommodation_diopters: float
    wavelength_nm: float
    wavelength_given: bool
    prescription: Prescription | None
    power_diopters: float
    image_focal_length_mm: float
    retinal_mm_per_deg: float
    paraxial_entrance_pupil_mm: float
    wavefront: EyeWavefront
    refraction: EyeRefraction
    mtf_cyc_per_deg: dict
    mtf_cyc_per_mm: dict
    lens_setup: TrialLensSetup | None = None
    mtf_spectrum: MtfSpectrum | None = None
    lca: LcaCurve | None = None
    base_model: str | None = None  # a measured eye's schematic base

    def as_json(self) -> dict:
        """The record of ``vissim eye --json`` (plain numbers; Zernikes keyed ``"n,m"``)."""
        wf = self.wavefront
        mtf = {}
        for key, table in (("cyc_per_mm", self.mtf_cyc_per_mm), ("cyc_per_deg", self.mtf_cyc_per_deg)):
            if table:
                mtf[key] = {direction: [[float(f), float(v)] for f, v in pairs] for direction, pairs in table.items()}
        if mtf:
            mtf["directions"] = ("radial average (on axis)" if "radial" in next(iter(mtf.values())) else
                                 "tangential: frequency along the field's meridian (x, y); sagittal: across it")
            if self.mtf_spectrum is not None:
                mtf["spectrum"] = self.mtf_spectrum.as_json(self.wavelength_nm)
        refraction = self.refraction.as_json()
        return {
            "model": self.model,
            **({} if self.base_model is None else {"base_model": self.base_model}),
            "accommodation_diopters": self.accommodation_diopters,
            "prescription": None if self.prescription is None else str(self.prescription),
            "power_diopters": self.power_diopters,
            "image_focal_length_mm": self.image_focal_length_mm,
            "retinal_mm_per_deg": self.retinal_mm_per_deg,
            "entrance_pupil": {"diameter_mm": float(wf.entrance_pupil_mm),
                               "position_mm": float(wf.entrance_pupil_position_mm),
                               "paraxial_diameter_mm": self.paraxial_entrance_pupil_mm,
                               "diameter": "real rays on axis (the Zernike pupil)", "given": wf.pupil_given,
                               "through_lenses": self.lens_setup is not None,
                               "eye_diameter_mm": float(wf.eye_entrance_pupil_mm)},
            "lenses": self._lenses_json(),
            "iris_mm": wf.iris_mm,
            "wavelength_nm": self.wavelength_nm,
            "wavelength": "given" if self.wavelength_given else "the model's reference wavelength",
            "field_deg": list(wf.field_deg),
            "field_axis": wf.field_axis,
            "zernike_um": {f"{n},{m}": float(v) for (n, m), v in sorted(wf.zernike_um.items())},
            "zernike_pupil": (ENTRANCE_PUPIL_PLANE if wf.pupil_plane != BEAM_PLANE
                              else f"entrance pupil seen along the chief ray ({BEAM_PLANE}: the data's)"),
            "rms_um": wf.rms_um,
            "refraction": {"paraxial": refraction["paraxial"], "minimum_rms": refraction["minimum_rms"],
                           "refraction_plane": self._plane_text(),
                           "vertex_distance_mm": refraction["vertex_distance_mm"],
                           "pupil_definition": refraction["pupil_definition"]},
            "mtf": mtf,
            **({} if self.lca is None else {"lca": self.lca.as_json()}),
        }

    def _plane_text(self) -> str:
        if self.refraction.plane == "corneal vertex":
            return "corneal vertex"
        if self.lens_setup is not None:
            return f"front of the lenses at {self.refraction.vertex_distance_mm:g} mm (over-refraction)"
        return f"spectacle plane at {self.refraction.vertex_distance_mm:g} mm"

    def _lenses_json(self) -> list:
        if self.lens_setup is None:
            return []
        return [{"marked_power": str(lens.marked_power), "refractive_index_d": lens.refractive_index,
                 "center_thickness_mm": lens.center_thickness_mm, "back_surface_diopters": lens.back_surface_diopters}
                for lens in self.lens_setup.lenses]


def _pairs(frequencies, table: dict) -> dict:
    return {name: list(zip(frequencies, values)) for name, values in table.items()}


def eye_report(eye: Eye, *, wavelength_nm=None, field_deg=(0.0, 0.0), at_spectacle_plane: bool = False,
               mtf_cyc_per_mm=(), mtf_cyc_per_deg=(), lenses=(), lens_gap_mm: float = 0.0,
               mtf_spectrum: MtfSpectrum | None = None, lca: bool = False) -> EyeReport:
    """The `EyeReport` of the `Eye` ``eye`` (its model, accommodation, pupil and the prescription it has), module doc.

    ``lenses``: thick trial or spectacle lenses worn at the eye's spectacle plane (``eye.vertex_distance_mm`` in front of
    the cornea, module doc); the refraction is stated there when the eye has a prescription, wears lenses or
    ``at_spectacle_plane``, else at the corneal vertex; ``lca``: add the eye's LCA curve (module doc). Bad input --
    a pupil the iris cannot give, a field where rays miss a surface, meet total internal reflection or leave the
    GRIN lens, a negative frequency -- raises one `VissimInputError` naming the value and its unit.
    ``mtf_spectrum``: the MTF of that light (module doc), all else at ``wavelength_nm``.
    """
    eye_in = checked_eye(eye, "eye_report")
    f_mm = _frequencies(mtf_cyc_per_mm, "MTF frequency (per mm)")
    f_deg = np.array(mtf_cyc_per_deg_in_range(_frequencies(mtf_cyc_per_deg, "MTF frequency (per degree)"),
                                              "MTF frequency (per degree)"), dtype=float)
    vertex = eye_in.vertex_distance_mm if (at_spectacle_plane or eye_in.rx is not None or len(lenses)) else None
    prescription = eye_in.rx
    eye = eye_in.optics
    pupil_mm, iris_mm = eye_in.pupil_diameter_mm, eye_in.iris_mm
    setup = None
    if len(lenses):
        setup = TrialLensSetup(tuple(lenses), vertex, math.inf, lens_gap_mm)
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else checked_wavelength_nm(wavelength_nm)
    field = tuple(float(v) for v in field_deg)
    front = trace_eye_wavefront(eye, wavelength, field, pupil_mm=pupil_mm, iris_mm=iris_mm, lenses=setup)
    if eye_in.measured is not None:
        front = measured_front(front, eye_in.measured, eye, traced=(front,))
    refraction = eye_refraction(front, vertex if setup is None else setup.span_mm)
    mean = mean_meridian_eye(eye)
    if setup is None:
        mm_per_deg = retinal_mm_per_deg(mean, wavelength)
    else:
        mm_per_deg = system_retinal_mm_per_deg(eye, setup, wavelength)
    _within_cutoff(f_mm, mm_per_deg)
    tables_deg, tables_mm = {}, {}
    if len(f_deg) or len(f_mm):
        everything = _mtf(eye, front, setup, mtf_spectrum, np.concatenate([f_deg, f_mm * mm_per_deg]), eye_in.measured)
        tables_deg = _pairs(f_deg, {k: v[:len(f_deg)] for k, v in everything.items()}) if len(f_deg) else {}
        tables_mm = _pairs(f_mm, {k: v[len(f_deg):] for k, v in everything.items()}) if len(f_mm) else {}
    if setup is None:
        paraxial_pupil = entrance_pupil_diameter_mm(mean, front.iris_mm, wavelength)
    else:
        paraxial_pupil = front.iris_mm * system_entrance_pupil_mm(eye, setup, wavelength)[1]
    curve = lca_curve(eye, iris_mm=front.iris_mm, reference_nm=wavelength, field_deg=field) if lca else None
    return EyeReport(eye_in.model, eye_in.accommodation_diopters, wavelength, wavelength_nm is not None, prescription,
                     float(equivalent_power_diopters(mean, wavelength)), float(image_focal_length_mm(mean, wavelength)),
                     float(mm_per_deg), float(paraxial_pupil), front, refraction, tables_deg, tables_mm, setup,
                     mtf_spectrum, curve, None if eye_in.measured is None else eye.name)


def _mtf(eye, front: EyeWavefront, setup, spectrum: MtfSpectrum | None, f_deg, measured=None) -> dict:
    """`eye_mtf` at the traced front's wavelength (orders 2-8), or over ``spectrum`` (tilts kept: the TCA)."""
    if spectrum is None:
        higher = {k: v for k, v in front.zernike_um.items() if k[0] >= 2}
        own = SpectralWavefront((front.wavelength_nm,), (Wavefront(higher, front.entrance_pupil_mm),),
                                field_map=front.field_map)
        return eye_mtf(own, front.wavelength_nm, f_deg, front.field_deg)
    spectral = traced_spectral_wavefront(eye, spectrum.wavelengths_nm, front.field_deg,
                                         pupil_mm=front.eye_entrance_pupil_mm, lenses=setup,
                                         reference_wavelength_nm=front.wavelength_nm, measured=measured)
    weights = dict(zip(spectrum.wavelengths_nm, spectrum.weights))
    return eye_mtf(spectral, spectral.wavelengths_nm, f_deg, front.field_deg,
                   [weights[w] for w in spectral.wavelengths_nm])
