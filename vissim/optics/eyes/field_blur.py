"""An image blurred by an `Eye`, its PSF varying over the field (`blur_eye`).

* **Nodes**: a regular grid of image points at most ``field_step_deg`` apart, spanning the image
  (`vissim.optics.blur.field_dependent.node_positions_px`); an image narrower than one step along an axis
  has one node column (or row) at its centre, and an image within one step both ways one PSF at
  its centre (isoplanatic).
* **A node's field angle** = the image centre's field ``field_deg`` (OSA's frame, as ``vissim psf
  --field-deg``: x the examiner's right, y up; default 0,0: the eye fixates the image centre)
  plus the node's visual-angle offset from the centre, per axis. Image offsets (columns to the
  observer's right, rows down: docs/conventions.md) turn into OSA's frame by
  `vissim.units.image_colrow_to_osa_xy`: a node right of the centre is at a smaller x, a node
  above it at a larger y. Field angles beyond ``checks.MAX_FIELD_DEG``, or where the rays miss,
  are refused as the trace refuses them.
* **A node's PSF**: `vissim.optics.eyes.psf_wavefront.eye_spectral_wavefront` (the traced eye at that
  field, at each wavelength of the channel's band, with the light's vergence added over its entrance
  pupil; each wavelength's transverse chromatic aberration relative to the eye's reference
  wavelength), then `compute_psf` at the image's sampling.
* **Between nodes** the PSF is interpolated bilinearly (`vissim.optics.blur.field_dependent`, Nagy &
  O'Leary 1998).
* The image stays in **visual-angle coordinates**: the eye's distortion (the chief ray's retinal
  position against its field angle) is not applied; each PSF is centred on its chief ray.

`DEFAULT_FIELD_STEP_DEG` (2°) was chosen by measurement (``benchmarks/bench_eye_field_step.py``,
2026-12-03): an ETDRS chart tiled over 0-20° at 1 arcmin/px, 4 mm pupil, 555 nm, blurred at node
steps 4, 2, 1 and 0.5°; the PSNR between each step and its half was, Navarro 1985: 44.5, 62.3,
74.1 dB; Escudero-Sanz 1999: 42.9, 61.3, 72.5 dB (largest pixel differences at 2° against 1°:
1.05e-2 and 1.17e-2 of a 0.86 range). 2° is the largest step whose halving stays above 50 dB.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import EYE_RENDER_MAX_THETA_DEG, MAX_FIELD_NODES, finite_number, positive_number, size_text
from vissim.errors import VissimInputError
from vissim.progress import counter
from vissim.optics.blur.convolve import image_kernel_psf, pixel_array
from vissim.optics.eyes.eye import Eye, checked_eye
from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront
from vissim.optics.eyes.traced_wavefront import image_reach_deg, node_field_deg
from vissim.optics.blur.field_dependent import PSFGrid, blur_field_dependent, node_positions_px, psf_grid
from vissim.optics.psf.compute import PSF
from vissim.units import ARCMIN_PER_DEG

__all__ = ["DEFAULT_FIELD_STEP_DEG", "node_field_deg", "eye_psf_grid", "eye_psf_grids", "blur_eye"]

#: The default spacing of the PSF nodes, degrees of visual angle (measured: module doc).
DEFAULT_FIELD_STEP_DEG = 2.0


def _band(wavelength_nm, weights) -> tuple[tuple[float, ...], tuple[float, ...] | None]:
    """A channel's wavelengths (nm) and weights: one wavelength, or a band of several (weights default equal)."""
    try:
        band = tuple(positive_number(w, "wavelength", "nm") for w in np.atleast_1d(wavelength_nm))
    except TypeError:
        raise VissimInputError(f"a channel's wavelength must be nm or a list of nm, got {wavelength_nm!r}") from None
    if weights is not None and len(np.atleast_1d(weights)) != len(band):
        raise VissimInputError(f"need one weight per wavelength, got {weights!r} for {band} nm")
    return band, None if weights is None else tuple(float(w) for w in np.atleast_1d(weights))


