"""Trial lenses in front of a camera or an eye: the power they add and how much they magnify.

The thesis (Krueger 2015, section 4.4.1, Eq. 4.10-4.13, Table 4.2) puts trial lenses 10 mm in
front of a DSLR and converts the lens power P into the power added at the camera by
P / (1 - dP).  That formula holds only for an object at infinity (ERRATA item 4); the chart
stood at 914.4 mm.  It also ignores spectacle magnification (ERRATA item 5).  This module does
both properly, by generalized (astigmatic) paraxial ray transfer:

* a ray is the 4-vector ``(x, y, n u_x, n u_y)``: heights in metres, reduced angles in radians,
  in the TABO frame used by `vissim.optics.rx.prescription.SpheroCylinder.power_matrix`
  (x to the examiner's right, y up), z from the object towards the camera;
* a refracting surface with 2x2 dioptric power matrix F is ``[[I, 0], [-F, I]]``, a gap of
  thickness t in a medium of index n is ``[[I, (t/n) I], [0, I]]`` (Keating 1981; Harris 1997),
  so cylinders at any axes combine correctly, in contact or apart;
* a wavefront of 2x2 vergence matrix L at a plane carries the rays ``u = -L x``.  Through a
  system ``S = [[A, B], [C, D]]`` it leaves with ``L' = (D L - C)(A - B L)^-1``;
* a chief ray through the centre of the camera's entrance pupil (at the camera principal plane)
  from an object point at distance s has, with the lenses, the angle ``s B'^-T`` times the
  angle it would have without them, where ``B'`` is the B block from the object plane to the
  pupil.  That 2x2 *magnification matrix* tends to ``A^-T`` for an object at infinity: for a
  thin lens ``1 / (1 - dP)``, and for a thick lens the shape factor ``1 / (1 - (t/n) F1)``
  appears by itself.

Also here: the pupil-size rules of thesis Table 4.1 (ERRATA item 3) and the thesis's Table 4.2
formula, both kept for explicit comparison only.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import finite_number as _number
from vissim.checks import BENCH_LENGTH_RANGE_MM, LENS_GAP_RANGE_MM, REFRACTIVE_INDEX_RANGE, number_within
from vissim.checks import vertex_distance_mm as check_vertex_mm
from vissim.errors import VissimInputError
from vissim.optics.rx.conventions import (CORNEA_TO_ENTRANCE_PUPIL_MM, CROWN_GLASS_INDEX,  # noqa: F401 (re-exported)
                                          EYE_VERTEX_DISTANCE_MM, SPECTACLE_VERTEX_DISTANCE_MM)
from vissim.optics.rx.prescription import LensPower, Prescription
from vissim.thesis import THESIS_EYE_FOCAL_LENGTH_MM, THESIS_VERTEX_DISTANCE_MM
from vissim.units import diopters_to_per_mm, mm_to_m

__all__ = ["CROWN_GLASS_INDEX", "lens_surface_curvatures_per_mm", "vergence_after_distance", "MAX_LENSES_IN_HOLDER", "SurfaceRadii", "TrialLens", "TrialLensSetup",
           "TrialLensEffect", "trial_lens_effect", "refraction_matrix", "transfer_matrix",
           "entrance_pupil_diameter_mm", "thesis_eye_pupil_diameter_mm", "thesis_table_4_2_power",
           "thesis_table_4_2_lens_power", "Matrix2", "matrix2_tuple", "tabo_meridian_deg", "principal_pairs"]

log = logging.getLogger(__name__)

#: The thesis's lens holder takes up to three trial lenses (section 4.4).
MAX_LENSES_IN_HOLDER = 3

Matrix2 = tuple[tuple[float, float], tuple[float, float]]
_I2 = np.eye(2)
_SINGULAR_TOL = 1e-12


def matrix2_tuple(matrix: np.ndarray) -> Matrix2:
    """A 2 x 2 array as nested tuples of floats (-0.0 made 0.0)."""
    return tuple(tuple(float(v) + 0.0 for v in row) for row in matrix)  # type: ignore[return-value]


def tabo_meridian_deg(vector: np.ndarray) -> float:
    """TABO meridian (0, 180] of the direction ``(x, y)``; the horizontal is 180."""
    angle = round(math.degrees(math.atan2(float(vector[1]), float(vector[0]))) % 180.0, 9)
    return 180.0 if angle in (0.0, 180.0) else angle


def principal_pairs(symmetric: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]]:
    """Eigen-pairs ``((value, meridian_deg), ...)`` of a symmetric 2x2 matrix, larger first."""
    values, vectors = np.linalg.eigh(symmetric)
    if abs(values[1] - values[0]) <= 1e-12 * max(1.0, abs(values[1])):
        mean = float(values.mean())
        return (mean, 180.0), (mean, 90.0)
    return ((float(values[1]), tabo_meridian_deg(vectors[:, 1])),
            (float(values[0]), tabo_meridian_deg(vectors[:, 0])))


def refraction_matrix(power_matrix_diopters) -> np.ndarray:
    """4x4 ray transfer of a thin refracting element of 2x2 power matrix F: ``[[I, 0], [-F, I]]``."""
    matrix = np.eye(4)
    matrix[2:, :2] = -np.asarray(power_matrix_diopters, dtype=float)
    return matrix


def transfer_matrix(reduced_distance_m: float) -> np.ndarray:
    """4x4 ray transfer across a gap of reduced thickness t/n (metres): ``[[I, (t/n) I], [0, I]]``."""
    matrix = np.eye(4)
    matrix[:2, 2:] = reduced_distance_m * _I2
    return matrix


@dataclass(frozen=True)
class SurfaceRadii:
    """Principal radii of curvature of one lens surface.

    ``radii_mm[i]`` is the radius of the section along TABO meridian ``meridians_deg[i]``.
    Cartesian sign: positive when the centre of curvature lies on the camera side (+z);
    ``math.inf`` for a plano section.
    """

    radii_mm: tuple[float, float]
    meridians_deg: tuple[float, float]


@dataclass(frozen=True)
class TrialLens:
    """One trial lens, as marked on its rim.

    Parameters
    ----------
    sphere_diopters : float
        The marked sphere power, D (plus lens > 0).  For a thick lens the marked power is the
        **back vertex power**, the power trial-case lenses are conventionally marked with (ISO
        9801, trial case lenses).  The thesis does not say how its lenses were marked, so this
        is an assumption; for a thin lens the distinction vanishes.
    cylinder_diopters : float
        The marked cylinder power, D (back vertex, like the sphere).
    axis_deg : float
        The cylinder's TABO axis, degrees.
    refractive_index : float or None
        None for a thin lens (the default); otherwise the glass index, > 1
        (`CROWN_GLASS_INDEX` = 1.523 for crown).
    center_thickness_mm : float
        Centre thickness, >= 0; a thick lens needs ``refractive_index``.
    back_surface_diopters : float
        Power of the (spherical) back surface, the one facing the camera; 0 (plano) by
        default.  The curved, possibly toric, surface faces the object.  A negative value makes
        a meniscus.  The front-surface power follows from the marked back vertex power.
    """

    sphere_diopters: float
    cylinder_diopters: float = 0.0
    axis_deg: float = 180.0
    refractive_index: float | None = None
    center_thickness_mm: float = 0.0
    back_surface_diopters: float = 0.0

    def __post_init__(self) -> None:
        marked = LensPower(self.sphere_diopters, self.cylinder_diopters, self.axis_deg)
        for name in ("sphere_diopters", "cylinder_diopters", "axis_deg"):
            object.__setattr__(self, name, getattr(marked, name))
        if self.refractive_index is not None:
            index = number_within(self.refractive_index, "refractive index", "(dimensionless)", REFRACTIVE_INDEX_RANGE,
                                  " (above air to beyond any optical glass)")
            object.__setattr__(self, "refractive_index", index)
        thickness = number_within(self.center_thickness_mm, "centre thickness", "mm", BENCH_LENGTH_RANGE_MM)
        if thickness > 0.0 and self.refractive_index is None:
            raise VissimInputError(
                f"a {thickness:g} mm thick lens needs a refractive index (crown: {CROWN_GLASS_INDEX})"
            )
        object.__setattr__(self, "center_thickness_mm", thickness + 0.0)
        back = _number(self.back_surface_diopters, "back-surface power", "dioptres")
        object.__setattr__(self, "back_surface_diopters", back + 0.0)
        self._front_surface()  # raises when the marked power cannot be made at this thickness

    # -- powers -------------------------------------------------------------------------
    @property
    def marked_power(self) -> LensPower:
        """The marked power (back vertex power for a thick lens)."""
        return LensPower(self.sphere_diopters, self.cylinder_diopters, self.axis_deg)

    @property
    def is_thin(self) -> bool:
        return self.center_thickness_mm == 0.0

    @property
    def reduced_thickness_m(self) -> float:
        """t/n in metres (0 for a thin lens)."""
        if self.is_thin:
            return 0.0
        return mm_to_m(self.center_thickness_mm) / self.refractive_index

    def _front_surface(self) -> np.ndarray:
        """F1 from F_bv = F1 (I - tau F1)^-1 + F2 I, i.e. F1 = G (I + tau G)^-1, G = F_bv - F2 I."""
        tau = self.reduced_thickness_m
        excess = np.asarray(self.marked_power.power_matrix()) - self.back_surface_diopters * _I2
        denominator = _I2 + tau * excess
        if np.linalg.eigvalsh(denominator).min() <= _SINGULAR_TOL:
            raise VissimInputError(
                f"back vertex power {self.marked_power} cannot be made with a "
                f"{self.center_thickness_mm:g} mm thick lens of index {self.refractive_index:g}"
            )
        front = excess @ np.linalg.inv(denominator)
        return 0.5 * (front + front.T)

    def front_surface_power_matrix(self) -> Matrix2:
        """2x2 power matrix of the front (object-side) surface, dioptres, TABO x/y frame."""
        return matrix2_tuple(self._front_surface())

    def ray_transfer_matrix(self) -> np.ndarray:
        """4x4 ray transfer from the front vertex to the back vertex (metres, radians, dioptres)."""
        return (
            refraction_matrix(self.back_surface_diopters * _I2)
            @ transfer_matrix(self.reduced_thickness_m)
            @ refraction_matrix(self._front_surface())
        )

    def surface_radii_mm(self) -> tuple[SurfaceRadii, SurfaceRadii]:
        """(front, back) principal radii by the lensmaker's relation, per principal meridian.

        Front surface ``F1 = (n - 1) / R1``, back surface ``F2 = (1 - n) / R2`` (Cartesian
        signs: a plano-convex plus lens has R1 > 0 and R2 = inf).
        """
        if self.refractive_index is None:
            raise VissimInputError(
                "a thin trial lens (refractive_index None) has no surface radii; give an index "
                f"(crown: {CROWN_GLASS_INDEX})"
            )
        n_minus_1 = self.refractive_index - 1.0

        def radius_mm(power_diopters: float, sign: float) -> float:
            if abs(power_diopters) < 1e-12:
                return math.inf
            return 1000.0 * sign * n_minus_1 / power_diopters

        (f_a, m_a), (f_b, m_b) = principal_pairs(self._front_surface())
        front = SurfaceRadii((radius_mm(f_a, 1.0), radius_mm(f_b, 1.0)), (m_a, m_b))
        back_r = radius_mm(self.back_surface_diopters, -1.0)
        return front, SurfaceRadii((back_r, back_r), (180.0, 90.0))



@dataclass(frozen=True)
class TrialLensSetup:
    """Trial lenses in a holder in front of a camera (or an eye).

    Parameters
    ----------
    lenses : tuple of TrialLens
        Up to `MAX_LENSES_IN_HOLDER`, ordered from the object to the camera.
    vertex_distance_mm : float
        From the back surface of the last lens to the camera's principal plane, which is also
        where its entrance pupil is.  The thesis used 10 mm.
    object_distance_m : float
        From the camera principal plane to the object; ``math.inf`` by default.  Must lie
        beyond the front surface of the first lens.
    lens_gap_mm : float
        Air between consecutive lenses (back surface to front surface); 0 = in contact.
    """

    lenses: tuple[TrialLens, ...] = ()
    vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM
    object_distance_m: float = math.inf
    lens_gap_mm: float = 0.0

    def __post_init__(self) -> None:
        try:
            lenses = (self.lenses,) if isinstance(self.lenses, TrialLens) else tuple(self.lenses)
        except TypeError:
            raise VissimInputError(f"lenses must be a tuple of TrialLens, got {self.lenses!r}") from None
        for lens in lenses:
            if not isinstance(lens, TrialLens):
                raise VissimInputError(f"lenses must be TrialLens objects, got {lens!r}")
        if len(lenses) > MAX_LENSES_IN_HOLDER:
            raise VissimInputError(
                f"the holder takes at most {MAX_LENSES_IN_HOLDER} trial lenses, got {len(lenses)}"
            )
        object.__setattr__(self, "lenses", lenses)
        object.__setattr__(self, "vertex_distance_mm", check_vertex_mm(self.vertex_distance_mm))
        gap = _number(self.lens_gap_mm, "lens gap", "mm")
        low, high = LENS_GAP_RANGE_MM
        if not low <= gap <= high:
            raise VissimInputError(f"lens gap must be within {low:g}-{high:g} mm, got {gap:g} mm")
        object.__setattr__(self, "lens_gap_mm", gap + 0.0)
        distance = _number(self.object_distance_m, "object distance", "m", allow_inf=True)
        if distance <= mm_to_m(self.span_mm):
            raise VissimInputError(
                f"object distance {distance:g} m must exceed {mm_to_m(self.span_mm):g} m, the "
                "distance from the camera principal plane to the front of the first trial lens"
            )
        object.__setattr__(self, "object_distance_m", distance)

    @property
    def span_mm(self) -> float:
        """From the front surface of the first lens to the camera principal plane (0 with no lens)."""
        if not self.lenses:
            return 0.0
        thickness = sum(lens.center_thickness_mm for lens in self.lenses)
        return self.vertex_distance_mm + thickness + self.lens_gap_mm * (len(self.lenses) - 1)

    def ray_transfer_matrix(self) -> np.ndarray:
        """4x4 ray transfer from the first lens's front surface to the camera principal plane."""
        system = np.eye(4)
        for position, lens in enumerate(self.lenses):
            if position:
                system = transfer_matrix(mm_to_m(self.lens_gap_mm)) @ system
            system = lens.ray_transfer_matrix() @ system
        if self.lenses:
            system = transfer_matrix(mm_to_m(self.vertex_distance_mm)) @ system
        return system


