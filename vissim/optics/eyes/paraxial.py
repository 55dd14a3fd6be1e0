"""Paraxial optics of a schematic eye: ray-transfer (ABCD) matrices surface by surface.

A paraxial ray is the column (y, n·u): height y (mm) and reduced angle n·u (u the slope, n the
index it travels in). A surface of vertex radius R between indices n and n' is
[[1, 0], [−(n' − n)/R, 1]] (power in mm⁻¹; the conic does not enter paraxially); a homogeneous gap
t is [[1, t/n], [0, 1]]. A GRIN gap n(z, r) = n0(z) + b r² is integrated: the paraxial ray
equation d/dz(n0 dy/dz) = ∂n/∂y = 2 b y, as y' = p/n0(z), p' = 2 b y with p = n0 y', by the
classical fourth-order Runge–Kutta method on a fixed step (`GRIN_STEPS` per half); the surface
sag into a GRIN medium adds nothing at paraxial order (its effect is O(r⁴) in the path).

Matrices start in air at the corneal front vertex, so vergences and refractions are in air.
A refraction is the far point's vergence (D) at a plane: negative for a myope (far point in front).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import positive_number
from vissim.checks import vertex_distance_mm as checked_vertex_distance_mm
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import GrinMedium
from vissim.optics.eyes.defaults import DEFAULT_SPECTACLE_VERTEX_MM
from vissim.optics.eyes.models import SchematicEye

__all__ = ["GRIN_STEPS", "LCA_REFERENCE_NM", "ParaxialEye", "grin_matrix", "matrix_to_surface",
           "equivalent_power_diopters", "image_focal_length_mm", "entrance_pupil_position_mm", "pupil_magnification",
           "entrance_pupil_diameter_mm", "iris_diameter_mm", "refraction_diopters", "spectacle_refraction_diopters",
           "retinal_mm_per_deg", "lca_diopters", "paraxial_eye", "mean_meridian_eye"]

#: Runge–Kutta steps per GRIN segment (a 1.6-2.4 mm half: 0.01 mm steps); halving the step
#: changes Liou–Brennan's power by < 1e-9 D (tests/test_eye_paraxial.py).
GRIN_STEPS = 200
#: The wavelength an LCA curve is referred to, nm (the d line the reference page's table uses).
LCA_REFERENCE_NM = 589.3


def _refraction(power_per_mm: float) -> np.ndarray:
    return np.array([[1.0, 0.0], [-power_per_mm, 1.0]])


def _transfer(thickness_mm: float, index: float) -> np.ndarray:
    return np.array([[1.0, thickness_mm / index], [0.0, 1.0]])


def grin_matrix(medium: GrinMedium, thickness_mm: float, wavelength_nm: float, steps: int = GRIN_STEPS) -> np.ndarray:
    """The paraxial matrix of a GRIN gap, by RK4 on (y, p = n0 y') with ``steps`` fixed steps."""
    h = thickness_mm / steps
    b = medium.r2_coefficient

    def rate(z: float, state: np.ndarray) -> np.ndarray:  # state: 2 x 2, columns are two rays
        return np.array([state[1] / medium.axial_index(z, wavelength_nm), 2.0 * b * state[0]])

    state = np.eye(2)
    for k in range(steps):
        z = k * h
        k1 = rate(z, state)
        k2 = rate(z + h / 2, state + h / 2 * k1)
        k3 = rate(z + h / 2, state + h / 2 * k2)
        k4 = rate(z + h, state + h * k3)
        state = state + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return state


def _index_before(eye: SchematicEye, i: int, wavelength_nm: float) -> float:
    """The axial index just in front of surface ``i``."""
    if i == 0:
        return eye.object_medium.index(wavelength_nm)
    previous = eye.surfaces[i - 1]
    medium = previous.medium_after
    if isinstance(medium, GrinMedium):
        return medium.axial_index(previous.thickness_after_mm, wavelength_nm)
    return medium.index(wavelength_nm)


def _index_after(eye: SchematicEye, i: int, wavelength_nm: float) -> float:
    medium = eye.surfaces[i].medium_after
    return medium.axial_index(0.0, wavelength_nm) if isinstance(medium, GrinMedium) else medium.index(wavelength_nm)


def matrix_to_surface(eye: SchematicEye, surface_index: int, wavelength_nm: float, steps: int = GRIN_STEPS) -> np.ndarray:
    """The matrix from air at the corneal front vertex to the vertex plane of ``surfaces[surface_index]``
    (before it refracts). ``surface_index = len(surfaces) - 1`` ends at the retina. A toric surface
    on the way has no 2 x 2 matrix and raises `VissimInputError`."""
    wavelength = checked_wavelength_nm(wavelength_nm)
    matrix = np.eye(2)
    for i, surface in enumerate(eye.surfaces[:surface_index]):
        if surface.is_toric:
            raise VissimInputError(f"the {eye.name} eye's {surface.name} is toric ({surface.radius_mm:g} mm and "
                                   f"{surface.radius_y_mm:g} mm): use vissim.optics.eyes.ametropia's 4 x 4 matrices")
        n, n_after = _index_before(eye, i, wavelength), _index_after(eye, i, wavelength)
        matrix = _refraction((n_after - n) / surface.radius_mm) @ matrix  # a plane: 1/inf = 0
        medium = surface.medium_after
        if isinstance(medium, GrinMedium):
            gap = grin_matrix(medium, surface.thickness_after_mm, wavelength, steps)
        else:
            gap = _transfer(surface.thickness_after_mm, n_after)
        matrix = gap @ matrix
    return matrix


def mean_meridian_eye(eye: SchematicEye) -> SchematicEye:
    """``eye`` with each toric surface replaced by the sphere of its mean curvature, (1/Rx + 1/Ry)/2
    (the same conic); ``eye`` itself when none is toric. The paraxial 2 x 2 matrices of
    this module need surfaces of revolution: its power is exactly the mean of the toric eye's two
    principal powers (a matrix element linear in each surface's curvature), and its pupils and
    focal lengths stand for the toric eye's mean meridian."""
    surfaces = tuple(dataclasses.replace(s, radius_mm=2.0 / (1.0 / s.radius_mm + 1.0 / s.radius_y_mm),
                                         radius_y_mm=None)
                     if s.is_toric else s for s in eye.surfaces)
    return eye if surfaces == eye.surfaces else dataclasses.replace(eye, surfaces=surfaces)


def _to_retina(eye: SchematicEye, wavelength_nm: float, steps: int = GRIN_STEPS) -> np.ndarray:
    return matrix_to_surface(eye, len(eye.surfaces) - 1, wavelength_nm, steps)


def equivalent_power_diopters(eye: SchematicEye, wavelength_nm: float, steps: int = GRIN_STEPS) -> float:
    """The eye's equivalent power, D: −C of the cornea-to-retina matrix (gaps do not change C)."""
    return -1000.0 * _to_retina(eye, wavelength_nm, steps)[1, 0]


def image_focal_length_mm(eye: SchematicEye, wavelength_nm: float) -> float:
    """The image-space (posterior) focal length f′ = n′/P, mm: n′ the vitreous's index, P the eye's
    equivalent power; the second principal point to the second focal point, in the vitreous (optiland's
    and Zemax's image-space EFL: 22.03 mm for the wide-angle Navarro eye at 543 nm). Not the focal
    length in air 1/P (16.6 mm there), which some texts call the EFL."""
    n_image = _index_before(eye, len(eye.surfaces) - 1, checked_wavelength_nm(wavelength_nm))
    return 1000.0 * n_image / equivalent_power_diopters(eye, wavelength_nm)


def entrance_pupil_position_mm(eye: SchematicEye, wavelength_nm: float) -> float:
    """The entrance pupil (the iris imaged by the cornea), mm behind the corneal front vertex."""
    a, b = matrix_to_surface(eye, eye.stop_index, wavelength_nm)[0]
    return b / a


def pupil_magnification(eye: SchematicEye, wavelength_nm: float) -> float:
    """Entrance-pupil diameter per iris diameter (paraxial)."""
    return 1.0 / matrix_to_surface(eye, eye.stop_index, wavelength_nm)[0, 0]


def entrance_pupil_diameter_mm(eye: SchematicEye, iris_mm: float, wavelength_nm: float) -> float:
    """The entrance-pupil diameter, mm, of an iris (stop) ``iris_mm`` across (paraxial)."""
    return positive_number(iris_mm, "iris diameter", "mm") * pupil_magnification(eye, wavelength_nm)


def iris_diameter_mm(eye: SchematicEye, entrance_pupil_mm: float, wavelength_nm: float) -> float:
    """The iris diameter, mm, whose entrance pupil is ``entrance_pupil_mm`` across (paraxial)."""
    return positive_number(entrance_pupil_mm, "entrance pupil diameter", "mm") / pupil_magnification(eye, wavelength_nm)


def refraction_diopters(eye: SchematicEye, wavelength_nm: float, steps: int = GRIN_STEPS) -> float:
    """The paraxial refraction at the corneal vertex, D: the vergence A/B in air that the eye images
    onto its retina (its far point's vergence); 0 for an emmetrope, negative for a myope."""
    a, b = _to_retina(eye, wavelength_nm, steps)[0]
    return 1000.0 * a / b


def spectacle_refraction_diopters(eye: SchematicEye, wavelength_nm: float, vertex_distance_mm: float = DEFAULT_SPECTACLE_VERTEX_MM) -> float:
    """The thin spectacle lens, D, at ``vertex_distance_mm`` in front of the corneal vertex whose
    image of infinity is the far point: K / (1 + d K), d in metres, K the corneal-plane refraction."""
    d_m = checked_vertex_distance_mm(vertex_distance_mm) / 1000.0
    k = refraction_diopters(eye, wavelength_nm)
    return k / (1.0 + d_m * k)


def retinal_mm_per_deg(eye: SchematicEye, wavelength_nm: float) -> float:
    """Retinal image height per degree of field, mm: the paraxial chief ray (through the entrance
    pupil's centre) carried to the retina's vertex plane."""
    e = entrance_pupil_position_mm(eye, wavelength_nm)
    a, b = _to_retina(eye, wavelength_nm)[0]
    return abs(b - a * e) * math.pi / 180.0


def lca_diopters(eye: SchematicEye, wavelengths_nm, reference_nm: float = LCA_REFERENCE_NM) -> np.ndarray:
    """Longitudinal chromatic aberration: the corneal-plane refraction at each wavelength minus that
    at ``reference_nm``, D (negative in the blue: the eye is more myopic there)."""
    k_ref = refraction_diopters(eye, reference_nm)
    return np.array([refraction_diopters(eye, w) - k_ref for w in np.atleast_1d(wavelengths_nm)])


@dataclass(frozen=True)
class ParaxialEye:
    """An eye's paraxial numbers at one wavelength; the pupils refer to an iris of ``iris_mm``."""

    model: str
    wavelength_nm: float
    power_diopters: float
    image_focal_length_mm: float
    entrance_pupil_position_mm: float
    entrance_pupil_diameter_mm: float
    iris_mm: float
    refraction_diopters: float
    retinal_mm_per_deg: float


def paraxial_eye(eye: SchematicEye, wavelength_nm: float, iris_mm: float) -> ParaxialEye:
    """`ParaxialEye` of ``eye`` at ``wavelength_nm`` with an iris ``iris_mm`` across."""
    return ParaxialEye(eye.name, checked_wavelength_nm(wavelength_nm), equivalent_power_diopters(eye, wavelength_nm),
                       image_focal_length_mm(eye, wavelength_nm), entrance_pupil_position_mm(eye, wavelength_nm),
                       entrance_pupil_diameter_mm(eye, iris_mm, wavelength_nm), iris_mm,
                       refraction_diopters(eye, wavelength_nm), retinal_mm_per_deg(eye, wavelength_nm))
