"""The forward model a prescription fit evaluates: a sharp reference blurred, magnified, shifted.

The capture is modelled as ``gain * (PSF_M * R shifted) o M^-1 + offset``: the reference R
(a pixel-integrated image at the capture's sampling: the no-lens render or capture, or the
chart) blurred by the PSF of the defocus matrix D (dioptres, TABO x/y frame, positive for a
myopic camera) and shifted by a sub-pixel translation, then magnified by the spectacle
magnification matrix M about the tile's centre (the optical axis, as
`vissim.optics.blur.resample.magnify`).  Gain and offset are solved in closed form by the fit.

**The shift is a phase ramp** on the transfer function, not a spline: a spline resampling of
the sharp, under-sampled reference attenuates its highest frequencies by up to ~30 % at half a
pixel, which the fit would read as defocus (measured: 0.09 D of spurious power on a no-lens
capture shifted by 0.3 px); the ramp changes no amplitude.

**Blur before magnification.**  ``PSF * (R o M^-1) = (PSF_M * R) o M^-1`` with
``PSF_M(v) = |M| PSF(M v)``: blurring first and magnifying the blurred, well-sampled result
avoids resampling an under-sampled sharp reference (the README's "magnifying, shifting or
filtering an under-sampled image can't be done exactly").  For a second-order wavefront the
scaled PSF is the PSF of the landing matrix ``M^-1 D``: exact in geometric optics; in wave
optics the 1-2 % ellipticity it gives the Airy core is neglected.

**Kernels.**  The reference already carries its pixel's integral (it is a render or a
pixel-integrated chart), so the kernel is the *point* PSF, not a second pixel integral:

* ``geometric``: the ray-optics PSF of ``W = -P r^2/2`` over a circular pupil of radius R is
  the pupil mapped linearly by the landing matrix A (arcmin per mm of pupil): uniform over an
  ellipse.  Its transfer function is analytic, ``2 J1(2 pi R |A^T f|) / (2 pi R |A^T f|)``, and
  smooth in the parameters, which is what a least-squares Jacobian needs.  Checked against the
  ray histogram of `vissim.optics.psf.compute.compute_psf` in ``tests/fit/test_forward.py``.
* ``wave``: `vissim.optics.psf.compute.compute_psf` (``pixel="sample"``), whose DFT is the OTF.

The reference is edge-padded by a margin that holds the largest blur allowed
(``max_power_diopters``), on the grid `vissim.optics.blur.convolve.padded_shape` gives that widest
kernel, and transformed once; each evaluation is one transfer function, one
inverse FFT and one cubic-spline resampling (`scipy.ndimage.affine_transform`).  The
blurred spectrum (reference x transfer) is cached by the optics (defocus, magnification, pupil),
so the Jacobian's steps in the shift alone reuse it and pay only the ramp and the inverse FFT.
Orientation: image (col, row) = (-x, -y) of the TABO/OSA frame
(`vissim.units.osa_xy_to_image_colrow`), so a 2 x 2 matrix in the x/y frame is the same
matrix in (col, row) and is reordered for (row, col).
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.blur.convolve import kernel_transfer, padded_shape, padding_width_px
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import mrad_to_arcmin, xy_matrix_to_image_rowcol

scipy_fft = lazy_module("scipy.fft")
scipy_ndimage = lazy_module("scipy.ndimage")
scipy_special = lazy_module("scipy.special")

__all__ = ["ForwardModel", "FORWARD_MODES", "landing_matrix_rc_px"]

FORWARD_MODES = ("geometric", "wave")
#: Extra margin around the largest blur radius, px (the wave PSF's Airy tail, the shift).
MARGIN_EXTRA_PX = 12
#: Blurred spectra kept per model, by optics: a Jacobian's base point outlives its 3-4 power steps.
SPECTRUM_CACHE_ENTRIES = 8


def landing_matrix_rc_px(defocus_xy, magnification_xy, arcmin_per_px: float) -> np.ndarray:
    """Pixels of landing offset per mm of pupil, (row, col), of the magnification-scaled PSF: M^-1 D."""
    d = np.asarray(defocus_xy, dtype=float)
    m_inv = np.linalg.inv(np.asarray(magnification_xy, dtype=float))
    scaled = m_inv @ d
    return xy_matrix_to_image_rowcol(0.5 * (scaled + scaled.T)) * float(mrad_to_arcmin(1.0)) / arcmin_per_px


#: The jinc 2 J1(x) / x tabulated (step `_JINC_STEP`), interpolated linearly: 20x faster than
#: `scipy.special.j1` on a transfer-function grid, within 2e-7 of it.
_JINC_STEP = 1e-3
_JINC_TABLE = np.empty(0)


def _jinc(x: np.ndarray) -> np.ndarray:
    global _JINC_TABLE
    top = float(x.max()) if x.size else 0.0
    if top >= (_JINC_TABLE.size - 2) * _JINC_STEP:
        grid = np.arange(int(top / _JINC_STEP * 1.25) + 1024) * _JINC_STEP
        table = np.ones_like(grid)
        table[1:] = 2.0 * scipy_special.j1(grid[1:]) / grid[1:]
        _JINC_TABLE = table
    position = x * (1.0 / _JINC_STEP)
    index = position.astype(np.intp)
    fraction = position - index
    low = _JINC_TABLE[index]
    return low + fraction * (_JINC_TABLE[index + 1] - low)


class ForwardModel:
    """The reference, padded and transformed once, and the model image for given optics.

    Parameters
    ----------
    reference : ndarray (H, W)
        Linear light, pixel-integrated, at ``arcmin_per_px``.
    pupil_diameter_mm
        The camera's entrance pupil, mm.
    wavelength_nm
        The wavelength (wave mode), nm.
    mode
        ``"geometric"`` or ``"wave"``.
    max_power_diopters
        The largest principal defocus the model is asked for; sets the padding.
    """

    def __init__(self, reference: np.ndarray, arcmin_per_px: float, pupil_diameter_mm: float, *,
                 mode: str = "geometric", wavelength_nm: float = DEFAULT_WAVELENGTH_NM, max_power_diopters: float = 10.0,
                 max_shift_px: float = 10.0) -> None:
        if mode not in FORWARD_MODES:
            raise VissimInputError(f"fit mode must be one of {', '.join(FORWARD_MODES)}, got {mode!r}")
        self.reference = np.asarray(reference, dtype=np.float64)
        self.shape = self.reference.shape
        self.arcmin_per_px = float(arcmin_per_px)
        self.pupil_diameter_mm = float(pupil_diameter_mm)
        self.mode = mode
        self.wavelength_nm = float(wavelength_nm)
        self.max_power_diopters = float(max_power_diopters)
        blur_radius_px = mrad_to_arcmin(self.max_power_diopters * self.pupil_diameter_mm / 2.0) / self.arcmin_per_px
        # the widest kernel the model applies (blur, shift, Airy tail): odd, its reach the margin
        self.kernel_px = 2 * (int(math.ceil(blur_radius_px + max_shift_px)) + MARGIN_EXTRA_PX) - 1
        self.margin_px = padding_width_px(self.kernel_px)
        self.padded_shape = padded_shape(self.shape, self.kernel_px)
        extra = (self.padded_shape[0] - self.shape[0] - 2 * self.margin_px,
                 self.padded_shape[1] - self.shape[1] - 2 * self.margin_px)
        padded = np.pad(self.reference, ((self.margin_px, self.margin_px + extra[0]),
                                         (self.margin_px, self.margin_px + extra[1])), mode="edge")
        # the blurred image is resampled from a window this much larger than the tile on each side
        # (the shift, up to 10 % magnification at the tile's corners, the spline's reach)
        self.window_px = int(math.ceil(max_shift_px + 0.05 * max(self.shape) + 4))
        self._reference_fft = scipy_fft.rfft2(padded, workers=-1)
        fr = scipy_fft.fftfreq(padded.shape[0])[:, None]
        fc = scipy_fft.rfftfreq(padded.shape[1])[None, :]
        self._freq = (fr, fc)
        self.centre_rc = (np.array(self.shape, dtype=float) - 1.0) / 2.0
        self._spectra: OrderedDict[bytes, np.ndarray] = OrderedDict()

    # -- kernels -------------------------------------------------------------------------
    def _geometric_transfer(self, landing_rc: np.ndarray, pupil_diameter_mm: float) -> np.ndarray:
        fr, fc = self._freq
        radius = pupil_diameter_mm / 2.0
        # |A^T f| with A in px/mm, f in cycles/px: cycles per mm of pupil.
        u = landing_rc[0, 0] * fr + landing_rc[1, 0] * fc
        v = landing_rc[0, 1] * fr + landing_rc[1, 1] * fc
        return _jinc(2.0 * math.pi * radius * np.sqrt(u * u + v * v))

    def _wave_transfer(self, defocus_xy: np.ndarray, magnification_xy, pupil_diameter_mm: float) -> np.ndarray:
        m_inv = np.linalg.inv(np.asarray(magnification_xy, dtype=float))
        scaled = m_inv @ np.asarray(defocus_xy, dtype=float)
        rx = Prescription.from_power_matrix(-0.5 * (scaled + scaled.T))
        front = Wavefront.from_prescription(rx, pupil_diameter_mm)
        size = suggested_size_px(front, self.arcmin_per_px, wavelength_nm=self.wavelength_nm)
        size = min(size, self.kernel_px)
        psf = compute_psf(front, wavelength_nm=self.wavelength_nm, arcmin_per_px=self.arcmin_per_px, size_px=size,
                          mode="wave", pixel="sample", dtype=np.float64)  # differentiated numerically
        return kernel_transfer(np.asarray(psf.data, dtype=np.float64), self.padded_shape, np.float64)

    # -- the model -----------------------------------------------------------------------
    def _blurred_spectrum(self, defocus_xy, magnification_xy, pupil_diameter_mm: float) -> np.ndarray:
        """The reference's spectrum times the optics' transfer, cached by the optics (not the shift)."""
        defocus = np.asarray(defocus_xy, dtype=np.float64)
        magnification = np.asarray(magnification_xy, dtype=np.float64)
        key = defocus.tobytes() + magnification.tobytes() + np.float64(pupil_diameter_mm).tobytes()
        spectrum = self._spectra.get(key)
        if spectrum is not None:
            self._spectra.move_to_end(key)
            return spectrum
        if self.mode == "geometric":
            landing = landing_matrix_rc_px(defocus, magnification, self.arcmin_per_px)
            transfer = self._geometric_transfer(landing, pupil_diameter_mm)
        else:
            transfer = self._wave_transfer(defocus, magnification, pupil_diameter_mm)
        spectrum = self._reference_fft * transfer
        self._spectra[key] = spectrum
        if len(self._spectra) > SPECTRUM_CACHE_ENTRIES:
            self._spectra.popitem(last=False)
        return spectrum

    def blurred(self, defocus_xy, magnification_xy, pupil_diameter_mm: float | None = None,
                shift_rc=(0.0, 0.0)) -> np.ndarray:
        """The padded reference blurred by the magnification-scaled PSF and shifted (before magnifying)."""
        pupil = self.pupil_diameter_mm if pupil_diameter_mm is None else float(pupil_diameter_mm)
        spectrum = self._blurred_spectrum(defocus_xy, magnification_xy, pupil)
        fr, fc = self._freq
        # the ramp is separable: two 1-D exponentials, not one over the grid
        ramp_rows = np.exp(-2j * math.pi * float(shift_rc[0]) * fr)
        ramp_cols = np.exp(-2j * math.pi * float(shift_rc[1]) * fc)
        return scipy_fft.irfft2(spectrum * ramp_rows * ramp_cols, s=self.padded_shape, workers=-1)

    def predict(self, defocus_xy, magnification_xy=((1.0, 0.0), (0.0, 1.0)), shift_rc=(0.0, 0.0),
                pupil_diameter_mm: float | None = None) -> np.ndarray:
        """The model image (H, W): blurred, content moved by ``shift_rc`` px, magnified about the tile's centre."""
        start = self.margin_px - self.window_px
        window = self.blurred(defocus_xy, magnification_xy, pupil_diameter_mm, shift_rc)[
            start:start + self.shape[0] + 2 * self.window_px, start:start + self.shape[1] + 2 * self.window_px]
        magnification = np.asarray(magnification_xy, dtype=float)
        if np.array_equal(magnification, np.eye(2)):
            return window[self.window_px:self.window_px + self.shape[0], self.window_px:self.window_px + self.shape[1]]
        m_inv = np.linalg.inv(xy_matrix_to_image_rowcol(magnification))
        c = self.centre_rc
        offset = self.window_px + c - m_inv @ c
        return scipy_ndimage.affine_transform(window, m_inv, offset=offset, output_shape=self.shape, order=3,
                                              mode="nearest", prefilter=True)