def eye_psf_grid(shape: tuple[int, int], eye: Eye, *, arcmin_per_px: float, wavelength_nm=None, weights=None,
                 vergence_diopters=0.0, field_deg=(0.0, 0.0), field_step_deg: float | None = None,
                 mode: str = "wave", progress=None) -> PSFGrid:
    """The `Eye` ``eye``'s PSFs at the nodes over an image of ``shape`` (rows, cols) (module doc).

    ``wavelength_nm``: one wavelength (default the eye's reference wavelength), or a band of several
    weighted by ``weights`` (default equal): each node's eye is traced at each (`eye_spectral_wavefront`,
    its transverse chromatic aberration relative to the eye's reference wavelength, as for one
    wavelength). Each PSF's field is cut to twice the image's longer side plus one (no pixel sees farther).
    ``progress(stage, done, total)`` (`vissim.progress`) after each node's PSF.
    """
    eye = checked_eye(eye, "eye_psf_grid")
    step = check_arcmin_per_px(arcmin_per_px, "the image's arcmin_per_px")
    spacing_deg = DEFAULT_FIELD_STEP_DEG if field_step_deg is None else positive_number(
        field_step_deg, "field step", "degrees")
    centre = tuple(finite_number(v, "field angle", "deg") for v in field_deg)
    if len(centre) != 2:
        raise VissimInputError(f"the field angle must be two angles (x, y) in degrees, got {field_deg!r}")
    band, band_weights = _band(eye.reference_wavelength_nm if wavelength_nm is None else wavelength_nm, weights)
    _check_image_field(shape, step, centre, eye)

    spacing_px = spacing_deg * ARCMIN_PER_DEG / step
    if field_step_deg is None:  # the default step over pixels coarser than it: a node at each pixel at most
        spacing_px = max(spacing_px, 1.0)
    nodes = _check_nodes(shape, spacing_px, spacing_deg, step)
    advance = counter(progress, "field PSFs", nodes)

    def psf_at(row_px: float, col_px: float) -> PSF:
        front = eye_spectral_wavefront(eye, wavelengths_nm=band, vergence_diopters=vergence_diopters,
                                       field_deg=node_field_deg(row_px, col_px, shape, step, centre))
        psf = image_kernel_psf(front, shape, arcmin_per_px=step, wavelength_nm=band, weights=band_weights, mode=mode)
        advance()
        return psf

    return psf_grid(shape, spacing_px, psf_at)


def _check_image_field(shape: tuple[int, int], arcmin_per_px: float, centre, eye: Eye) -> None:
    """The image within `EYE_RENDER_MAX_THETA_DEG` of the eye's optical axis (`image_reach_deg`: as far as an eye's
    image is rendered), refused before any PSF."""
    widest = image_reach_deg(eye.schematic, shape[:2], arcmin_per_px, centre)
    if widest > EYE_RENDER_MAX_THETA_DEG:
        raise VissimInputError(f"the image reaches {widest:.4g} deg from the eye's optical axis ({size_text(shape[:2])} at "
                               f"{arcmin_per_px:g} arcmin/px about the field angle ({centre[0]:g}, {centre[1]:g}) deg), "
                               f"beyond the {EYE_RENDER_MAX_THETA_DEG:g} deg an eye's image is simulated and rendered "
                               "to: crop it, or give its true (finer) sampling")


def _check_nodes(shape: tuple[int, int], spacing_px: float, spacing_deg: float, arcmin_per_px: float) -> int:
    """The number of PSF nodes; refused, before any PSF, for a node step finer than a pixel (nodes closer than the
    pixels they blend) or one that would need more than `MAX_FIELD_NODES` PSFs."""
    pixel_deg = arcmin_per_px / ARCMIN_PER_DEG
    if spacing_px < 1.0:
        raise VissimInputError(f"field step {spacing_deg:g} deg is finer than the image's pixels ({pixel_deg:.4g} deg "
                               f"at {arcmin_per_px:g} arcmin/px): give at least {pixel_deg:.4g} deg")
    nodes = len(node_positions_px(shape[0], spacing_px)) * len(node_positions_px(shape[1], spacing_px))
    if nodes > MAX_FIELD_NODES:
        span_deg = max(shape) * pixel_deg
        least = span_deg / (math.isqrt(MAX_FIELD_NODES) - 1)
        raise VissimInputError(f"field step {spacing_deg:g} deg needs {nodes} PSF nodes over the {size_text(shape)} "
                               f"image (at most {MAX_FIELD_NODES}, each a trace and a PSF): give a step of at least "
                               f"{least:.3g} deg")
    return nodes


