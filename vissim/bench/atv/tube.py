"""The ATV tube of thesis section 5.4 (Fig. 5.4): one lit phone pixel seen through an 8 D lens.

A 125 mm tube, dull black inside, holds an iPhone 5 (326 ppi) at one end and an 8 D
plano-convex lens with an eyecup at the other; the phone sits in the lens's focal plane, so a
lit pixel reaches the eye as parallel light, "equivalent to observing a point at infinity".
Trial lenses (-5 ... +5 D) go in a slot between the lens and the eye.

World frame (millimetres), the same as `vissim.bench.dslr.bench`: the eye's pupil -- a reduced
eye, a thin lens at its pupil -- at z = 0, looking along +z with +y up; world x is the
examiner's right (TABO and OSA pupil x), so the eye's right is world -x.  Light travels toward
-z: pixel (``phone_z_mm``), collimator, trial lens, pupil.

Choices, and why:

* **Tube length** is measured from the phone's screen to the collimator's *front principal
  plane*; the default 125 mm = 1000 / 8 D puts the pixel exactly in the focal plane (thesis:
  "the length of the tube equal to this lens focal distance").  Another length defocuses the
  phone, and every prediction here follows it.
* **Collimator**: ``lens_power_diopters`` is its equivalent power.  Convex side toward the eye
  by default -- the orientation of least spherical aberration for a collimator (the thesis does
  not say); ``lens_convex_side="phone"`` turns it round.  3 mm thick over a 22 mm clear aperture.
* **Pixel**: a Lambertian square of side 25.4 / ppi mm (77.9 µm at 326 ppi) whose *linear*
  radiance is ``pixel_radiance``.  The thesis's "iPhone intensity [0, 1]" is a display code
  value (ERRATA item 9); `display_code_to_linear` is the separate transfer step.
* **Trial lens**: a thick crown-glass `TrialLens` (marked with its back
  vertex power, as meshed by `vissim.bench.lenses.mesh`), back vertex
  ``trial_lens_distance_mm`` in front of the pupil (15 mm: a 12 mm vertex distance plus 3 mm
  from the cornea to the entrance pupil).  `atv_trial_lens` makes one of realistic
  thickness.
* **Eye**: pupil within ``vissim.checks.EYE_PUPIL_RANGE_MM`` (1-10 mm), its own `RefractiveError` (a
  `Prescription` is converted) and accommodation >= 0 D.  A ray
  through pupil point x (mm) with direction angle u lands at visual angle
  ``-u + (E + A) x`` milliradians: the thin lens is the eye's excess power E plus accommodation.

The paraxial theory is `vissim.bench.atv.paraxial`, the Mitsuba scene dict
`vissim.bench.atv.scene`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from vissim.optics.rx.trial_lens import lens_surface_curvatures_per_mm
from vissim.bench.lenses.mesh import (realistic_center_thickness_mm,
                                      rim_thickness_mm, sag_mm)
from vissim.charts import MM_PER_INCH
from vissim.checks import (ACCOMMODATION_RANGE_DIOPTERS, BENCH_LENGTH_RANGE_MM, COLLIMATOR_POWER_RANGE_DIOPTERS,
                           DISPLAY_CODE_RANGE, DISPLAY_PPI_RANGE, MAX_PIXEL_RADIANCE, REFRACTIVE_INDEX_RANGE,
                           VERTEX_DISTANCE_RANGE_MM, eye_pupil_diameter_mm, finite_number)
from vissim.errors import VissimInputError
from vissim.imageio import srgb_decode
from vissim.optics.rx.prescription import LensPower, Prescription, RefractiveError
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX, EYE_VERTEX_DISTANCE_MM, TrialLens
from vissim.units import diopters_to_mm, m_to_mm, mm_to_m

__all__ = ["IPHONE5_PPI", "DISPLAY_TRANSFERS", "AtvTube", "AtvEye", "AtvConfig", "AtvLayout",
           "atv_trial_lens", "atv_layout", "display_code_to_linear", "pixel_pitch_mm"]

#: Pixel density of the iPhone 5's Retina display (thesis section 5.4).
IPHONE5_PPI = 326.0
#: From the trial lens's back vertex to the eye's pupil in the eyecup slot (mm); the thesis gives none,
#: so it is an eye's default (12 mm spectacle vertex distance + 3 mm cornea to entrance pupil).
ATV_TRIAL_LENS_DISTANCE_MM = EYE_VERTEX_DISTANCE_MM
DISPLAY_TRANSFERS = ("srgb", "gamma2.2")
#: Tube radius beyond the largest clear aperture, mm (the lenses sit in the tube).
TUBE_CLEARANCE_MM = 0.05
#: Least air between the trial lens and the collimator, and between the pupil and the trial lens, mm.
MIN_AIR_GAP_MM = 0.5


def _number(value, name: str, unit: str, *, lo: float | None = None, hi: float | None = None,
            lo_open: bool = False) -> float:
    number = finite_number(value, name, unit)
    if lo is not None and (number < lo or (lo_open and number == lo)):
        raise VissimInputError(f"{name} must be {'>' if lo_open else '>='} {lo:g} {unit}, got {number:g} {unit}")
    if hi is not None and number > hi:
        raise VissimInputError(f"{name} must be <= {hi:g} {unit}, got {number:g} {unit}")
    return number + 0.0



def pixel_pitch_mm(pixels_per_inch: float) -> float:
    """Side of one display pixel in mm: 25.4 / ppi (77.9 µm at 326 ppi)."""
    return MM_PER_INCH / _number(pixels_per_inch, "display resolution", "pixels per inch", lo=0.0, lo_open=True)


#: The phone display's transfer function used by every ATV path (render atv, atv simulate):
#: a pure 2.2 power law, a common model of phone displays; "srgb" is available explicitly.
ATV_DISPLAY_TRANSFER = "gamma2.2"


def display_code_to_linear(code, transfer: str = ATV_DISPLAY_TRANSFER):
    """Relative linear luminance in [0, 1] of a display code value in [0, 1] (ERRATA item 9).

    ``"srgb"``: the IEC 61966-2-1 decoding (`vissim.imageio.srgb_decode`); ``"gamma2.2"``:
    a pure power law ``code ** 2.2``.  Multiply by the display's white radiance to get
    `AtvTube.pixel_radiance`.  Scalars give floats, arrays arrays.
    """
    if transfer not in DISPLAY_TRANSFERS:
        raise VissimInputError(f"display transfer must be one of {', '.join(DISPLAY_TRANSFERS)}, got {transfer!r}")
    try:
        values = np.asarray(code, dtype=float)
    except (TypeError, ValueError):
        raise VissimInputError(f"display code must be a number in [0, 1] (code units), got {code!r}") from None
    low, high = DISPLAY_CODE_RANGE
    if not np.all(np.isfinite(values)) or values.min(initial=low) < low or values.max(initial=low) > high:
        raise VissimInputError(f"display code must lie in [0, 1] (code units), got {code!r}")
    linear = srgb_decode(values) if transfer == "srgb" else np.power(values, 2.2)
    return float(linear) if np.ndim(code) == 0 else np.asarray(linear, dtype=float)


@dataclass(frozen=True)
class AtvTube:
    """The tube, its collimating lens and the phone (module doc for the conventions)."""

    tube_length_mm: float = 125.0
    lens_power_diopters: float = 8.0
    lens_refractive_index: float = CROWN_GLASS_INDEX
    lens_center_thickness_mm: float = 3.0
    lens_clear_aperture_mm: float = 22.0
    lens_convex_side: str = "eye"
    eye_relief_mm: float = 25.0
    pixels_per_inch: float = IPHONE5_PPI
    pixel_radiance: float = 1.0
    pixel_offset_mm: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name, (what, unit, lo, lo_open, hi) in {  # field: (what, unit, lowest, lowest excluded, highest)
            "tube_length_mm": ("tube length", "mm", 0.0, True, BENCH_LENGTH_RANGE_MM[1]),
            "lens_power_diopters": ("collimator power", "dioptres", COLLIMATOR_POWER_RANGE_DIOPTERS[0], True,
                                    COLLIMATOR_POWER_RANGE_DIOPTERS[1]),
            "lens_refractive_index": ("collimator refractive index", "(dimensionless)",
                                      REFRACTIVE_INDEX_RANGE[0], False, REFRACTIVE_INDEX_RANGE[1]),
            "lens_center_thickness_mm": ("collimator centre thickness", "mm", 0.0, True, BENCH_LENGTH_RANGE_MM[1]),
            "lens_clear_aperture_mm": ("collimator clear aperture", "mm", 0.0, True, BENCH_LENGTH_RANGE_MM[1]),
            "eye_relief_mm": ("eye relief", "mm", 0.0, True, BENCH_LENGTH_RANGE_MM[1]),
            "pixels_per_inch": ("display resolution", "pixels per inch", DISPLAY_PPI_RANGE[0], False,
                                DISPLAY_PPI_RANGE[1]),
            "pixel_radiance": ("pixel radiance", "linear radiance units", 0.0, False, MAX_PIXEL_RADIANCE),
        }.items():
            object.__setattr__(self, name, _number(getattr(self, name), what, unit, lo=lo, lo_open=lo_open, hi=hi))
        if self.lens_convex_side not in ("eye", "phone"):
            raise VissimInputError(f"lens_convex_side must be 'eye' or 'phone', got {self.lens_convex_side!r}")
        try:
            offset = tuple(_number(v, "pixel offset", "mm") for v in self.pixel_offset_mm)
        except TypeError:
            raise VissimInputError(f"pixel offset must be (x, y) in mm, got {self.pixel_offset_mm!r}") from None
        if len(offset) != 2 or math.hypot(*offset) > 0.25 * self.lens_clear_aperture_mm:
            raise VissimInputError(
                f"pixel offset must be (x, y) in mm within {0.25 * self.lens_clear_aperture_mm:g} mm of the axis, "
                f"got {self.pixel_offset_mm!r}")
        object.__setattr__(self, "pixel_offset_mm", offset)
        thinnest, _ = rim_thickness_mm(self.collimator_lens(), self.lens_clear_aperture_mm)
        if thinnest <= 0.0:
            raise VissimInputError(
                f"a {self.lens_center_thickness_mm:g} mm thick {self.lens_power_diopters:g} D collimator has no edge "
                f"at a {self.lens_clear_aperture_mm:g} mm clear aperture ({thinnest:.3g} mm); make it thicker")
        if self.front_focal_distance_mm() + self.tube_length_mm - self.focal_length_mm <= 0.0:
            raise VissimInputError(f"tube length {self.tube_length_mm:g} mm puts the phone inside the collimator")

    @property
    def focal_length_mm(self) -> float:
        return diopters_to_mm(self.lens_power_diopters)

    @property
    def pixel_pitch_mm(self) -> float:
        return pixel_pitch_mm(self.pixels_per_inch)

    def collimator_lens(self) -> TrialLens:
        """The plano-convex collimator as a `TrialLens` (front = phone side) of equivalent power P."""
        power, n, t = self.lens_power_diopters, self.lens_refractive_index, self.lens_center_thickness_mm
        if self.lens_convex_side == "eye":  # plano front, F2 = P: back vertex power = P
            return TrialLens(power, refractive_index=n, center_thickness_mm=t, back_surface_diopters=power)
        reduced_m = mm_to_m(t) / n  # convex front F1 = P, plano back: back vertex power P / (1 - t/n P)
        return TrialLens(power / (1.0 - reduced_m * power), refractive_index=n, center_thickness_mm=t)

    def front_focal_distance_mm(self) -> float:
        """From the phone-side vertex to the front focal point, mm (f - t/n for convex toward the eye)."""
        d = self.collimator_lens().ray_transfer_matrix()[2, 2]
        return m_to_mm(d) / self.lens_power_diopters


@dataclass(frozen=True)
class AtvEye:
    """The observer: pupil diameter, own refractive error (excess power), accommodation."""

    pupil_diameter_mm: float = 4.0
    refractive_error: RefractiveError | Prescription | None = None
    accommodation_diopters: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "pupil_diameter_mm", eye_pupil_diameter_mm(self.pupil_diameter_mm))
        error = self.refractive_error
        if error is None:
            error = RefractiveError(0.0)
        elif isinstance(error, Prescription):
            error = error.refractive_error()
        elif isinstance(error, LensPower) or not isinstance(error, RefractiveError):
            raise VissimInputError(
                f"the eye's refraction must be a Prescription or a RefractiveError, got {type(error).__name__}")
        object.__setattr__(self, "refractive_error", error)
        low, high = ACCOMMODATION_RANGE_DIOPTERS
        object.__setattr__(self, "accommodation_diopters", _number(
            self.accommodation_diopters, "accommodation", "dioptres", lo=low, hi=high))

    def viewing_setup(self, vergence_diopters=None) -> ViewingSetup:
        """This eye's `ViewingSetup.eye`; its defocus matrix
        is the eye's excess power, error + accommodation, plus ``vergence_diopters`` at the pupil (0 if None)."""
        return ViewingSetup.eye(self.refractive_error.prescription(), self.pupil_diameter_mm,
                                self.accommodation_diopters, vergence_diopters=vergence_diopters)


