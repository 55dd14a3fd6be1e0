"""The schematic eye that has a given prescription: axial ametropia and a toric cornea, solved in closed form.

**The prescription's plane.** A prescription is written as clinicians write it: the correcting
thin spectacle lens (a `Prescription`, a myope's sphere < 0) ``vertex_distance_mm`` in front of
the corneal front vertex (12 mm by default, `SPECTACLE_VERTEX_DISTANCE_MM`). It is converted once,
by `far_point_vergence_matrix`, to the eye's refraction at the corneal vertex: the far point's
vergence matrix there, ``K = P (I − d P)⁻¹`` (the lens P sends light from infinity to its focal
point, the far point; the gap d carries the vergence matrix L to L (I − d L)⁻¹). A refraction here,
at either plane, is the correcting thin lens at that plane: negative for a myope.

**Method: generalized (astigmatic) paraxial optics** (Keating 1981; Harris 1997), as
`vissim.optics.rx.trial_lens` uses it. Rays are 4-vectors (x, y, n·u_x, n·u_y) in metres and
radians in the TABO frame (x the examiner's right, y up, as the examiner faces the eye); a
surface of 2 × 2 dioptric power matrix F is [[I, 0], [−F, I]] and a gap t in index n is
[[I, (t/n) I], [0, I]]. Only the cornea's front may be toric here; every other surface is one of
revolution, so the eye behind that front is the scalar matrix [[a, b], [c, d]] of
`vissim.optics.eyes.paraxial` times I, and the whole eye is [[aI − bF, bI], [cI − dF, dI]]. The
vergence in air at the cornea that the eye focuses on its retina is then

    K = B⁻¹ A = (a/b) I − F,

and with the vitreous (reduced length τ = L/n) the only change, a = a₀ + τ c₀, b = b₀ + τ d₀.

**Solution (closed form, no iteration).** Given the target K (2 × 2, from the prescription):

* **spherical equivalent by axial ametropia**: the cornea front keeps its mean power F₀ (the
  model's), so a/b = tr(K)/2 + F₀ =: G, and τ = (G b₀ − a₀)/(c₀ − G d₀): only the vitreous (the
  last surface's distance to the retina) changes; the retina keeps its radius;
* **cylinder by a toric cornea front**: F = G I − K; its principal sections along the
  prescription's axis (x') and 90° from it (y') have radii R = (n_cornea − 1)/F_meridian, both
  with the model's conic Q (a biconic with Qx = Qy). A spherical prescription leaves the cornea
  exactly as the model has it.

The solve is exact at one wavelength (the model's reference wavelength unless given); at others
the eye's dispersion acts on the solved geometry.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import vertex_distance_mm as checked_vertex_distance_mm
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import GrinMedium
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.paraxial import matrix_to_surface
from vissim.optics.rx.prescription import Prescription, as_prescription
from vissim.optics.rx.trial_lens import (SPECTACLE_VERTEX_DISTANCE_MM, Matrix2, matrix2_tuple, refraction_matrix,
                                      vergence_after_distance)
from vissim.units import mm_to_m

__all__ = ["CORNEA", "SPECTACLE", "ParaxialRefraction", "far_point_vergence_matrix", "cornea_front_power_matrix",
           "eye_ray_matrix", "corneal_refraction", "refraction_from_matrix", "paraxial_ametropic_eye", "solved_eye",
           "solve_inputs", "with_source"]

#: The planes a refraction is given at: the corneal front vertex, or the spectacle plane in front of it.
CORNEA = "corneal vertex"
SPECTACLE = "spectacle plane"
_I2 = np.eye(2)
_SINGULAR_TOL = 1e-12


@dataclass(frozen=True)
class ParaxialRefraction:
    """A refraction: the correcting thin lens at ``plane``, ``plane_distance_mm`` in front of the
    corneal front vertex (0 at the cornea), at ``wavelength_nm``.

    ``prescription`` is its sphere, cylinder and TABO axis in minus-cylinder form;
    ``power_matrix_diopters`` its dioptric power matrix (TABO x/y frame). M, J0 and J45 follow
    Thibos, Wheeler & Horner (1997) as `Prescription.power_vector` does.
    """

    prescription: Prescription
    power_matrix_diopters: Matrix2
    plane: str
    plane_distance_mm: float
    wavelength_nm: float

    @property
    def sphere_diopters(self) -> float:
        return self.prescription.sphere_diopters

    @property
    def cylinder_diopters(self) -> float:
        return self.prescription.cylinder_diopters

    @property
    def axis_deg(self) -> float:
        return self.prescription.axis_deg

    @property
    def power_vector_diopters(self) -> tuple[float, float, float]:
        """(M, J0, J45), dioptres."""
        return self.prescription.power_vector()

    def to_json_dict(self) -> dict:
        """Sphere, cylinder, axis, M, J0, J45 and the plane, as plain numbers."""
        m, j0, j45 = self.power_vector_diopters
        return {"sphere_diopters": self.sphere_diopters, "cylinder_diopters": self.cylinder_diopters,
                "axis_deg": self.axis_deg, "M": m, "J0": j0, "J45": j45, "plane": self.plane,
                "plane_distance_mm": self.plane_distance_mm, "wavelength_nm": self.wavelength_nm}


def refraction_from_matrix(matrix_diopters, plane: str, plane_distance_mm: float,
                           wavelength_nm: float) -> ParaxialRefraction:
    """An `ParaxialRefraction` from a 2 × 2 power matrix (its symmetric part; D)."""
    matrix = np.asarray(matrix_diopters, dtype=float)
    symmetric = 0.5 * (matrix + matrix.T)
    rx = Prescription.from_power_matrix(symmetric).minus_cylinder()
    return ParaxialRefraction(rx, matrix2_tuple(symmetric), plane, float(plane_distance_mm), float(wavelength_nm))


def far_point_vergence_matrix(rx: Prescription, vertex_distance_mm: float = SPECTACLE_VERTEX_DISTANCE_MM) -> np.ndarray:
    """The refraction at the corneal vertex, 2 × 2 D, of the spectacle prescription ``rx`` worn
    ``vertex_distance_mm`` in front of it: K = P (I − d P)⁻¹ (module doc). Refuses a principal
    power P ≥ 1/d, whose far point would lie between the lens and the eye (or at the lens)."""
    rx = as_prescription(rx)
    d_m = mm_to_m(checked_vertex_distance_mm(vertex_distance_mm))
    try:
        return vergence_after_distance(rx.power_matrix(), d_m)
    except VissimInputError:
        raise VissimInputError(f"prescription {rx} at {vertex_distance_mm:g} mm puts the far point between the "
                               f"spectacle plane and the eye (a principal power >= {1.0 / d_m:.4g} dioptres)") from None


def _curvature_matrix_per_mm(radius_x_mm: float, radius_y_mm: float, axis_deg: float) -> np.ndarray:
    """R diag(1/Rx, 1/Ry) Rᵀ with R the rotation by ``axis_deg`` (x' along the TABO meridian)."""
    cos_a, sin_a = math.cos(math.radians(axis_deg)), math.sin(math.radians(axis_deg))
    rotation = np.array([[cos_a, -sin_a], [sin_a, cos_a]])
    return rotation @ np.diag([1.0 / radius_x_mm, 1.0 / radius_y_mm]) @ rotation.T


def _front_indices(eye: SchematicEye, wavelength_nm: float) -> tuple[float, float]:
    medium = eye.surfaces[0].medium_after
    if isinstance(medium, GrinMedium):
        raise VissimInputError(f"the {eye.name} eye's cornea is a GRIN medium; its front must face a homogeneous one")
    return eye.object_medium.index(wavelength_nm), medium.index(wavelength_nm)


def cornea_front_power_matrix(eye: SchematicEye, wavelength_nm: float) -> np.ndarray:
    """The 2 × 2 power matrix of the cornea's front, D: (n_cornea − n_air) × its curvature matrix."""
    front = eye.surfaces[0]
    n_air, n_cornea = _front_indices(eye, checked_wavelength_nm(wavelength_nm))
    radius_y = front.radius_mm if front.radius_y_mm is None else front.radius_y_mm
    return 1000.0 * (n_cornea - n_air) * _curvature_matrix_per_mm(front.radius_mm, radius_y, front.axis_deg)


def _behind_front(eye: SchematicEye, vitreous_mm: float | None = None) -> SchematicEye:
    """``eye`` with a plane cornea front (no power) and, if given, another vitreous length."""
    surfaces = list(eye.surfaces)
    for i, surface in enumerate(surfaces[1:], start=1):
        if surface.is_toric:
            raise VissimInputError(f"the {eye.name} eye's {surface.name} is toric; only the cornea's front may be")
    surfaces[0] = dataclasses.replace(surfaces[0], radius_mm=math.inf, radius_y_mm=None)
    if vitreous_mm is not None:
        surfaces[-2] = dataclasses.replace(surfaces[-2], thickness_after_mm=vitreous_mm)
    return dataclasses.replace(eye, surfaces=tuple(surfaces))


def _scalar_metres(matrix_mm: np.ndarray) -> np.ndarray:
    """A (mm, 1/mm) ray matrix in (m, D)."""
    (a, b), (c, d) = matrix_mm
    return np.array([[a, b / 1000.0], [c * 1000.0, d]])


def eye_ray_matrix(eye: SchematicEye, wavelength_nm: float) -> np.ndarray:
    """The 4 × 4 ray matrix (m, D) from air at the corneal front vertex to the retina's vertex plane."""
    wavelength = checked_wavelength_nm(wavelength_nm)
    rest = _scalar_metres(matrix_to_surface(_behind_front(eye), len(eye.surfaces) - 1, wavelength))
    return np.kron(rest, _I2) @ refraction_matrix(cornea_front_power_matrix(eye, wavelength))


def corneal_refraction(eye: SchematicEye, wavelength_nm: float | None = None) -> ParaxialRefraction:
    """The eye's own refraction at the corneal vertex: K = B⁻¹ A of `eye_ray_matrix` (module doc),
    at ``wavelength_nm`` (default: the model's reference wavelength)."""
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else checked_wavelength_nm(wavelength_nm)
    system = eye_ray_matrix(eye, wavelength)
    k = np.linalg.solve(system[:2, 2:], system[:2, :2])
    return refraction_from_matrix(k, CORNEA, 0.0, wavelength)


def _solve_vitreous_mm(eye: SchematicEye, mean_k_per_mm: float, front_power_per_mm: float, wavelength_nm: float,
                       rx_text: str) -> float:
    (a0, b0), (c0, d0) = matrix_to_surface(_behind_front(eye, 0.0), len(eye.surfaces) - 1, wavelength_nm)
    g = mean_k_per_mm + front_power_per_mm
    denominator = c0 - g * d0
    tau = (g * b0 - a0) / denominator if abs(denominator) > _SINGULAR_TOL else -1.0
    if tau <= 0.0:
        raise VissimInputError(f"prescription {rx_text} needs a retina in front of the {eye.name} eye's lens "
                               f"(no vitreous length > 0 mm gives it)")
    return tau * eye.surfaces[-2].medium_after.index(wavelength_nm)


def _check_far_points(k: np.ndarray, axial_length_mm: float, rx_text: str) -> None:
    for power in np.linalg.eigvalsh(k):
        if power > 0.0 and 1000.0 / power <= axial_length_mm:
            raise VissimInputError(f"prescription {rx_text} puts the far point {1000.0 / power:.4g} mm behind the "
                                   f"corneal vertex, inside the {axial_length_mm:.4g} mm long eye")


def _toric_front(eye: SchematicEye, front_matrix_d: np.ndarray, axis: float, wavelength_nm: float, rx_text: str):
    """The cornea front of power matrix ``front_matrix_d`` (D), its principal meridians ``axis`` and ``axis`` + 90°."""
    front = eye.surfaces[0]
    n_air, n_cornea = _front_indices(eye, wavelength_nm)
    radii = []
    for meridian in (axis, axis + 90.0):
        e = np.array([math.cos(math.radians(meridian)), math.sin(math.radians(meridian))])
        power = float(e @ front_matrix_d @ e)
        if power <= 0.0:
            raise VissimInputError(f"prescription {rx_text} needs the cornea's front to have {power:.4g} dioptres "
                                   f"along {meridian if meridian <= 180.0 else meridian - 180.0:g} deg "
                                   "(a radius <= 0 mm or a plane)")
        radii.append(1000.0 * (n_cornea - n_air) / power)
    return dataclasses.replace(front, radius_mm=radii[0], radius_y_mm=radii[1], axis_deg=axis)


def solved_eye(eye: SchematicEye, k: np.ndarray, axis_deg: float, toric: bool, wavelength_nm: float,
                rx_text: str) -> tuple[SchematicEye, float]:
    """``eye`` with the vitreous and (``toric``) the cornea front that give it the refraction ``k`` at the
    corneal vertex (2 × 2 D) paraxially about its optical axis (module doc), and the vitreous, mm."""
    front_matrix = cornea_front_power_matrix(eye, wavelength_nm)
    mean_front_d = 0.5 * float(np.trace(front_matrix))
    mean_k_d = 0.5 * float(np.trace(k))
    vitreous_mm = _solve_vitreous_mm(eye, mean_k_d / 1000.0, mean_front_d / 1000.0, wavelength_nm, rx_text)
    surfaces = list(eye.surfaces)
    surfaces[-2] = dataclasses.replace(surfaces[-2], thickness_after_mm=vitreous_mm)
    _check_far_points(k, sum(s.thickness_after_mm for s in surfaces[:-1]), rx_text)
    if toric:
        surfaces[0] = _toric_front(eye, (mean_front_d + mean_k_d) * _I2 - k, axis_deg, wavelength_nm, rx_text)
    return dataclasses.replace(eye, surfaces=tuple(surfaces)), vitreous_mm


def paraxial_ametropic_eye(eye: SchematicEye, rx: Prescription,
                           vertex_distance_mm: float = SPECTACLE_VERTEX_DISTANCE_MM,
                           wavelength_nm: float | None = None) -> SchematicEye:
    """``eye`` made to have the spectacle prescription ``rx`` worn ``vertex_distance_mm`` in front of
    its corneal vertex, paraxially about its optical axis, at ``wavelength_nm`` (default: the model's
    reference wavelength): the closed-form solve (module doc). An eye with a visual axis is then
    corrected along it by `vissim.optics.eyes.fixation.ametropic_eye` (the one callers use).

    Spherical equivalent by axial ametropia (the vitreous solved in closed form), cylinder by a
    toric cornea front with the model's mean front power and conic (module doc). Returns a new
    `SchematicEye`; ``eye`` is unchanged. Raises `VissimInputError` when the far point would fall
    inside the eye or between the lens and the eye, when no vitreous > 0 mm gives the spherical
    equivalent, or when the cylinder needs a cornea-front section of power <= 0 D.
    """
    rx, wavelength, rx_text, target = solve_inputs(eye, rx, vertex_distance_mm, wavelength_nm)
    toric = rx.cylinder_diopters != 0.0 or eye.surfaces[0].is_toric
    solved, vitreous_mm = solved_eye(eye, target, rx.axis_deg, toric, wavelength, rx_text)
    return with_source(eye, solved, rx_text, wavelength, vitreous_mm, "")


def solve_inputs(eye: SchematicEye, rx, vertex_distance_mm: float, wavelength_nm: float | None):
    """(the prescription, the wavelength, its text for messages, its far point's vergence at the cornea)."""
    rx = as_prescription(rx)
    wavelength = eye.reference_wavelength_nm if wavelength_nm is None else checked_wavelength_nm(wavelength_nm)
    rx_text = f"{rx} at {checked_vertex_distance_mm(vertex_distance_mm):g} mm"
    return rx, wavelength, rx_text, far_point_vergence_matrix(rx, vertex_distance_mm)


def with_source(eye: SchematicEye, solved: SchematicEye, rx_text: str, wavelength: float, vitreous_mm: float,
                along: str) -> SchematicEye:
    """``solved`` with a source that says how it was made from ``eye``."""
    how = "; toric cornea front" if solved.surfaces[0].is_toric else ""
    source = (f"{eye.source}; made ametropic by vissim.optics.eyes.ametropia for spectacle Rx {rx_text} at "
              f"{wavelength:g} nm (axial: vitreous {vitreous_mm:.6f} mm{how}{along})")
    return dataclasses.replace(solved, source=source)
