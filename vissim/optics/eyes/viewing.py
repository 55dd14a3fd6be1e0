"""What an eye sees of a chart: an `Eye`, a trial lens in front, a chart distance and a field, decided once.

`EyeView` is the viewing physics the eye bench's simulations, the command line and a library user share:

* **The lens** (a thick `TrialLens`, its back vertex ``vertex_mm`` in front of the cornea): its added
  power and spectacle magnification at any plane behind the cornea (`trial_lens_effect`, the chart's
  vergence through it).
* **The reduced eye** (`reduced_setup`): `ViewingSetup.eye` with the eye's prescription carried to the
  corneal vertex (a thin lens at the vertex distance: P (I − dP)⁻¹), the lens's added power there and
  the chart's −1/d; the thesis's setup (`thesis_setup`): its lens P / (1 − dP), the chart at infinity.
* **The schematic eye** (`vergence_at_pupil`): the eye itself (ametropic when it has a prescription)
  and the light's vergence at its entrance pupil, ``depth`` behind the cornea: the lens's added power
  there and −1/(d + depth); `blur` and `spectral_wavefront` apply it (`vissim.blur_eye`).
* **The chart as seen** (`chart_points_arcmin`): pixel (row, col) of an image centred on the chart
  looks along the field angle (x, y) = the image's field minus its (col, row) offset (columns to the
  observer's right: −x), on the line that leaves the chief ray's point on the entrance-pupil plane
  (`vissim.optics.eyes.sight`: the film names a retinal point by a collimated chief ray), and meets
  the flat chart (facing the eye, its centre at the image's field from the corneal vertex) where this
  returns, in arcmin from the chart's centre as seen from the vertex. Off axis the chart is seen
  stretched across the field direction (1 / cos of the field angle) and nearer the axis by the pupil's
  parallax (3 mm × sin 20° / 6 m = 0.6 arcmin).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.checks import positive_number
from vissim.optics.eyes.ametropia import far_point_vergence_matrix
from vissim.optics.eyes.eye import Eye, checked_eye
from vissim.optics.eyes.field_blur import blur_eye, node_field_deg
from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye
from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront
from vissim.optics.eyes.sight import chief_pupil_point_mm, eye_to_world_rotation
from vissim.optics.eyes.traced_wavefront import entrance_pupil_from_iris_mm, field_direction
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import (TrialLensSetup, thesis_table_4_2_power, trial_lens_effect,
                                      vergence_after_distance)
from vissim.units import rad_to_arcmin

__all__ = ["EyeView"]


@dataclass(frozen=True)
class EyeView:
    """The `Eye` ``eye`` looking at a chart ``chart_distance_m`` away, its centre at ``field_deg`` (OSA x, y),
    through ``lens`` (a thick `TrialLens`, or None) whose back vertex is ``vertex_mm`` in front of the cornea."""

    eye: Eye
    chart_distance_m: float
    field_deg: tuple[float, float] = (0.0, 0.0)
    lens: object = None
    vertex_mm: float | None = None

    def __post_init__(self) -> None:
        checked_eye(self.eye, "EyeView")
        positive_number(self.chart_distance_m, "chart distance", "m")
        object.__setattr__(self, "field_deg", tuple(float(v) for v in self.field_deg))
        if self.vertex_mm is None:  # the lens at the eye's own spectacle plane, where its prescription is measured
            object.__setattr__(self, "vertex_mm", self.eye.vertex_distance_mm)

    @property
    def entrance_pupil_mm(self) -> float:
        """The eye's entrance pupil, mm: given, or the one its iris gives at its reference wavelength."""
        if self.eye.pupil_diameter_mm is not None:
            return self.eye.pupil_diameter_mm
        return entrance_pupil_from_iris_mm(self.eye.optics, self.eye.iris_mm, self.eye.reference_wavelength_nm)

    # -- the lens and the eye's own refraction ---------------------------------------------------------
    def lens_effect(self, to_pupil_mm: float) -> tuple[np.ndarray, np.ndarray]:
        """(added power matrix D, magnification matrix) of the lens at a plane ``to_pupil_mm`` behind the cornea."""
        if self.lens is None:
            return np.zeros((2, 2)), np.eye(2)
        setup = TrialLensSetup((self.lens,), self.vertex_mm + to_pupil_mm, self.chart_distance_m + 1e-3 * to_pupil_mm)
        effect = trial_lens_effect(setup)
        return np.asarray(effect.added_power_matrix, float), np.asarray(effect.magnification_matrix, float)

    def eye_refraction(self, depth_mm: float) -> np.ndarray:
        """The eye's own correcting lens (2 x 2 D; myope < 0) at ``depth_mm`` behind the corneal vertex: its
        prescription at its spectacle plane carried there (the far point's vergence); zero for an emmetrope."""
        if self.eye.rx is None:
            return np.zeros((2, 2))
        at_cornea = far_point_vergence_matrix(self.eye.rx, self.eye.vertex_distance_mm)
        return vergence_after_distance(at_cornea, 1e-3 * depth_mm)

    # -- the reduced eye --------------------------------------------------------------------------------
    def reduced_setup(self, wavelength_nm: float) -> tuple[ViewingSetup, np.ndarray]:
        """The reduced eye's `ViewingSetup` (module doc) in focus at ``wavelength_nm``, and the lens's magnification."""
        added, magnification = self.lens_effect(0.0)
        vergence = added - np.eye(2) / self.chart_distance_m
        rx = Prescription.from_power_matrix(self.eye_refraction(0.0))
        setup = ViewingSetup.eye(rx, self.entrance_pupil_mm, self.eye.accommodation_diopters,
                                 vergence_diopters=vergence, wavelength_nm=wavelength_nm)
        return setup, magnification

    def thesis_setup(self, wavelength_nm: float) -> ViewingSetup:
        """The thesis's setup: the eye's prescription, the lens's P / (1 - dP) (its sphere), the chart at infinity."""
        power = 0.0 if self.lens is None else thesis_table_4_2_power(self.lens.sphere_diopters, self.vertex_mm)
        rx = Prescription.from_power_matrix(self.eye_refraction(0.0))
        return ViewingSetup.eye(rx, self.entrance_pupil_mm, self.eye.accommodation_diopters, vergence_diopters=power,
                                wavelength_nm=wavelength_nm)

    # -- the schematic eye ------------------------------------------------------------------------------
    def vergence_at_pupil(self, wavelength_nm: float) -> tuple[np.ndarray, np.ndarray]:
        """The light's vergence at the eye's entrance pupil (2 x 2 D) and the lens's magnification (module doc)."""
        depth_mm = entrance_pupil_position_mm(mean_meridian_eye(self.eye.optics), wavelength_nm)
        added, magnification = self.lens_effect(depth_mm)
        return added - np.eye(2) / (self.chart_distance_m + 1e-3 * depth_mm), magnification

    def spectral_wavefront(self, wavelengths_nm, *, focus_nm: float, field_deg=None, eye: Eye | None = None):
        """The eye's `SpectralWavefront` at ``wavelengths_nm`` with the light's vergence (its entrance pupil's depth
        at ``focus_nm``), at ``field_deg`` (default the chart centre's); ``eye`` another pupil of the same eye."""
        vergence, _ = self.vergence_at_pupil(focus_nm)
        return eye_spectral_wavefront(self.eye if eye is None else eye, wavelengths_nm=wavelengths_nm,
                                      field_deg=self.field_deg if field_deg is None else field_deg,
                                      vergence_diopters=vergence)

    def blur(self, image: np.ndarray, *, arcmin_per_px: float, wavelength_nm, focus_nm: float, weights=None,
             **options) -> np.ndarray:
        """``image`` (centred on the chart) as the eye sees it through the lens: `vissim.blur_eye` with the light's
        vergence at its entrance pupil (depth at ``focus_nm``), at the chart centre's field."""
        vergence, _ = self.vergence_at_pupil(focus_nm)
        return blur_eye(image, self.eye, arcmin_per_px=arcmin_per_px, wavelength_nm=wavelength_nm, weights=weights,
                        vergence_diopters=vergence, field_deg=self.field_deg, **options)

    # -- the chart as seen ------------------------------------------------------------------------------
    def chart_points_arcmin(self, shape: tuple[int, int], step_arcmin: float) -> tuple[np.ndarray, np.ndarray] | None:
        """(rows, cols) arcmin from the chart's centre that each pixel of a ``shape`` image of ``step_arcmin`` sees
        (module doc); None when the chart is seen as drawn in visual angle (on the axis of a model without a
        visual axis, where the parallax only shrinks it by the pupil's depth over the distance, 0.05 % at 6 m)."""
        optics = self.eye.optics
        if self.field_deg == (0.0, 0.0) and optics.visual_axis_deg == 0.0:
            return None
        rows, cols = np.indices(shape)
        to_world = eye_to_world_rotation(optics, self.field_deg)
        sight = field_direction(optics, node_field_deg(rows, cols, shape, step_arcmin, self.field_deg)) @ to_world.T
        pupil = chief_pupil_point_mm(optics, self.field_deg, self.entrance_pupil_mm)  # the trace's frame: z to the retina
        start = to_world @ np.array([pupil[0], pupil[1], -pupil[2]])
        distance_mm = 1000.0 * self.chart_distance_m
        reach = (distance_mm - start[2]) / sight[..., 2]
        world_x, world_y = start[0] + reach * sight[..., 0], start[1] + reach * sight[..., 1]
        col_arcmin = rad_to_arcmin(np.arctan(-world_x / distance_mm))  # world +x: the observer's left
        row_arcmin = rad_to_arcmin(np.arctan(-world_y / distance_mm))
        return row_arcmin, col_arcmin