@dataclass(frozen=True)
class TrialLensEffect:
    """What the trial lenses do at the camera, for the object distance of ``setup``.

    Attributes
    ----------
    added_power : LensPower
        Vergence at the camera principal plane with the lenses minus without (minus-cylinder
        form); positive for a plus lens.
    added_power_matrix : 2x2 tuple
        The same as a dioptric power matrix (TABO x/y frame).
    camera_prescription : Prescription
        The lens that would correct the camera so made ametropic (``-added_power``).
    magnification_principal : ((mag, meridian_deg), (mag, meridian_deg))
        Spectacle magnification in each principal meridian (TABO), larger first: the chief-ray
        angle at the camera's pupil centre with the lenses over that without.  Taken from the
        symmetric part of ``magnification_matrix``; its antisymmetric part (a tiny image
        rotation with obliquely crossed cylinders set apart) is left out.
    magnification : float
        Geometric mean of the two principal magnifications.
    magnification_matrix : 2x2 tuple
        Maps a chief-ray angle (x, y) without lenses onto the angle with them.
    """

    setup: TrialLensSetup
    added_power: LensPower
    added_power_matrix: Matrix2
    camera_prescription: Prescription
    magnification_principal: tuple[tuple[float, float], tuple[float, float]]
    magnification: float
    magnification_matrix: Matrix2

    def to_json_dict(self) -> dict:
        """Plain JSON-ready values; ``object_distance_m`` is None for an object at infinity."""
        added = self.added_power.minus_cylinder()
        meridians = (added.axis_deg, (added.axis_deg + 90.0) % 180.0 or 180.0)
        distance = self.setup.object_distance_m
        return {
            "effective_sphere_diopters": added.sphere_diopters,
            "effective_cylinder_diopters": added.cylinder_diopters,
            "effective_axis_deg": added.axis_deg,
            "added_power": str(added),
            "added_power_meridians": [
                {"meridian_deg": m, "power_diopters": added.meridian_power(m)} for m in meridians
            ],
            "camera_prescription": str(self.camera_prescription.minus_cylinder()),
            "magnification": self.magnification,
            "magnification_principal": [
                {"magnification": mag, "meridian_deg": meridian}
                for mag, meridian in self.magnification_principal
            ],
            "magnification_matrix": [list(row) for row in self.magnification_matrix],
            "object_distance_m": None if math.isinf(distance) else distance,
            "vertex_distance_mm": self.setup.vertex_distance_mm,
        }