def atv_trial_lens(sphere_diopters: float, cylinder_diopters: float = 0.0, axis_deg: float = 180.0, *,
                   clear_aperture_mm: float = 22.0, refractive_index: float = CROWN_GLASS_INDEX) -> TrialLens:
    """A crown-glass trial lens of realistic centre thickness (1 mm minimum at edge and centre)."""
    power = LensPower(sphere_diopters, cylinder_diopters, axis_deg)
    thickness = realistic_center_thickness_mm(power, clear_aperture_mm, refractive_index)
    return TrialLens(power.sphere_diopters, power.cylinder_diopters, power.axis_deg,
                     refractive_index=refractive_index, center_thickness_mm=thickness)


@dataclass(frozen=True)
class AtvLayout:
    """Axial positions in the world frame, mm (pupil at 0); ``trial_*`` are None without a trial lens."""

    collimator_back_vertex_z_mm: float
    collimator_front_vertex_z_mm: float
    collimator_front_principal_z_mm: float
    phone_z_mm: float
    tube_radius_mm: float
    trial_back_vertex_z_mm: float | None = None
    trial_front_vertex_z_mm: float | None = None


def _surface_z_extent_mm(lens: TrialLens, aperture_mm: float, z_back_vertex: float) -> tuple[float, float]:
    """(nearest to the eye, farthest) z of a lens's surfaces over its clear aperture."""
    front, back = lens_surface_curvatures_per_mm(lens)
    angles = np.linspace(0.0, 2.0 * np.pi, 72, endpoint=False)
    radii = 0.5 * aperture_mm * np.linspace(0.0, 1.0, 9)
    xy = np.stack([np.outer(radii, np.cos(angles)), np.outer(radii, np.sin(angles))], axis=-1).reshape(-1, 2)
    z_front = z_back_vertex + lens.center_thickness_mm - sag_mm(front, xy)
    z_back = z_back_vertex - sag_mm(back, xy)
    return float(min(z_back.min(), z_front.min())), float(max(z_back.max(), z_front.max()))


