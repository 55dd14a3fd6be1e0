"""One wavefront per wavelength over one pupil: an eye with its own dispersion.

A `SpectralWavefront` holds a `Wavefront` (OSA Zernikes in µm over one pupil) for each of its
wavelengths, e.g. a schematic eye traced at each one
(`vissim.optics.eyes.psf_wavefront.eye_spectral_wavefront`). `vissim.optics.psf.compute.compute_psf`
and the field sizing of `vissim.optics.psf.field_size` take it in place of a `Wavefront`: each
wavelength's PSF is of that wavelength's own front (`field_size.front_at_wavelength`, the one
place it is chosen), and a Thibos chromatic defocus (``lca_reference_nm``) is refused, the
fronts carrying their own.

Every front is in one image frame: its tilt places its wavelength's PSF relative to the origin
the PSF is centred on (for a traced eye, the chief ray's image point at
``reference_wavelength_nm``), so a polychromatic PSF shows the transverse chromatic aberration.

``field_map`` (a 2 x 2 matrix over OSA's x, y; None: the identity) takes the angles the fronts' slopes
give to the visual angles they are seen at: off axis a traced eye's pupil coordinates lie in a plane
oblique to the beam (`vissim.optics.eyes.traced_wavefront.field_map`). `vissim.optics.psf.compute.compute_psf`
draws every PSF of the front through it (`field_mapped`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vissim.checks import instance_of
from vissim.checks import wavelength_nm as checked_wavelength_nm
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.pupil.wavefront import WAVELENGTH_MATCH_NM, Wavefront, same_wavelength
from vissim.units import xy_matrix_to_image_rowcol

ndimage = lazy_module("scipy.ndimage")

__all__ = ["SpectralWavefront", "WAVELENGTH_MATCH_NM", "wavelengths_for", "field_mapped", "field_map_stretch",
           "FIELD_MAP_IDENTITY_TOL"]

#: A field map within this of the identity (largest element) is the identity: no PSF is resampled.
FIELD_MAP_IDENTITY_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class SpectralWavefront:
    """``fronts[i]`` is the wavefront at ``wavelengths_nm[i]`` (increasing), all over one pupil (mm).

    ``reference_wavelength_nm``: the wavelength whose image point is the frame's origin (None when the
    fronts were not placed in one frame by such a point); ``description``: what the fronts are (for
    the record); ``field_map``: slopes' angles -> visual angles (module doc).

    Examples
    --------
    >>> from vissim.optics.pupil.wavefront import Wavefront
    >>> s = SpectralWavefront((500.0, 600.0), (Wavefront({(2, 0): 0.1}, 3.0), Wavefront({(2, 0): -0.1}, 3.0)))
    >>> s.pupil_diameter_mm, s.at(600.0).coefficients_um[(2, 0)]
    (3.0, -0.1)
    """

    wavelengths_nm: tuple[float, ...]
    fronts: tuple[Wavefront, ...]
    reference_wavelength_nm: float | None = None
    description: str = ""
    field_map: tuple | None = None

    def __post_init__(self) -> None:
        wavelengths = tuple(checked_wavelength_nm(w) for w in self.wavelengths_nm)
        fronts = tuple(self.fronts)
        if not wavelengths or len(fronts) != len(wavelengths):
            raise VissimInputError(f"a spectral wavefront needs one front per wavelength, got {len(fronts)} fronts "
                                   f"for {len(wavelengths)} wavelengths")
        if any(b <= a for a, b in zip(wavelengths, wavelengths[1:])):
            raise VissimInputError(f"a spectral wavefront's wavelengths must increase, got {wavelengths} nm")
        for wavelength, front in zip(wavelengths, fronts):
            instance_of(front, Wavefront, "each front of a SpectralWavefront", "a Wavefront (µm over a pupil)")
            if front.wavelength_nm is not None and not same_wavelength(front.wavelength_nm, wavelength):
                raise VissimInputError(f"a spectral wavefront's front at {front.wavelength_nm:g} nm is given for "
                                       f"{wavelength:g} nm")
        pupils = {front.pupil_diameter_mm for front in fronts}
        if len(pupils) != 1:
            raise VissimInputError(f"a spectral wavefront's fronts must share one pupil, got {sorted(pupils)} mm")
        object.__setattr__(self, "wavelengths_nm", wavelengths)
        object.__setattr__(self, "fronts", fronts)
        object.__setattr__(self, "field_map", _checked_map(self.field_map))

    @property
    def pupil_diameter_mm(self) -> float:
        return self.fronts[0].pupil_diameter_mm

    def at(self, wavelength_nm: float) -> Wavefront:
        """The front at ``wavelength_nm`` (one of `wavelengths_nm`); any other is refused."""
        for w, front in zip(self.wavelengths_nm, self.fronts):
            if same_wavelength(w, wavelength_nm):
                return front
        held = ", ".join(f"{w:g}" for w in self.wavelengths_nm)
        raise VissimInputError(f"wavelength {wavelength_nm:g} nm is not one of this spectral wavefront's ({held} nm)")

    def map(self, change) -> SpectralWavefront:
        """The same wavelengths with ``change(front)`` in place of each front (e.g. a prescription added)."""
        return SpectralWavefront(self.wavelengths_nm, tuple(change(f) for f in self.fronts),
                                 self.reference_wavelength_nm, self.description, self.field_map)

    def as_json(self) -> dict:
        return {
            "pupil_diameter_mm": self.pupil_diameter_mm,
            "reference_wavelength_nm": self.reference_wavelength_nm,
            "description": self.description,
            "field_map": None if self.field_map is None else [list(row) for row in self.field_map],
            "per_wavelength": [{"wavelength_nm": w, "zernike_um": front.as_json()["zernike_um"]}
                               for w, front in zip(self.wavelengths_nm, self.fronts)],
        }

    def __repr__(self) -> str:
        span = f"{self.wavelengths_nm[0]:g}-{self.wavelengths_nm[-1]:g}" if len(self.fronts) > 1 else \
            f"{self.wavelengths_nm[0]:g}"
        return f"SpectralWavefront({len(self.fronts)} fronts, {span} nm, over {self.pupil_diameter_mm:g} mm)"


def wavelengths_for(wavefront, wavelength_nm: float | Sequence[float] | None, default_nm: float):
    """The wavelength(s) (nm) a PSF of ``wavefront`` is computed at: ``wavelength_nm`` when given, else a
    spectral front's own, else the one a `Wavefront` knows, else ``default_nm``."""
    if wavelength_nm is not None:
        return wavelength_nm
    if isinstance(wavefront, SpectralWavefront):
        return wavefront.wavelengths_nm
    own = getattr(wavefront, "wavelength_nm", None)
    return default_nm if own is None else own


