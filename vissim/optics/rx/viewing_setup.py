"""What a viewer focuses, through which pupil, with which magnification: decided once, here.

A `ViewingSetup` is one viewer (the DSLR bench camera, an eye, the ATV observer) looking
at an object at ``object_distance_m``.  It holds

* ``pupil_diameter_mm`` -- the entrance pupil (the camera's is focal length / f-number);
* ``defocus_matrix_diopters`` -- the dioptric defocus at the pupil, 2 x 2 in the TABO x/y frame:
  the viewer's excess power over what the object's light needs, ``D = E + A I + V`` (E the eye's
  refractive error or the power trial lenses add, A accommodation, V the vergence arriving
  at the pupil: ``-1/d`` for an object at d).  **A myopic viewer has D > 0**; it sees sharply
  where D = 0.  Its prescription (the correcting lens, `vissim.optics.rx.prescription`) is
  ``-D``;
* ``magnification_matrix`` -- maps a chief-ray angle without the trial lenses onto the angle
  with them (spectacle magnification, ERRATA item 5);
* ``wavelength_nm`` -- the wavelength the defocus is referenced to (the in-focus wavelength).

From these follow the wavefront (``W = -P r^2 / 2`` of the prescription P) and the geometric
blur: pupil (mm) x |principal defocus| (D) milliradians per principal meridian.

A `DepthViewer` is an uncorrected eye at every depth at once (the depth blurs,
`vissim.optics.depth.depth_map.blur_depth` and `vissim.optics.depth.layered.composite_layers`): the
same decision per depth as `ViewingSetup.eye`, on the eye's wavefront.

Named constructors only: `ViewingSetup.dslr`, `ViewingSetup.through_lenses`, `ViewingSetup.eye`,
`ViewingSetup.atv_observer`.  The thesis's choices are named replacements, each one field
changed (``dataclasses.replace``): `with_thesis_pupil` (ERRATA item 3),
`with_table_4_2_power` (item 4), `without_magnification`
(item 5).  Pinned by ``tests/test_setup.py``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM, finite_number, instance_of
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError
from vissim.optics.rx.accommodation import object_proximity_diopters
from vissim.optics.rx.prescription import Prescription, as_prescription
from vissim.optics.psf.field_size import front_at_wavelength
from vissim.optics.rx.trial_lens import (Matrix2, TrialLens, TrialLensSetup, entrance_pupil_diameter_mm, matrix2_tuple,
                                      principal_pairs, tabo_meridian_deg, thesis_eye_pupil_diameter_mm,
                                      thesis_table_4_2_lens_power, thesis_table_4_2_power, trial_lens_effect)
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import rad_to_arcmin

__all__ = ["ViewingSetup", "DepthViewer", "check_accommodation_diopters"]

_IDENTITY: Matrix2 = ((1.0, 0.0), (0.0, 1.0))


def _proximity(distance_m: float) -> float:
    return object_proximity_diopters(distance_m, "object distance")


def _lens_effect(lenses: TrialLensSetup) -> tuple[np.ndarray, Matrix2]:
    """(added power matrix D, magnification matrix) of ``lenses``: none and the identity without lenses."""
    if not lenses.lenses:
        return np.zeros((2, 2)), _IDENTITY
    effect = trial_lens_effect(lenses)
    return np.asarray(effect.added_power_matrix), effect.magnification_matrix


def check_accommodation_diopters(accommodation_diopters) -> float:
    """The accommodation exerted (D), refused unless finite and >= 0."""
    accommodation = finite_number(accommodation_diopters, "accommodation", "dioptres")
    if accommodation < 0.0:
        raise VissimInputError(f"accommodation exerted must be >= 0 dioptres, got {accommodation:g} D")
    return accommodation


@dataclass(frozen=True)
class ViewingSetup:
    """One viewer looking at one object distance (module doc); build it with a named constructor."""

    pupil_diameter_mm: float
    defocus_matrix_diopters: Matrix2
    magnification_matrix: Matrix2 = _IDENTITY
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM
    object_distance_m: float = math.inf

    # -- constructors -----------------------------------------------------------------------
    @classmethod
    def dslr(cls, focal_length_mm: float, f_number: float, focus_distance_m: float, lenses: TrialLensSetup,
             *, wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """The bench camera (pupil f/N) focused at ``focus_distance_m``, looking through ``lenses``.

        ``lenses.object_distance_m`` is the chart's distance; the lenses add their power at the
        pupil by `trial_lens_effect`, and the focus error adds
        ``1/focus - 1/chart``.
        """
        chart_m = lenses.object_distance_m
        focus_error = _proximity(focus_distance_m) - _proximity(chart_m)
        added, magnification = _lens_effect(lenses)
        return cls(entrance_pupil_diameter_mm(focal_length_mm, f_number), matrix2_tuple(added + focus_error * np.eye(2)),
                   magnification, wavelength_nm, chart_m)

    @classmethod
    def through_lenses(cls, pupil_diameter_mm: float, lenses: TrialLensSetup, *,
                       wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """A viewer of entrance pupil ``pupil_diameter_mm`` focused on the lenses' object (``lenses.object_distance_m``),
        looking through ``lenses``: their added power (`trial_lens_effect`) is its defocus, their spectacle
        magnification its magnification (what the eye bench sizes its chart texture by)."""
        added, magnification = _lens_effect(lenses)
        pupil = finite_number(pupil_diameter_mm, "entrance pupil diameter", "mm")
        if pupil <= 0.0:
            raise VissimInputError(f"entrance pupil diameter must be > 0 mm, got {pupil:g} mm")
        return cls(pupil, matrix2_tuple(added), magnification, wavelength_nm, lenses.object_distance_m)

    @classmethod
    def eye(cls, prescription: Prescription, pupil_diameter_mm: float, accommodation_diopters: float = 0.0,
            object_distance_m: float = math.inf, *, vergence_diopters=None,
            wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """An eye of correcting lens ``prescription`` (myope < 0, not worn) exerting ``accommodation_diopters``.

        D = -Rx + A I + V, V = -I/d for an object at ``object_distance_m`` or the given
        ``vergence_diopters`` (scalar or 2 x 2) of the light arriving at the pupil.
        """
        as_prescription(prescription)
        accommodation = check_accommodation_diopters(accommodation_diopters)
        if vergence_diopters is None:
            vergence = -_proximity(object_distance_m) * np.eye(2)
        else:
            vergence = np.asarray(vergence_diopters, dtype=float)
            vergence = vergence * np.eye(2) if vergence.ndim == 0 else vergence
        defocus = accommodation * np.eye(2) - np.asarray(prescription.power_matrix(), dtype=float) + vergence
        return cls(check_pupil_mm(pupil_diameter_mm), matrix2_tuple(defocus), _IDENTITY, wavelength_nm,
                   float(object_distance_m))

    @classmethod
    def atv_observer(cls, prescription: Prescription, pupil_diameter_mm: float, accommodation_diopters: float,
                     trial_lens_diopters: float, vertex_distance_mm: float, *,
                     wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """The ATV observer: a collimated pixel (source at infinity) through a thin trial lens.

        The lens of power P at d mm adds the vergence ``P / (1 - dP)`` at the eye, exact for a
        source at infinity (`thesis_table_4_2_power`).
        """
        vergence = thesis_table_4_2_power(trial_lens_diopters, vertex_distance_mm)
        return cls.eye(prescription, pupil_diameter_mm, accommodation_diopters, vergence_diopters=vergence,
                       wavelength_nm=wavelength_nm)

    # -- the thesis's choices, one field each -----------------------------------------------
    def with_thesis_pupil(self, f_number: float) -> ViewingSetup:
        """ERRATA item 3: the f-number-matched eye pupil of Table 4.1 (2.7 mm at f/5)."""
        return replace(self, pupil_diameter_mm=thesis_eye_pupil_diameter_mm(f_number))

    def with_table_4_2_power(self, lenses: tuple[TrialLens, ...], vertex_distance_mm: float) -> ViewingSetup:
        """ERRATA item 4: Table 4.2's P / (1 - dP) per principal meridian of the lenses' summed power."""
        power = thesis_table_4_2_lens_power(lenses, vertex_distance_mm)
        return replace(self, defocus_matrix_diopters=power.power_matrix())

    def without_magnification(self) -> ViewingSetup:
        """ERRATA item 5: no spectacle magnification."""
        return replace(self, magnification_matrix=_IDENTITY)

    def in_focus(self) -> ViewingSetup:
        """The same pupil and wavelength with no defocus: the diffraction limit."""
        return replace(self, defocus_matrix_diopters=((0.0, 0.0), (0.0, 0.0)))

    # -- what follows -----------------------------------------------------------------------
    @property
    def camera_prescription(self) -> Prescription:
        """The correcting lens equivalent to the defocus: ``-D`` (a myopic viewer's is < 0), minus cylinder."""
        return Prescription.from_power_matrix(-np.asarray(self.defocus_matrix_diopters, dtype=float))

    @property
    def wavefront(self) -> Wavefront:
        return Wavefront.from_prescription(self.camera_prescription, self.pupil_diameter_mm)

    @property
    def focus_matrix_diopters(self) -> np.ndarray:
        """The vergence matrix K the viewer focuses: objects at d are sharp where K = I/d."""
        return np.asarray(self.defocus_matrix_diopters, dtype=float) + _proximity(self.object_distance_m) * np.eye(2)

    @property
    def blur_diameter_arcmin(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Geometric blur ((diameter arcmin, meridian deg), ...) per principal meridian, larger defocus first."""
        values, vectors = np.linalg.eigh(np.asarray(self.defocus_matrix_diopters, dtype=float))
        return tuple((float(rad_to_arcmin(abs(value) * self.pupil_diameter_mm / 1000.0)), tabo_meridian_deg(vector))
                     for value, vector in zip(values[::-1], vectors.T[::-1]))  # type: ignore[return-value]

    def blur_diameter_at_arcmin(self, distance_m) -> np.ndarray:
        """Largest-meridian geometric blur of objects at axial ``distance_m`` (array, inf ok), same focus."""
        k = np.linalg.eigvalsh(self.focus_matrix_diopters)
        distance = np.asarray(distance_m, dtype=float)
        with np.errstate(divide="ignore"):
            proximity = np.where(np.isinf(distance), 0.0, 1.0 / distance)
        defocus = np.maximum(np.abs(k[0] - proximity), np.abs(k[1] - proximity))
        return rad_to_arcmin(defocus * self.pupil_diameter_mm / 1000.0)

    @property
    def magnification_principal(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Spectacle magnification per principal meridian ((mag, meridian_deg), ...), larger first."""
        m = np.asarray(self.magnification_matrix, dtype=float)
        return principal_pairs(0.5 * (m + m.T))


@dataclass(frozen=True, eq=False)
class DepthViewer:
    """An uncorrected eye seen at every depth: its defocus there, on its wavefront.

    ``prescription`` is the eye's correcting lens (myope < 0, *not* worn), ``pupil_diameter_mm``
    its pupil, ``accommodation_diopters`` (>= 0) the accommodation it exerts for the whole
    scene, ``extra_wavefront`` its further aberrations (higher orders, rescaled to the pupil).
    An object at proximity ``L = 1/d`` (D) sees the eye of `ViewingSetup.eye` at ``d``:
    ``D = A I - Rx - L I``, i.e. the prescription ``Rx + (L - A)`` on the sphere
    (`vissim.optics.rx.accommodation`); astigmatism and the extra terms are the same at every
    depth.  `wavefront_at` is that decision on the wavefront, `viewing_setup` the setup itself.

    A schematic eye (`vissim.optics.eyes.depth_eye.traced_depth_eye`) is built with
    ``accommodation_diopters = 0`` and its traced wavefront, accommodation included (physical: its
    lens changes shape), as ``extra_wavefront``: `in_focus_proximity_diopters` (``A - M`` of the
    whole wavefront) then finds its focus by the same rule, with no second one (a Navarro eye
    accommodated 2 D is in focus at its traced refraction, 2.56 D at 555 nm and 3 mm:
    ``tests/test_eye_field_blur.py``).
    """

    prescription: Prescription
    pupil_diameter_mm: float
    accommodation_diopters: float = 0.0
    extra_wavefront: Wavefront | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "prescription", as_prescription(self.prescription))
        object.__setattr__(self, "pupil_diameter_mm", check_pupil_mm(self.pupil_diameter_mm))
        object.__setattr__(self, "accommodation_diopters", check_accommodation_diopters(self.accommodation_diopters))
        extra = self.extra_wavefront
        if extra is not None:
            instance_of(extra, Wavefront, "extra_wavefront", "a Wavefront (higher-order terms) or None")
            if extra.pupil_diameter_mm < self.pupil_diameter_mm * (1 - 1e-12):
                raise VissimInputError(f"extra_wavefront is measured over {extra.pupil_diameter_mm:g} mm, smaller "
                                       f"than the {self.pupil_diameter_mm:g} mm pupil")

    @functools.cached_property
    def wavefront(self) -> Wavefront:
        """The relaxed eye's wavefront over its pupil: its prescription plus the extra terms."""
        front = Wavefront.from_prescription(self.prescription, self.pupil_diameter_mm)
        extra = self.extra_wavefront
        return front if extra is None else front + extra.rescaled(self.pupil_diameter_mm)

    def defocus_change_diopters(self, proximity_diopters: float) -> float:
        """``L - A``: the sphere an object at ``proximity_diopters`` adds to the relaxed eye's prescription."""
        return proximity_diopters - self.accommodation_diopters

    def wavefront_at(self, proximity_diopters: float) -> Wavefront:
        """The wavefront for an object at ``proximity_diopters`` (D, 0 at infinity)."""
        return self.wavefront.with_defocus_diopters(self.defocus_change_diopters(proximity_diopters))

    def sphere_at_diopters(self, proximity_diopters: float) -> float:
        """The effective prescription's sphere ``Rx_S + L - A`` for an object at ``proximity_diopters``."""
        return self.prescription.sphere_diopters + proximity_diopters - self.accommodation_diopters

    def check_light(self, wavelength_nm: float) -> None:
        """Refuse ``wavelength_nm`` when the eye's wavefront holds in other light (a traced eye's front: it is used in
        its own light only, `vissim.optics.psf.field_size.front_at_wavelength`)."""
        front_at_wavelength(self.wavefront, wavelength_nm, None)

    @property
    def in_focus_proximity_diopters(self) -> float:
        """``A - M`` (``M`` the wavefront's spherical equivalent): the proximity the eye focuses."""
        return self.accommodation_diopters - self.wavefront.to_prescription().spherical_equivalent_diopters

    def viewing_setup(self, object_distance_m: float = math.inf, *,
                      wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """This eye looking at ``object_distance_m`` (`ViewingSetup.eye`; the extra terms are not in a setup)."""
        return ViewingSetup.eye(self.prescription, self.pupil_diameter_mm, self.accommodation_diopters,
                                object_distance_m, wavelength_nm=wavelength_nm)
