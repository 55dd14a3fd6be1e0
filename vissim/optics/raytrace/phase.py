"""A phase plane: a thin element that adds an optical path φ(x, y) to each ray and turns it by ∇φ.

The "Zernike phase" surface of optical design programs, reduced to a plane normal to the axis at
``vertex_z_mm``: a ray crossing it at (x, y) gains the optical path φ(x, y) and its direction
cosines across the axis change by the gradient, ``n d_xy -> n d_xy + ∇φ`` (the grating equation;
d_z keeps its sign and the direction stays a unit vector).  A converging thin lens is
φ = φ0 − (x² + y²) / (2 f): it turns a ray at height x by −x / f towards the axis, either way it
travels, so a phase plane is reciprocal and the eye sensor (tracing out of the eye) and the
numpy trace (into it) apply the same rule.

φ is a polynomial in ``u = (x − x_c) / R``, ``v = (y − y_c) / R`` (``centre_mm``, ``radius_mm``):
``Σ c_pq u^p v^q`` (mm), the terms a tuple of ``(p, q, c_pq)``.

**Virtual plane**: the plane may lie where no ray can reach it (an eye's entrance pupil, behind
the cornea): a ray in a homogeneous medium is carried along its line to the plane, turned there,
and carried back along its new direction to the z it came from (signed optical paths), so that
what follows sees it as if the plane were where it stands in the list of surfaces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.checks import counted
from vissim.errors import VissimInputError

__all__ = ["PhasePlane", "through_phase_plane"]


@dataclass(frozen=True)
class PhasePlane:
    """φ(x, y) (module doc) on the plane ``z = vertex_z_mm``; ``travel_z`` as a `Surface`'s."""

    vertex_z_mm: float
    centre_mm: tuple[float, float]
    radius_mm: float
    terms: tuple[tuple[int, int, float], ...]
    name: str = "phase plane"
    travel_z: int = 1

    def __post_init__(self) -> None:
        if not self.radius_mm > 0.0:
            raise VissimInputError(f"a phase plane's normalisation radius must be > 0 mm, got {self.radius_mm!r}")

    def path_mm(self, x_mm: np.ndarray, y_mm: np.ndarray) -> np.ndarray:
        """φ at (x, y), mm."""
        u, v = self._uv(x_mm, y_mm)
        return sum(c * u ** p * v ** q for p, q, c in self.terms) + 0.0 * u

    def gradient(self, x_mm: np.ndarray, y_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(∂φ/∂x, ∂φ/∂y) at (x, y), dimensionless (mm per mm)."""
        u, v = self._uv(x_mm, y_mm)
        gx = sum(c * p * u ** (p - 1) * v ** q for p, q, c in self.terms if p > 0) + 0.0 * u
        gy = sum(c * q * u ** p * v ** (q - 1) for p, q, c in self.terms if q > 0) + 0.0 * u
        return gx / self.radius_mm, gy / self.radius_mm

    def _uv(self, x_mm, y_mm):
        r = self.radius_mm
        return (np.asarray(x_mm, float) - self.centre_mm[0]) / r, (np.asarray(y_mm, float) - self.centre_mm[1]) / r


def through_phase_plane(plane: PhasePlane, points: np.ndarray, directions: np.ndarray,
                        index: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays (N, 3) in a homogeneous medium of ``index`` through ``plane``, virtual or not (module doc):
    (points back at their own z, new unit directions, optical path gained, mm)."""
    d_z = directions[:, 2]
    to_plane = (plane.vertex_z_mm - points[:, 2]) / d_z
    hit = points + to_plane[:, None] * directions
    gx, gy = plane.gradient(hit[:, 0], hit[:, 1])
    across = np.stack([directions[:, 0] + gx / index, directions[:, 1] + gy / index], axis=1)
    left = 1.0 - np.einsum("ij,ij->i", across, across)
    if np.any(left <= 0.0):
        turned_along = int(np.sum(left <= 0.0))
        raise VissimInputError(f"{counted(turned_along, 'ray')} {'is' if turned_along == 1 else 'are'} turned along "
                               f"the {plane.name} (its gradient exceeds the medium's index)")
    turned = np.column_stack([across, np.sign(d_z) * np.sqrt(left)])
    back = (points[:, 2] - plane.vertex_z_mm) / turned[:, 2]
    path = index * (to_plane + back) + plane.path_mm(hit[:, 0], hit[:, 1])
    return hit + back[:, None] * turned, turned, path