def _checked_map(matrix) -> tuple | None:
    """A field map as a tuple of two rows, or None for none or the identity; refused unless 2 x 2, finite and
    orientation-keeping (positive determinant)."""
    if matrix is None:
        return None
    try:
        m = np.asarray(matrix, dtype=float)
    except (TypeError, ValueError):
        m = np.full(1, np.nan)
    if m.shape != (2, 2) or not np.all(np.isfinite(m)) or np.linalg.det(m) <= 0.0:
        raise VissimInputError(f"a field map must be a finite 2 x 2 matrix with a positive determinant, got {matrix!r}")
    if np.max(np.abs(m - np.eye(2))) <= FIELD_MAP_IDENTITY_TOL:
        return None
    return tuple(tuple(float(v) for v in row) for row in m)


def field_map_stretch(field_map) -> float:
    """How much ``field_map`` widens a PSF at most (its largest singular value; 1 for None)."""
    return 1.0 if field_map is None else float(np.linalg.norm(np.asarray(field_map, dtype=float), 2))


def field_mapped(array: np.ndarray, field_map) -> np.ndarray:
    """A PSF array ``[row, col]`` (image axes, docs/conventions.md: `vissim.units.xy_matrix_to_image_rowcol`; origin
    at ``[N//2, N//2]``; values per pixel) as seen through ``field_map`` (module doc): value(θ) = value(map⁻¹ θ) / det(map), by
    cubic interpolation (negative ringing clipped); ``field_map`` None returns ``array``. The energy the map
    moves beyond the field is lost (the caller's field check sees it)."""
    if field_map is None:
        return array

    in_rows = xy_matrix_to_image_rowcol(np.linalg.inv(np.asarray(field_map, dtype=float)))
    centre = np.array([array.shape[0] // 2, array.shape[1] // 2], dtype=float)
    rows, cols = np.indices(array.shape, dtype=float)
    offsets = np.stack([rows.ravel() - centre[0], cols.ravel() - centre[1]])
    source = in_rows @ offsets + centre[:, None]
    values = ndimage.map_coordinates(np.asarray(array, dtype=np.float64), source, order=3, mode="constant", cval=0.0)
    return np.maximum(values.reshape(array.shape), 0.0) / float(np.linalg.det(np.asarray(field_map, dtype=float)))