def eye_psf_grids(shape: tuple[int, int], eye: Eye, channels_nm: Sequence, channel_weights=None,
                  **options) -> list[PSFGrid]:
    """One `eye_psf_grid` of ``eye`` per channel (each distinct band computed once): ``channels_nm[c]`` is
    channel ``c``'s wavelength or band, ``channel_weights[c]`` its band's weights (None: equal); ``options``:
    the other keywords of `eye_psf_grid`."""
    weights = [None] * len(channels_nm) if channel_weights is None else list(channel_weights)
    if len(weights) != len(channels_nm):
        raise VissimInputError(f"got {len(weights)} weight lists for {len(channels_nm)} channels")
    bands = [_band(w, k) for w, k in zip(channels_nm, weights)]
    grids: dict = {}
    for band in bands:
        if band not in grids:
            grids[band] = eye_psf_grid(shape, eye, wavelength_nm=band[0], weights=band[1], **options)
    return [grids[band] for band in bands]


def blur_eye(image: np.ndarray, eye: Eye, *, arcmin_per_px: float, wavelength_nm: float | Sequence | None = None,
             weights: Sequence | None = None, vergence_diopters=0.0, field_deg=(0.0, 0.0),
             field_step_deg: float | None = None, mode: str = "wave", padding: str = "constant", background=None,
             dtype=np.float32) -> np.ndarray:
    """Blur a linear-light image as the `Eye` ``eye`` sees it, the PSF varying over the field.

    Parameters
    ----------
    image : ndarray of shape (H, W) or (H, W, C)
        Linear light, ``[row, col]``, at ``arcmin_per_px`` (visual angle; the eye's distortion is
        not applied).
    eye : Eye
        The eye (`vissim.build_eye`): its model, accommodation, pupil and the prescription it has.
    wavelength_nm : float or sequence, optional
        One wavelength for every channel (default: the eye's reference wavelength), or one entry per
        channel: a wavelength, or a band (a sequence of wavelengths); each is traced (the eye's own
        dispersion, its transverse chromatic aberration relative to the eye's reference wavelength).
    weights : sequence, optional
        Per channel, its band's relative weights (None: equal).
    vergence_diopters : float or 2 x 2, optional
        The light's vergence at the entrance pupil, D (default 0: a distant object; −1/d for one d
        metres away; lenses in front add their power), as `vissim.eye_wavefront`.
    field_deg : (x, y) degrees
        The field angle of the image centre, OSA's frame (default (0, 0): fixation at the centre).
    field_step_deg : float, optional
        The PSF nodes' spacing, degrees (default `DEFAULT_FIELD_STEP_DEG`).
    mode : {"wave", "geometric"}
        The PSFs' optics, as `vissim.compute_psf`.
    padding : {"constant", "edge", "reflect", "wrap"}
        Outside the image, as `vissim.blur_image`.
    background : float or per-channel floats, optional
        The value outside for ``"constant"`` (default: the mean of the border pixels).
    dtype : float32 (default) or float64

    Returns
    -------
    ndarray, the shape of ``image``, ``dtype``.

    Examples
    --------
    >>> import numpy as np, vissim
    >>> image = np.zeros((41, 41)); image[20, 20] = 1.0
    >>> eye = vissim.build_eye("navarro-1985", pupil_diameter_mm=3.0)
    >>> blurred = vissim.blur_eye(image, eye, arcmin_per_px=1.0, wavelength_nm=555.0, background=0.0)
    >>> round(float(blurred.sum()), 4)
    1.0
    """
    eye = checked_eye(eye, "blur_eye")
    array = pixel_array(image)
    n_channels = array.shape[2] if array.ndim == 3 else 1
    wavelength_nm = eye.reference_wavelength_nm if wavelength_nm is None else wavelength_nm
    per_channel = [wavelength_nm] * n_channels if np.ndim(wavelength_nm) == 0 else list(wavelength_nm)
    if len(per_channel) != n_channels:
        raise VissimInputError(f"got {len(per_channel)} wavelengths for an image with {n_channels} channels")
    grids = eye_psf_grids(array.shape[:2], eye, per_channel, weights, arcmin_per_px=arcmin_per_px,
                          vergence_diopters=vergence_diopters, field_deg=field_deg, field_step_deg=field_step_deg,
                          mode=mode)
    return blur_field_dependent(array, grids if array.ndim == 3 else grids[0], arcmin_per_px=arcmin_per_px,
                                padding=padding, background=background, dtype=dtype)