def trial_lens_effect(setup: TrialLensSetup) -> TrialLensEffect:
    """Added power and spectacle magnification of ``setup`` by 4x4 ray transfer (see module doc)."""
    system = setup.ray_transfer_matrix()
    a, b, c, d = system[:2, :2], system[:2, 2:], system[2:, :2], system[2:, 2:]
    distance_m = setup.object_distance_m
    span_m = mm_to_m(setup.span_mm)
    if math.isinf(distance_m):
        inv_distance, inv_front_distance, front_over_distance = 0.0, 0.0, 1.0
    else:
        inv_distance = 1.0 / distance_m
        inv_front_distance = 1.0 / (distance_m - span_m)
        front_over_distance = (distance_m - span_m) / distance_m

    # Vergence of the object's wavefront at the first lens, carried to the camera plane.
    incoming = -inv_front_distance * _I2
    denominator = a - b @ incoming
    if abs(np.linalg.det(denominator)) < _SINGULAR_TOL:
        raise VissimInputError(
            f"the trial lenses focus the object on the camera principal plane (vertex distance "
            f"{setup.vertex_distance_mm:g} mm); the added power would be infinite"
        )
    outgoing = (d @ incoming - c) @ np.linalg.inv(denominator)
    added = 0.5 * (outgoing + outgoing.T) + inv_distance * _I2  # minus the bare vergence -1/s

    # Chief ray to the pupil centre: angle with lenses = s B'^-T (angle without), B' = A s1 + B.
    object_b = front_over_distance * a + inv_distance * b
    if abs(np.linalg.det(object_b)) < _SINGULAR_TOL:
        raise VissimInputError(
            "the trial lenses image the object onto the camera's pupil; magnification undefined"
        )
    magnification_matrix = np.linalg.inv(object_b).T
    principal = principal_pairs(0.5 * (magnification_matrix + magnification_matrix.T))
    (mag_a, _), (mag_b, _) = principal
    if mag_a * mag_b <= 0.0:
        raise VissimInputError(
            f"the trial lenses invert the image (magnifications {mag_a:.3g}, {mag_b:.3g}); "
            "their power is too strong for this vertex distance"
        )
    skew = abs(magnification_matrix[0, 1] - magnification_matrix[1, 0]) / 2.0
    if skew > 1e-9:
        log.debug("magnification matrix has an antisymmetric part %.3g (image rotation)", skew)

    added_power = LensPower.from_power_matrix(added)
    log.debug("trial lenses %s: added %s, magnification %s", setup, added_power, principal)
    return TrialLensEffect(setup=setup, added_power=added_power, added_power_matrix=matrix2_tuple(added),
                           camera_prescription=added_power.prescription_of_camera(),
                           magnification_principal=principal,
                           magnification=math.copysign(math.sqrt(mag_a * mag_b), mag_a),
                           magnification_matrix=matrix2_tuple(magnification_matrix))


