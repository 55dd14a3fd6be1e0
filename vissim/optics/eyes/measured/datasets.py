"""The measured human wavefronts shipped with vissim, loaded into vissim's field convention.

Two datasets (``data/``, converted number for number from ISETBio's MATLAB files, MIT licence in
``data/LICENSE-isetbio.txt``): Zernike coefficients (µm, OSA/ANSI j) over a 4 mm pupil across the visual field.

* ``jaeken-artal-2012``: Jaeken & Artal 2012, IOVS 53:3405. 130 subjects, both eyes, the horizontal meridian
  −40…40° in 1° steps, j = 0–14 (15–20 not measured: zero). NaN where the file has no measurement: the optic
  disc, and spots too distorted to measure (mostly beyond ±30°).
* ``polans-2015``: Polans et al. 2015, Optica 2:124. 10 right eyes, horizontal −40…40° (1°) × vertical −25…25°
  (5°), j = 3–20 (0–2 not given: zero). The file fills the optic disc; its coefficients there are the roughest of
  the meridian (`OPTIC_DISC_X_DEG`), and are refused as the other dataset's missing points are.

**The field rule, once for both datasets**: vissim's field x (the examiner's right, the observer's left) is minus
the data's horizontal angle, and vissim's y (up) is the data's vertical angle. The data's horizontal axis is the
observer's (positive: the observer's right). The evidence, pinned by tests: each dataset's optic disc (its blind
spot lies in the temporal visual field) is at data +12…+17° for right eyes and −17…−15° for left eyes, i.e. at
x < 0 for a right eye (its temporal field is the observer's right) and x > 0 for a left eye; and horizontal and
vertical coma (j = 8, 7) fall with x and y, as every schematic eye's do (Navarro: −0.0117 µm/deg at 4 mm).
ISETBio's comments (the right eye's disc at −18…−10°; Polans's vertical axis the retina's) disagree with the data.
The coefficients of both eyes are in OSA's one frame (x to the examiner's right): a left eye is not mirrored.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import MEASURED_DATASET_NAMES

__all__ = ["UnmeasuredFieldError", "WavefrontDataset", "DATASET_NAMES", "load_dataset", "DATA_DIR", "OPTIC_DISC_X_DEG", "HIGHEST_OSA_J", "measured_eye_words"]

DATA_DIR = Path(__file__).resolve().parent / "data"
#: The highest OSA j either dataset holds.
HIGHEST_OSA_J = 20
#: Polans et al.'s right eyes: the optic disc (vissim x, deg), refused as missing (module doc).
OPTIC_DISC_X_DEG = (-18.0, -10.0)


class UnmeasuredFieldError(VissimInputError):
    """A field an eye was not measured at (the optic disc, a spot too distorted to measure): a population skips
    the eye there, where a single eye refuses it."""


@dataclass(frozen=True)
class _Source:
    file: str
    sha256: str
    arrays: dict  # name -> shape
    citation: str
    label: str  # as a report names it: authors and year


_SOURCES = {
    "jaeken-artal-2012": _Source(
        "jaeken-artal-2012.npz", "0cadea733f7776c071ae5488e3c03ef04faf11aa69bf0dab2b3f0b2614d99781",
        {"zernike_um": (130, 2, 81, 15), "subject": (130,), "eye": (2,), "field_deg": (81,), "osa_j": (15,),
         "pupil_mm": ()},
        "Jaeken B., Artal P. (2012) Invest. Ophthalmol. Vis. Sci. 53(7):3405-3413; via ISETBio (MIT)",
        "Jaeken & Artal 2012"),
    "polans-2015": _Source(
        "polans-2015.npz", "33bafc6bc0d53422fc42f71beb3891f85aed09038dddfc24816a676b7cb72ff3",
        {"zernike_um": (10, 11, 81, 18), "subject": (10,), "vertical_deg": (11,), "horizontal_deg": (81,),
         "osa_j": (18,), "pupil_mm": ()},
        "Polans J., Jaeken B., McNabb R.P., Artal P., Izatt J.A. (2015) Optica 2(2):124-134; via ISETBio (MIT)",
        "Polans et al. 2015"),
}
def measured_eye_words(name: str) -> str:
    """A measured eye's name (``jaeken-artal-2012:17:right``) as a report says it: ``Jaeken & Artal 2012
    subject 17, right eye``; any other name as it is."""
    dataset, _, rest = str(name).partition(":")
    subject, _, side = rest.partition(":")
    if dataset not in _SOURCES or not subject or not side:
        return str(name)
    return f"{_SOURCES[dataset].label} subject {subject}, {side} eye"


#: The datasets' names, as a measured eye's name begins (``jaeken-artal-2012:17:right``).
DATASET_NAMES = MEASURED_DATASET_NAMES  # the light list the command line reads; a test pins it to the files


@dataclass(frozen=True, eq=False)
class WavefrontDataset:
    """One dataset in vissim's field convention (module doc): ``zernike_um[subject, eye, y, x, j]`` (µm, j = 0…
    `HIGHEST_OSA_J`; NaN where not measured) over a ``pupil_mm`` pupil at the fields ``x_deg`` × ``y_deg`` (ascending)."""

    name: str
    citation: str
    subjects: tuple[int, ...]
    eyes: tuple[str, ...]
    x_deg: np.ndarray
    y_deg: np.ndarray
    zernike_um: np.ndarray
    measured_j: tuple[int, ...]
    pupil_mm: float

    def eye_index(self, subject: int, eye: str) -> tuple[int, int]:
        """(subject row, eye column) of ``subject`` (as numbered in the data) and ``eye``; refused when absent."""
        if subject not in self.subjects:
            raise VissimInputError(f"{self.name} has subjects {self.subjects[0]}-{self.subjects[-1]}, got {subject}")
        if eye not in self.eyes:
            raise VissimInputError(f"{self.name} has {' and '.join(self.eyes)} eyes, got {eye!r}")
        return self.subjects.index(subject), self.eyes.index(eye)

    def at_field(self, subject: int, eye: str, field_deg) -> np.ndarray:
        """The coefficients (µm, j = 0…`HIGHEST_OSA_J`) of one eye at ``field_deg`` (x, y; vissim's convention).

        Between measured fields, each coefficient is interpolated linearly along each axis the data samples
        (bilinearly on Polans's grid): the nearest measured fields on either side, weighted by distance. A field
        outside the data, or one whose neighbours were not measured (the optic disc, distorted spots), is refused
        with the nearest measured fields named."""
        row, column = self.eye_index(subject, eye)
        grid = self.zernike_um[row, column]  # y, x, j
        x, y = (float(v) for v in field_deg)
        (xi, xw), (yi, yw) = self._brackets(x, y)
        result = np.zeros(grid.shape[-1])
        for i, wy in zip(yi, yw):
            for k, wx in zip(xi, xw):
                if np.isnan(grid[i, k, 0]):
                    raise UnmeasuredFieldError(f"{self.name} subject {subject} {eye} eye: no measurement at field "
                                           f"{self.x_deg[k]:g},{self.y_deg[i]:g} deg (the optic disc or a spot too "
                                           f"distorted to measure); measured nearby: {self._nearest(grid, x, y)}")
                result += wy * wx * grid[i, k]
        return result

    def check_field(self, field_deg) -> tuple[float, float]:
        """``field_deg`` (x, y), if it lies within the fields the data span (each eye may still miss it); else
        refused, naming the span."""
        x, y = (float(v) for v in field_deg)
        self._brackets(x, y)
        return x, y

    def _brackets(self, x: float, y: float):
        return _bracket(self.x_deg, x, "x", self.name), _bracket(self.y_deg, y, "y", self.name)

    def _nearest(self, grid: np.ndarray, x: float, y: float, count: int = 2) -> str:
        measured = [(abs(self.x_deg[k] - x) + abs(self.y_deg[i] - y), self.x_deg[k], self.y_deg[i])
                    for i in range(len(self.y_deg)) for k in range(len(self.x_deg)) if not np.isnan(grid[i, k, 0])]
        nearest = sorted(measured)[:count]
        return ", ".join(f"{fx:g},{fy:g} deg" for _, fx, fy in nearest) or "none"


def _bracket(axis: np.ndarray, value: float, name: str, dataset: str) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The indices of ``axis`` (ascending) that ``value`` lies between, and their linear weights."""
    if not axis[0] - 1e-9 <= value <= axis[-1] + 1e-9:
        span = f"{axis[0]:g} deg only" if len(axis) == 1 else f"{axis[0]:g} to {axis[-1]:g} deg"
        raise VissimInputError(f"{dataset} was measured at field {name} {span}, got {value:g} deg")
    hit = np.flatnonzero(np.abs(axis - value) <= 1e-9)
    if hit.size:
        return (int(hit[0]),), (1.0,)
    upper = int(np.searchsorted(axis, value))
    lower = upper - 1
    t = (value - axis[lower]) / (axis[upper] - axis[lower])
    return (lower, upper), (1.0 - t, t)


def _verified_arrays(name: str) -> dict:
    source = _SOURCES[name]
    path = DATA_DIR / source.file
    data = path.read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    if digest != source.sha256:
        raise VissimInputError(f"{path}: sha256 {digest} is not the shipped file's {source.sha256}; reinstall vissim")
    with np.load(path, allow_pickle=False) as npz:
        arrays = {key: npz[key] for key in npz.files}
    for key, shape in source.arrays.items():
        if key not in arrays or arrays[key].shape != shape:
            got = arrays[key].shape if key in arrays else "missing"
            raise VissimInputError(f"{path}: array {key!r} should have shape {shape}, got {got}; reinstall vissim")
    return arrays


def _all_j(coefficients: np.ndarray, osa_j: np.ndarray) -> np.ndarray:
    """Coefficients over j = 0…`HIGHEST_OSA_J` (the last axis), zero for the j the data does not hold."""
    full = np.zeros(coefficients.shape[:-1] + (HIGHEST_OSA_J + 1,))
    full[..., osa_j.astype(int)] = coefficients
    missing = np.isnan(coefficients).any(axis=-1)
    full[missing] = np.nan
    return full


def _jaeken_artal(arrays: dict, name: str) -> WavefrontDataset:
    x = -arrays["field_deg"].astype(np.float64)  # the field rule (module doc)
    order = np.argsort(x)
    z = _all_j(arrays["zernike_um"].astype(np.float64), arrays["osa_j"])  # subject, eye, field, j
    z = z[:, :, order][:, :, None]  # subject, eye, y (one), x, j
    return WavefrontDataset(name, _SOURCES[name].citation, tuple(int(s) for s in arrays["subject"]),
                            tuple(str(e) for e in arrays["eye"]), x[order], np.array([0.0]), z,
                            tuple(int(j) for j in arrays["osa_j"]), float(arrays["pupil_mm"]))


def _polans(arrays: dict, name: str) -> WavefrontDataset:
    x, y = -arrays["horizontal_deg"].astype(np.float64), arrays["vertical_deg"].astype(np.float64)
    ox, oy = np.argsort(x), np.argsort(y)
    z = _all_j(arrays["zernike_um"].astype(np.float64), arrays["osa_j"])  # subject, vertical, horizontal, j
    z = z[:, oy][:, :, ox][:, None]  # subject, eye (right), y, x, j
    x = x[ox]
    disc = (x >= OPTIC_DISC_X_DEG[0]) & (x <= OPTIC_DISC_X_DEG[1])
    z[:, :, :, disc] = np.nan
    return WavefrontDataset(name, _SOURCES[name].citation, tuple(int(s) for s in arrays["subject"]), ("right",),
                            x, y[oy], z, tuple(int(j) for j in arrays["osa_j"]), float(arrays["pupil_mm"]))


@functools.lru_cache(maxsize=None)
def load_dataset(name: str) -> WavefrontDataset:
    """The dataset ``name`` (one of `DATASET_NAMES`), its file's sha256 and shapes checked, read once."""
    if name not in _SOURCES:
        raise VissimInputError(f"unknown measured-wavefront dataset {name!r}; known: {', '.join(DATASET_NAMES)}")
    build = _jaeken_artal if name == "jaeken-artal-2012" else _polans
    dataset = build(_verified_arrays(name), name)
    dataset.zernike_um.setflags(write=False)
    return dataset
