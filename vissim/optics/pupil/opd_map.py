"""A wavefront given as sampled optical path difference: a traced or measured OPD map.

`compute_psf` accepts an `OpdMap` wherever it accepts a Zernike
`Wavefront`: the PSF core evaluates it at its own pupil
quadrature points (bicubic spline through the samples, evaluated cell by cell:
`vissim.optics.pupil.spline_cells`), and its slopes give the ray-optics PSF and the field size.

Grid (``docs/conventions.md``, OSA pupil frame): ``samples_um[i, j]`` is the OPD in µm at
``x_j = -R + 2 R j / (n - 1)`` (column index increases towards the examiner's right, +x) and
``y_i = R - 2 R i / (n - 1)`` (row 0 at the top, +y), R = ``pupil_diameter_mm`` / 2, so the
grid's square circumscribes the pupil.  Samples outside the pupil disc carry no light; give
them a smooth continuation (a traced map's extrapolation, or zeros where the OPD is smooth to
the rim) so that the spline is exact inside it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.pupil.spline_cells import CellPolynomials
from vissim.optics.pupil.wavefront import Wavefront, ring_fit_um

__all__ = ["OpdMap"]


@dataclass(frozen=True, eq=False)
class OpdMap:
    """OPD samples (µm) on a square grid over a pupil of ``pupil_diameter_mm``, plus Zernike terms."""

    samples_um: np.ndarray
    pupil_diameter_mm: float
    added: Wavefront | None = None  # Zernike terms on top (e.g. chromatic defocus), same pupil
    _spline: object = field(init=False, repr=False)  # scipy's RectBivariateSpline

    def __post_init__(self) -> None:
        values = np.array(self.samples_um, dtype=float)
        if values.ndim != 2 or values.shape[0] != values.shape[1] or values.shape[0] < 4:
            raise VissimInputError(f"an OPD map must be a square 2-D array of at least 4 x 4 µm, got {values.shape}")
        if not np.all(np.isfinite(values)):
            raise VissimInputError("an OPD map must be finite µm everywhere (continue it smoothly outside the pupil)")
        diameter = float(self.pupil_diameter_mm)
        if not math.isfinite(diameter) or diameter <= 0:
            raise VissimInputError(f"an OPD map's pupil diameter must be positive mm, got {self.pupil_diameter_mm!r}")
        values.setflags(write=False)
        radius = diameter / 2.0
        axis = np.linspace(-radius, radius, values.shape[0])
        from scipy.interpolate import RectBivariateSpline  # ~0.2 s to import: only when a map is made

        # The spline's first axis is x (columns), its second y ascending (rows reversed).
        spline = RectBivariateSpline(axis, axis, values[::-1, :].T, kx=3, ky=3)
        object.__setattr__(self, "samples_um", values)
        object.__setattr__(self, "pupil_diameter_mm", diameter)
        object.__setattr__(self, "_spline", spline)

    @classmethod
    def sample(cls, wavefront: Wavefront, size: int = 65) -> OpdMap:
        """A wavefront sampled on this class's grid over its own pupil (for tests and round trips)."""
        radius = wavefront.pupil_diameter_mm / 2.0
        axis = np.linspace(-radius, radius, size)
        return cls(wavefront.opd_um(axis[None, :], axis[::-1, None]), wavefront.pupil_diameter_mm)

    def opd_um(self, x_mm: np.ndarray, y_mm: np.ndarray) -> np.ndarray:
        """OPD (µm) at OSA pupil points (mm); just beyond the grid's square, continued linearly
        from its edge (the PSF core's finite differences reach half a cell past the pupil)."""
        x, y = np.broadcast_arrays(np.asarray(x_mm, dtype=float), np.asarray(y_mm, dtype=float))
        radius = self.pupil_diameter_mm / 2.0
        cx, cy = np.clip(x, -radius, radius).ravel(), np.clip(y, -radius, radius).ravel()
        value, along_x, along_y = self._cells
        out = value(cx, cy) + along_x(cx, cy) * (x.ravel() - cx) + along_y(cx, cy) * (y.ravel() - cy)
        out = out.reshape(x.shape)
        return out if self.added is None else out + self.added.opd_um(x, y)

    def slopes_mrad(self, x_mm: np.ndarray, y_mm: np.ndarray, step_mm: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(dW/dx, dW/dy) in µm/mm = mrad, from the spline's derivatives."""
        x, y = np.broadcast_arrays(np.asarray(x_mm, dtype=float), np.asarray(y_mm, dtype=float))
        _, along_x, along_y = self._cells
        dx, dy = along_x(x, y), along_y(x, y)
        if self.added is not None:
            ax, ay = self.added.slopes_mrad(x, y, step_mm)
            dx, dy = dx + ax, dy + ay
        return dx, dy

    @functools.cached_property
    def _cells(self) -> tuple[CellPolynomials, CellPolynomials, CellPolynomials]:
        """The spline and its x and y derivatives, a polynomial per knot cell (`vissim.optics.pupil.spline_cells`)."""
        return tuple(CellPolynomials.of(s) for s in (self._spline, self._spline.partial_derivative(1, 0),
                                                      self._spline.partial_derivative(0, 1)))

    def with_defocus_diopters(self, extra_sphere_diopters: float) -> OpdMap:
        """Add a spherical *prescription* change (negative = more myopic), as Zernike terms."""
        extra = Wavefront.from_prescription(Prescription(extra_sphere_diopters), self.pupil_diameter_mm)
        return OpdMap(self.samples_um, self.pupil_diameter_mm, extra if self.added is None else self.added + extra)

    def zernike_fit(self, max_order: int = 8) -> Wavefront:
        """Least-squares OSA Zernike fit over the pupil up to ``max_order`` (µm)."""
        keys, solution = ring_fit_um(self.opd_um, self.pupil_diameter_mm, max_order, 3 * max_order + 8,
                                     6 * max_order + 16)
        return Wavefront({k: float(v) for k, v in zip(keys, solution)}, self.pupil_diameter_mm)

    def as_json(self) -> dict:
        fit = self.zernike_fit(6)
        return {
            "kind": "opd_map",
            "pupil_diameter_mm": self.pupil_diameter_mm,
            "samples": list(self.samples_um.shape),
            "added": None if self.added is None else self.added.as_json(),
            "zernike_fit_um": fit.as_json()["zernike_um"],
        }