# -- the thesis's rules, kept for explicit comparison --------------------------------------


def entrance_pupil_diameter_mm(focal_length_mm: float, f_number: float) -> float:
    """Entrance-pupil diameter f / N in mm (Eq. 4.9); 18 mm at f/5 gives 3.6 mm."""
    focal = _number(focal_length_mm, "focal length", "mm")
    number = _number(f_number, "f-number", "(dimensionless)")
    if focal <= 0.0:
        raise VissimInputError(f"focal length must be > 0 mm, got {focal:g} mm")
    if number <= 0.0:
        raise VissimInputError(f"f-number must be > 0, got {number:g}")
    return focal / number


def thesis_eye_pupil_diameter_mm(
    f_number: float, eye_focal_length_mm: float = THESIS_EYE_FOCAL_LENGTH_MM
) -> float:
    """The thesis's f-number-matched eye pupil (Table 4.1): 13.5 mm / N.

    f/4 -> 3.375 (printed 3.4), f/4.5 -> 3.0, f/5 -> 2.7 mm.  ERRATA item 3: this is the wrong
    invariant for images sampled in angle -- the angular blur scales with the entrance-pupil
    diameter itself (3.6 mm for the thesis's camera at f/5, see
    `entrance_pupil_diameter_mm`), so this pupil shrinks the blur by 25 %.  Offered as a
    named option for reproducing the thesis, never as a default.
    """
    return entrance_pupil_diameter_mm(eye_focal_length_mm, f_number)


