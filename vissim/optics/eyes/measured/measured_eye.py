"""A measured human eye: one subject's wavefront data on a schematic base eye.

Spelled ``jaeken-artal-2012:SUBJECT:EYE`` (``jaeken-artal-2012:17:right``) or ``polans-2015:SUBJECT`` (right
eyes only), a measured eye is an `Eye` whose schematic is the **base eye** `BASE_EYE_MODEL` (Navarro 1985: centred,
so one base serves right and left eyes). The base gives the entrance pupil's place and size, the retina's map, the
chief ray (the PSF's origin, and the transverse chromatic aberration as tilt) and the dispersion; the data give the
rest. Its monochromatic wavefront at a measured field is the measured one:

* **Orders 2 and up** (j ≥ 3) are the data's at that field (`datasets.WavefrontDataset.at_field`: interpolated
  between measured fields), re-expanded over the eye's entrance pupil (`Wavefront.rescaled`: exact for a smaller
  concentric pupil; a pupil larger than the data's 4 mm is refused, nothing is extrapolated); the base eye's own
  aberrations at that field are dropped. Piston and tilt are the base eye's (the data's tilts are the instrument's
  alignment: −4.8 µm of vertical tilt on average at the fovea); over a pupil smaller than the data's, the tilt
  the higher orders have over it (coma's) is added to the base's.
* **Defocus in other light**: the data's defocus is that of `DEFOCUS_WAVELENGTH_NM`; at another wavelength it gains
  the base eye's traced chromatic difference of defocus between the two, at that field and pupil. The other terms
  are the data's at every wavelength (astigmatism and the higher orders change little with wavelength).
* **Wavelengths**: both studies measured with near-infrared light (`MEASURING_WAVELENGTH_NM`, 780 nm: the value the
  stored papers' abstracts do not give; the evidence for it is Polans et al.'s note, below). Jaeken & Artal's
  defocus is at that wavelength: the data's foveal defocus is about 0.76 D more hyperopic than in the visible.
  Polans et al.'s defocus (j = 4) already had −0.8 D of chromatic difference applied (ISETBio's note) to bring it
  to the visible, 555 nm here; the base eye's traced difference between 780 and 555 nm is −0.76 D.
* **The pupil's plane**: the data are over a circle in the plane normal to the measuring beam (the
  wavefront sensor's), not in the entrance pupil's plane as a traced schematic eye's are. A measured eye's
  front stays in the data's plane (`BEAM_PLANE`, the `EyeWavefront.pupil_plane`): its refraction takes no
  oblique stretch (`refraction.eye_refraction`), its slopes go to visual angle by `beam_field_map`, the base
  eye's tilt and ray points are carried into that plane, and its pupil at every field is the circle the data
  define (the entrance pupil's oblique foreshortening, cos θ, is the instrument's, already in the data).
* **Lenses** in front of a measured eye are not traced yet (refused): their effect is given as the light's
  vergence at the entrance pupil, as a campaign's trial lens is for the schematic eye. In the beam's plane a
  vergence is a plain sphere at every field (no oblique stretch: `psf_wavefront.eye_spectral_wavefront`).
* **Rendered** (`phase_plane`): the base eye with a phase plane at its entrance pupil that gives it this front.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import MEASURED_EYE_SPELLING
from vissim.optics.eyes.measured.datasets import DATASET_NAMES, load_dataset
from vissim.optics.eyes.refraction import BEAM_PLANE, chief_ray_stretch
from vissim.optics.eyes.traced_wavefront import DEFAULT_SAMPLES, trace_eye_wavefront
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.pupil.zernike import ansi_j_to_nm

__all__ = ["MeasuredWavefront", "parse_measured_eye", "is_measured_name", "BASE_EYE_MODEL",
           "MEASURING_WAVELENGTH_NM", "DEFOCUS_WAVELENGTH_NM", "measured_trace", "measured_front", "MEASURED_EYE_SPELLING",
           "beam_field_map"]

#: The schematic eye a measured eye is built on (module doc).
BASE_EYE_MODEL = "navarro-1985"
#: The wavelength each study measured its wavefronts in, nm (module doc).
MEASURING_WAVELENGTH_NM = {"jaeken-artal-2012": 780.0, "polans-2015": 780.0}
#: The wavelength each study's defocus (j = 4) refers to, nm (module doc).
DEFOCUS_WAVELENGTH_NM = {"jaeken-artal-2012": 780.0, "polans-2015": 555.0}
_NAME = re.compile(r"^(?P<dataset>[a-z0-9-]+):(?P<subject>[^:]*)(?::(?P<eye>[^:]*))?$")


@dataclass(frozen=True)
class MeasuredWavefront:
    """One measured eye of a dataset: ``subject`` as numbered in the data, ``eye`` ``"right"`` or ``"left"``."""

    dataset: str
    subject: int
    eye: str = "right"

    def __post_init__(self) -> None:
        load_dataset(self.dataset).eye_index(self.subject, self.eye)  # refused when the data has no such eye

    @property
    def name(self) -> str:
        """How the eye is spelled (module doc)."""
        if self.dataset == "polans-2015":
            return f"{self.dataset}:{self.subject}"
        return f"{self.dataset}:{self.subject}:{self.eye}"

    @property
    def pupil_mm(self) -> float:
        """The pupil the data were measured over, mm."""
        return load_dataset(self.dataset).pupil_mm

    @property
    def defocus_wavelength_nm(self) -> float:
        return DEFOCUS_WAVELENGTH_NM[self.dataset]

    def checked_pupil_mm(self, pupil_mm: float) -> float:
        """``pupil_mm`` if the data cover it (at most their pupil: nothing is extrapolated); else refused."""
        limit = self.pupil_mm
        if pupil_mm > limit * (1.0 + 1e-12):
            raise VissimInputError(f"{self.name} was measured over a {limit:g} mm pupil; an entrance pupil of "
                                   f"{pupil_mm:g} mm would extrapolate it: give at most {limit:g} mm")
        return pupil_mm

    def front(self, field_deg, pupil_mm: float) -> Wavefront:
        """The data's orders 2 and up (j ≥ 3) at ``field_deg``, µm over a ``pupil_mm`` entrance pupil, in the light
        its defocus refers to."""
        data = load_dataset(self.dataset)
        pupil_mm = self.checked_pupil_mm(pupil_mm)
        coefficients = data.at_field(self.subject, self.eye, field_deg)
        terms = {ansi_j_to_nm(j): float(c) for j, c in enumerate(coefficients) if j >= 3 and c != 0.0}
        return Wavefront(terms, data.pupil_mm, self.defocus_wavelength_nm).rescaled(pupil_mm)


def is_measured_name(name) -> bool:
    """Whether ``name`` spells a measured eye (``DATASET:...``) rather than a schematic model."""
    return isinstance(name, str) and name.split(":", 1)[0] in DATASET_NAMES and ":" in name


def parse_measured_eye(name: str) -> MeasuredWavefront:
    """The `MeasuredWavefront` ``name`` spells (module doc); a malformed name is refused with the spelling."""
    spelling = f"{MEASURED_EYE_SPELLING} (e.g. jaeken-artal-2012:17:right)"
    match = _NAME.match(name)
    if match is None or match["dataset"] not in DATASET_NAMES:
        raise VissimInputError(f"a measured eye is spelled {spelling}, got {name!r}")
    try:
        subject = int(match["subject"])
    except ValueError:
        raise VissimInputError(f"a measured eye's subject is a whole number ({spelling}), got {name!r}") from None
    eye = match["eye"]
    if match["dataset"] == "jaeken-artal-2012" and eye is None:
        raise VissimInputError(f"say which eye: {spelling}, got {name!r}")
    return MeasuredWavefront(match["dataset"], subject, eye or "right")


def beam_field_map(trace) -> np.ndarray:
    """The 2 x 2 map from slopes over the plane normal to the chief ray to visual angle: the traced front's
    ``field_map`` (from slopes over the entrance-pupil plane) after the stretch that carries those slopes over
    (`refraction.chief_ray_stretch`; the identity on axis)."""
    return np.asarray(trace.field_map, dtype=float) @ np.linalg.inv(chief_ray_stretch(trace.chief_direction))


def measured_trace(trace, measured: MeasuredWavefront, defocus_reference):
    """The base eye's `EyeWavefront` ``trace`` (no lenses in front) with its own aberrations replaced by
    ``measured``'s (module doc); ``defocus_reference``: the base eye traced at ``measured.defocus_wavelength_nm``,
    same field and pupil. The front is over the plane normal to the chief ray (`BEAM_PLANE`), as the data are."""
    if trace.lenses is not None:
        raise VissimInputError(f"{measured.name} is a measured eye: lenses in front of it are not traced yet; give "
                               "their effect as the light's vergence instead")
    front = measured.front(trace.field_deg, trace.entrance_pupil_mm).coefficients_um
    shift = trace.zernike_um.get((2, 0), 0.0) - defocus_reference.zernike_um.get((2, 0), 0.0)
    stretch = chief_ray_stretch(trace.chief_direction)  # slopes over the pupil's plane -> over the beam's
    tilt = stretch @ np.array([trace.zernike_um.get((1, 1), 0.0), trace.zernike_um.get((1, -1), 0.0)])
    zernike = {(1, 1): float(tilt[0]), (1, -1): float(tilt[1])}  # the chief ray's, plus the data's over the pupil
    for key in set(front) | {(2, 0)}:
        if key[0] >= 1:
            zernike[key] = zernike.get(key, 0.0) + front.get(key, 0.0) + (shift if key == (2, 0) else 0.0)
    new = Wavefront(zernike, trace.entrance_pupil_mm, trace.wavelength_nm)
    x_mm, y_mm = np.linalg.inv(stretch) @ np.stack([np.asarray(trace.x_mm, float), np.asarray(trace.y_mm, float)])
    opd = np.asarray(new.opd_um(x_mm, y_mm), dtype=float)
    return dataclasses.replace(trace, model=measured.name, zernike_um=zernike, x_mm=x_mm, y_mm=y_mm, opd_um=opd,
                               fit_residual_rms_um=0.0, pupil_plane=BEAM_PLANE,
                               field_map=tuple(tuple(float(v) for v in row) for row in beam_field_map(trace)))


def measured_front(trace, measured: MeasuredWavefront, base, *, samples: int = DEFAULT_SAMPLES, traced=()):
    """`measured_trace` of the base eye ``base``'s ``trace``, its defocus reference taken from ``traced`` (traces
    of the same field and pupil) when one is at ``measured.defocus_wavelength_nm``, else traced here."""
    wanted = measured.defocus_wavelength_nm
    reference = next((t for t in traced if t.wavelength_nm == wanted and t.entrance_pupil_mm == trace.entrance_pupil_mm
                      and t.field_deg == trace.field_deg), None)
    if reference is None:
        reference = trace_eye_wavefront(base, wanted, trace.field_deg, pupil_mm=trace.entrance_pupil_mm,
                                        samples=samples)
    return measured_trace(trace, measured, reference)
