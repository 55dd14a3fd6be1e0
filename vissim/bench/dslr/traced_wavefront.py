"""The wavefront the bench's trial lenses add at the camera, from the exact trace (`vissim.bench.lenses.trace`).

The ``thinlens`` camera is an ideal lens in its aperture plane z = 0, focused on the chart: it
turns the spherical wave from a chart point into a perfect image.  With trial lenses, the
field in the aperture carries the extra phase ``k (L - L_ref)``, L the traced optical path from
the chart point to an aperture point and ``L_ref = |x - X|`` the straight path.  That is the
camera's pupil function exactly (no exit-pupil reference sphere to choose), so

    W(x, y) = L_ref - L      (µm; OSA sign: W > 0 is phase advance)

The sign: the camera seen as an eye, its outgoing wave (by reciprocity) is ahead where the
incoming one is late.  So a plus lens, which makes the camera myopic, gives c(2,0) > 0 like
``Wavefront.from_prescription`` of the camera's prescription, and a ray through (x, y) is seen
in the direction +grad W (docs/conventions.md; pinned by ``tests/bench/test_lens_trace.py``).

Frames: the pupil's (x, y) are the world's (x, y) on z = 0 -- x the examiner's right (the
camera's left), y up: OSA's frame for the camera as the observer, the one of ``Wavefront``.

Piston and tilt: piston (the glass's extra path) is removed.  Tilt is the image's displacement
-- the trial lens's magnification and distortion at that field point -- and is reported apart
(``tilt_um``, ``image_shift_mrad``: 2c/R per axis), not left in the map or the ``wavefront``:
a PSF is centred on its image point and the magnification is applied to the chart.

Amplitude: the pupil stays uniformly lit; the lenses' ray-density change over a 3.6 mm pupil
(relative order d P r, ~1e-4) is left out.

The samples are on the grid of `vissim.optics.pupil.opd_map.OpdMap` (square, circumscribing
the pupil, row 0 at +y): every grid point, corners too, is a real aimed ray, so outside the
disc the map is the traced continuation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from vissim.bench.lenses.trace import bench_surfaces, object_point_mm
from vissim.checks import finite_number
from vissim.errors import VissimInputError
from vissim.optics.rx.glass import D_LINE_NM
from vissim.optics.rx.prescription import LensPower
from vissim.optics.raytrace import aim_rays
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.pupil.zernike import fit_zernike_um, zernike_nm
from vissim.units import arcmin_to_rad, mm_to_m

__all__ = ["TracedWavefront", "ShiftInvariance", "fit_zernike_um", "trace_bench_wavefront", "frame_field_points_deg",
           "shift_invariance"]

#: Defaults: 65 x 65 samples (centre on a sample), Zernike radial order 8.
DEFAULT_SAMPLES = 65
DEFAULT_MAX_ORDER = 8


@dataclass(frozen=True, eq=False)
class TracedWavefront:
    """The traced OPD of the trial lenses at one chart point (module doc for frames and signs).

    ``samples_um`` (n, n): W at ``x_mm[j]``, ``y_mm[i]`` (row 0 at +y), piston and tilt removed.
    ``coefficients_um``: the full fit, piston and tilt included.  ``wavefront``: n >= 2 only.
    ``directions`` (n, n, 3): unit ray directions after the last surface (world frame).
    """

    field_deg: tuple[float, float]
    object_point_mm: tuple[float, float, float]
    wavelength_nm: float
    pupil_diameter_mm: float
    x_mm: np.ndarray
    y_mm: np.ndarray
    samples_um: np.ndarray
    directions: np.ndarray
    coefficients_um: dict
    fit_residual_rms_um: float
    focus_error_diopters: float = 0.0
    wavefront: Wavefront = field(init=False)

    def __post_init__(self) -> None:
        for name in ("x_mm", "y_mm", "samples_um", "directions"):
            getattr(self, name).setflags(write=False)
        higher = {k: v for k, v in self.coefficients_um.items() if k[0] >= 2}
        object.__setattr__(self, "wavefront", Wavefront(higher, self.pupil_diameter_mm))

    @property
    def tilt_um(self) -> dict[tuple[int, int], float]:
        return {k: self.coefficients_um.get(k, 0.0) for k in ((1, -1), (1, 1))}

    @property
    def image_shift_mrad(self) -> tuple[float, float]:
        """Where the chart point is seen, minus where it is: (x, y) mrad in the OSA frame, 2c/R."""
        return Wavefront(self.tilt_um, self.pupil_diameter_mm).image_shift_mrad

    @property
    def rms_um(self) -> float:
        """RMS wavefront error over the pupil without piston and tilt (unit-RMS Zernikes, n >= 2)."""
        return math.sqrt(sum(v * v for v in self.wavefront.coefficients_um.values()))

    @property
    def higher_order_rms_um(self) -> float:
        return math.sqrt(sum(v * v for (n, _), v in self.wavefront.coefficients_um.items() if n >= 3))

    @property
    def added_power(self) -> LensPower:
        """The equivalent power the lenses add at the camera (minus cylinder; a plus lens > 0)."""
        rx = self.wavefront.to_prescription()
        return LensPower.from_power_matrix(-np.asarray(rx.power_matrix(), dtype=float)).minus_cylinder()

    def as_opd_map(self):
        """The samples as a `vissim.optics.pupil.opd_map.OpdMap` (same grid and sign)."""
        from vissim.optics.pupil.opd_map import OpdMap

        return OpdMap(self.samples_um, self.pupil_diameter_mm)

    def as_json(self) -> dict:
        added = self.added_power
        return {
            "field_deg": list(self.field_deg),
            "object_point_mm": list(self.object_point_mm),
            "wavelength_nm": self.wavelength_nm,
            "pupil_diameter_mm": self.pupil_diameter_mm,
            "zernike_um": {f"{n},{m}": v for (n, m), v in self.wavefront.coefficients_um.items()},
            "tilt_um": {f"{n},{m}": v for (n, m), v in self.tilt_um.items()},
            "image_shift_mrad": list(self.image_shift_mrad),
            "rms_um": self.rms_um,
            "higher_order_rms_um": self.higher_order_rms_um,
            "fit_residual_rms_um": self.fit_residual_rms_um,
            "effective_sphere_diopters": added.sphere_diopters,
            "effective_cylinder_diopters": added.cylinder_diopters,
            "effective_axis_deg": added.axis_deg,
            "added_power": added.format(4),
            "focus_error_diopters": self.focus_error_diopters,
            "samples": list(self.samples_um.shape),
        }


def trace_bench_wavefront(bench, *, field_deg=(0.0, 0.0), wavelength_nm: float = D_LINE_NM,
                          samples: int = DEFAULT_SAMPLES, max_order: int = DEFAULT_MAX_ORDER) -> TracedWavefront:
    """Trace ``bench``'s lenses from the chart point at ``field_deg`` onto its entrance pupil (module doc).

    ``field_deg`` (x, y): world / TABO frame (x towards the examiner's right).  ``wavelength_nm``
    defaults to the d line, where the glass has the rendered index.  ``focus_error_diopters``
    (``1/focus - 1/chart``) is *not* in the wavefront: it is the camera's, not the lenses'.
    """
    wavelength = finite_number(wavelength_nm, "wavelength", "nm")
    if int(samples) != samples or not 9 <= samples <= 1025:
        raise VissimInputError(f"pupil samples must be a whole number within 9-1025, got {samples!r}")
    samples = int(samples)
    pupil = bench.entrance_pupil_diameter_mm
    radius = 0.5 * pupil
    axis = np.linspace(-radius, radius, samples)
    x, y = np.meshgrid(axis, axis[::-1])  # row 0 at +y, as OpdMap
    origin = object_point_mm(bench.chart_distance_mm, field_deg)
    surfaces = bench_surfaces(bench, wavelength)
    in_pupil = np.hypot(x, y).ravel() <= radius * (1.0 + 1e-9)
    bundle, _ = aim_rays(surfaces, origin, np.stack([x.ravel(), y.ravel()], axis=1), apertured=in_pupil)
    reference = np.linalg.norm(bundle.points_mm - origin, axis=1)
    opd_um = 1000.0 * (reference - bundle.opl_mm)  # mm -> µm, W = L_ref - L
    coefficients, residual = fit_zernike_um(x, y, opd_um, pupil, max_order)
    radius_rho = np.hypot(x, y).ravel() / radius
    theta = np.arctan2(y, x).ravel()
    low = sum(coefficients[k] * zernike_nm(*k, radius_rho, theta) for k in ((0, 0), (1, -1), (1, 1)))
    focus_error = 1.0 / mm_to_m(bench.focus_distance_mm) - 1.0 / mm_to_m(bench.chart_distance_mm)
    return TracedWavefront(
        field_deg=tuple(float(v) for v in field_deg), object_point_mm=tuple(float(v) for v in origin),
        wavelength_nm=wavelength, pupil_diameter_mm=pupil, x_mm=axis.copy(), y_mm=axis[::-1].copy(),
        samples_um=(opd_um - low).reshape(samples, samples), directions=bundle.directions.reshape(samples, samples, 3),
        coefficients_um=coefficients, fit_residual_rms_um=residual, focus_error_diopters=focus_error)


def frame_field_points_deg(bench) -> tuple[tuple[float, float], ...]:
    """Centre and the four corners of the camera's frame (``size_px`` at ``arcmin_per_px``), degrees."""
    rows, cols = bench.size_px
    pitch = math.tan(arcmin_to_rad(bench.arcmin_per_px))
    half_x = math.degrees(math.atan(0.5 * cols * pitch))
    half_y = math.degrees(math.atan(0.5 * rows * pitch))
    return ((0.0, 0.0),) + tuple((sx * half_x, sy * half_y) for sy in (1, -1) for sx in (1, -1))


@dataclass(frozen=True, eq=False)
class ShiftInvariance:
    """Traced wavefronts at several field points and how much they differ from the first (the centre)."""

    traces: tuple[TracedWavefront, ...]

    def coefficient_spread_um(self) -> dict[tuple[int, int], float]:
        """Per term (n >= 2): the largest |c(field) - c(centre)|, µm."""
        centre = self.traces[0].wavefront.coefficients_um
        keys = sorted({k for t in self.traces for k in t.wavefront.coefficients_um})
        return {k: max(abs(t.wavefront.coefficients_um.get(k, 0.0) - centre.get(k, 0.0)) for t in self.traces)
                for k in keys}

    def max_difference_rms_um(self) -> float:
        """The largest RMS of (wavefront at a field point - wavefront at the centre), µm."""
        centre = self.traces[0].wavefront.coefficients_um
        return max(math.sqrt(sum((t.wavefront.coefficients_um.get(k, 0.0) - centre.get(k, 0.0)) ** 2
                                 for k in set(centre) | set(t.wavefront.coefficients_um))) for t in self.traces)

    def as_json(self) -> dict:
        return {
            "field_points_deg": [list(t.field_deg) for t in self.traces],
            "added_power": [t.added_power.format(4) for t in self.traces],
            "coefficient_spread_um": {f"{n},{m}": v for (n, m), v in self.coefficient_spread_um().items()},
            "max_difference_rms_um": self.max_difference_rms_um(),
        }


def shift_invariance(bench, field_points_deg=None, **kwargs) -> ShiftInvariance:
    """Trace the centre and corners of the frame (or ``field_points_deg``, centre first); kwargs as
    `trace_bench_wavefront`."""
    points = frame_field_points_deg(bench) if field_points_deg is None else tuple(field_points_deg)
    return ShiftInvariance(tuple(trace_bench_wavefront(bench, field_deg=p, **kwargs) for p in points))