def thesis_table_4_2_power(lens_diopters: float, vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM) -> float:
    """The thesis's Table 4.2 value P / (1 - dP), dioptres: right only for an object at infinity.

    ERRATA item 4: with the chart at a finite distance use `trial_lens_effect`.
    """
    power = _number(lens_diopters, "lens power", "dioptres")
    vertex_m = mm_to_m(check_vertex_mm(vertex_distance_mm))
    if abs(1.0 - vertex_m * power) < _SINGULAR_TOL:
        raise VissimInputError(
            f"a {power:g} D lens at {vertex_distance_mm:g} mm focuses on the camera principal plane"
        )
    return power / (1.0 - vertex_m * power)


def thesis_table_4_2_lens_power(lenses, vertex_distance_mm: float) -> LensPower:
    """Table 4.2's P / (1 - dP) per principal meridian of ``lenses``' summed marked power (0 D for none)."""
    if not lenses:
        return LensPower(0.0)
    total = sum((np.asarray(lens.marked_power.power_matrix()) for lens in lenses), np.zeros((2, 2)))
    summed = LensPower.from_power_matrix(total)
    axis = summed.axis_deg
    p_axis = thesis_table_4_2_power(summed.meridian_power(axis), vertex_distance_mm)
    p_perp = thesis_table_4_2_power(summed.meridian_power(axis + 90.0), vertex_distance_mm)
    return LensPower(p_axis, p_perp - p_axis, axis)