@dataclass(frozen=True)
class AtvConfig:
    """Tube, eye and an optional trial lens in the slot (module doc)."""

    tube: AtvTube = field(default_factory=AtvTube)
    eye: AtvEye = field(default_factory=AtvEye)
    trial_lens: TrialLens | None = None
    trial_lens_distance_mm: float = ATV_TRIAL_LENS_DISTANCE_MM
    trial_clear_aperture_mm: float = 22.0
    fresnel_loss: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.tube, AtvTube) or not isinstance(self.eye, AtvEye):
            raise VissimInputError("AtvConfig needs an AtvTube and an AtvEye")
        object.__setattr__(self, "trial_lens_distance_mm", _number(
            self.trial_lens_distance_mm, "trial lens distance", "mm", lo=0.0, lo_open=True,
            hi=VERTEX_DISTANCE_RANGE_MM[1]))
        object.__setattr__(self, "trial_clear_aperture_mm", _number(
            self.trial_clear_aperture_mm, "trial lens clear aperture", "mm", lo=0.0, lo_open=True,
            hi=BENCH_LENGTH_RANGE_MM[1]))
        object.__setattr__(self, "fresnel_loss", bool(self.fresnel_loss))
        lens = self.trial_lens
        if lens is None:
            return
        if not isinstance(lens, TrialLens):
            raise VissimInputError(f"trial_lens must be a TrialLens or None, got {type(lens).__name__}")
        if lens.is_thin or lens.refractive_index is None:
            raise VissimInputError(
                f"the ATV bench meshes its trial lens: {lens.marked_power} needs a refractive index and a centre "
                "thickness in mm (use atv_trial_lens)")
        thinnest, _ = rim_thickness_mm(lens, self.trial_clear_aperture_mm)
        if thinnest <= 0.0:
            raise VissimInputError(f"trial lens {lens.marked_power} has no edge at a "
                                   f"{self.trial_clear_aperture_mm:g} mm aperture ({thinnest:.3g} mm)")
        near, far = _surface_z_extent_mm(lens, self.trial_clear_aperture_mm, self.trial_lens_distance_mm)
        coll_near, _ = _surface_z_extent_mm(self.tube.collimator_lens(), self.tube.lens_clear_aperture_mm,
                                            self.tube.eye_relief_mm)
        if near < MIN_AIR_GAP_MM or far > coll_near - MIN_AIR_GAP_MM:
            raise VissimInputError(
                f"trial lens {lens.marked_power} at {self.trial_lens_distance_mm:g} mm spans z = "
                f"{near:.2f}-{far:.2f} mm "
                f"but must fit between {MIN_AIR_GAP_MM:g} mm and the collimator at {coll_near:.2f} mm "
                f"(eye relief {self.tube.eye_relief_mm:g} mm)")

    def layout(self) -> AtvLayout:
        return atv_layout(self)


def atv_layout(config: AtvConfig) -> AtvLayout:
    """Where everything sits along the axis (module doc)."""
    tube = config.tube
    back = tube.eye_relief_mm
    front = back + tube.lens_center_thickness_mm
    principal = front - (tube.focal_length_mm - tube.front_focal_distance_mm())
    apertures = [tube.lens_clear_aperture_mm]
    trial_back = trial_front = None
    if config.trial_lens is not None:
        trial_back = config.trial_lens_distance_mm
        trial_front = trial_back + config.trial_lens.center_thickness_mm
        apertures.append(config.trial_clear_aperture_mm)
    return AtvLayout(float(back), float(front), float(principal), float(principal + tube.tube_length_mm),
                     0.5 * max(apertures) + TUBE_CLEARANCE_MM, trial_back, trial_front)