def lens_surface_curvatures_per_mm(lens: TrialLens) -> tuple[np.ndarray, np.ndarray]:
    """(front, back) 2x2 curvature matrices K in 1/mm of a thick lens's surfaces: the front carries its marked
    power over (n - 1), the back its back-surface power, negated (sag z = x^T K x / (1 + sqrt(1 - x^T K^2 x))
    along the light; `vissim.bench.lenses.mesh`, `vissim.optics.eyes.spectacles`)."""
    if lens.refractive_index is None:
        raise VissimInputError(
            f"trial lens {lens.marked_power} is thin (no refractive index); a mesh needs an index and a "
            "centre thickness (see realistic_center_thickness_mm)"
        )
    n_minus_1 = lens.refractive_index - 1.0
    front = diopters_to_per_mm(np.asarray(lens.front_surface_power_matrix(), dtype=float)) / n_minus_1
    back = -diopters_to_per_mm(lens.back_surface_diopters * np.eye(2)) / n_minus_1
    return front, back


def vergence_after_distance(vergence_matrix_diopters, distance_m: float) -> np.ndarray:
    """A vergence (2 x 2, D) carried ``distance_m`` along the light through air: V' = V (I - d V)^-1,
    symmetrised (d < 0 carries it back upstream). Refuses a principal vergence whose focus lies
    within the gap (I - d V singular or of the wrong sign)."""
    vergence = np.asarray(vergence_matrix_diopters, dtype=float)
    gap = np.eye(2) - distance_m * vergence
    if np.linalg.eigvalsh(0.5 * (gap + gap.T)).min() <= _SINGULAR_TOL:
        raise VissimInputError(f"a vergence of {np.linalg.eigvalsh(vergence).round(4).tolist()} D comes to a focus "
                               f"within {1000.0 * abs(distance_m):g} mm, before the next plane")
    moved = vergence @ np.linalg.inv(gap)
    return 0.5 * (moved + moved.T)
