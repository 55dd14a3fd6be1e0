"""Depth-dependent blur: one eye, one accommodation state, a scene with a depth map.

Defocus per depth (derivation in :mod:`vissim.optics.accommodation`).  An object ``d`` metres away
has *proximity* ``L = 1/d`` dioptres (``L = 0`` for sky at infinity).  An eye whose correcting
lens is ``Rx`` (myope negative), exerting accommodation ``A``, is corrected *for that object*
by the lens::

    effective prescription = Rx + (L - A) on the sphere      (cylinder, axis unchanged)

so an uncorrected -2.00 DS myope with ``A = 0`` needs ``-2 + 2 = 0`` for 0.5 m (sharp) and
``-2 + 1/6 = -1.83`` D for 6 m (blurred like a -1.83 D myope: a disc of pupil x 1.83 mrad).
Astigmatism and any higher-order terms (``extra_wavefront``) ride along unchanged at every
depth; only the defocus term changes.

Layers.  Pixels are sorted into layers by proximity.  Neighbouring layers' geometric blur
discs differ in diameter by ``p dL`` radians (``p`` the pupil in metres), so a spacing
``dL <= fraction * theta / p`` (``theta`` the pixel angle in radians) keeps that step below
``fraction`` of a pixel (Barsky et al. 2005, discretisation).  The layers span the scene's
proximities evenly, with one extra layer exactly at the in-focus proximity (``A - M``, ``M``
the spherical equivalent) so that what the eye focuses on gets exactly its in-focus PSF; the
count is ``ceil(range / dL) + 1`` (+1 for the anchor): linear in the dioptric range.

Matting: each pixel is split *linearly in dioptres* between its two neighbouring layers (tent
weights ``alpha_k`` summing to 1), so slanted surfaces show no bands.

Compositing.  Back-to-front *over* of every layer on the next (Barsky 2004) treats the bands
of one slanted surface as occluding each other: at each band edge it mixes in
``a (1 - a) (c1 - c0)`` of the wrong colour, an error that grows, not shrinks, with more
layers (measured: 5 % of the range between spacing fractions 0.5 and 0.25 on a white-noise
ramp, 7 % between 0.25 and 0.125).  In ray optics the occlusion of far light by
near content vanishes as their defocus becomes equal and equals the over operator when either
is in focus.  So nearer content occludes layer ``k`` with weight ``w`` rising from 0 to 1 as
their blur discs differ by 1x to 2x ``occlusion_threshold_px``; closer in depth they add::

    T_k = clip(1 - sum_j w_jk B_j(A_j), 0, 1)
    out = sum_k T_k B_k(P_k) / sum_k T_k B_k(A_k)

``B_k`` is the blur with layer ``k``'s PSF, ``P_k, A_k`` its premultiplied colour and coverage
*extended* behind its occluders by pull-push interpolation (Gortler et al. 1996) of its own
colour and coverage, as in Kraus & Strengert (2007): a near panel's blurred edge is partly
transparent and shows the background's continuation (and a layer's continuation occludes
what lies behind it).  Exact limits (pinned in
``tests/test_depth.py``): a constant depth gives the single-PSF blur; delta PSFs give the
input; a bright near panel over black gives its own blur only; a black near panel over a
uniform background of 1 gives ``1 - B_near(mask)`` (no halo, no dark fringe) whichever is in
focus; every output is a weighted mean of (extended) input colours.

Cost: per non-empty layer one PSF (cached by wavefront; for an eye whose wavefront is defocus
alone the symmetric plan pairs layers of opposite defocus, whose PSFs are point reflections of
each other, so about half are computed), one pull-push and one batched convolution of
(colours, extended coverage) (one real FFT pair, :func:`vissim.optics.blur_device.convolve_padded`;
blur.py's overlap-save squares measured no faster on these windows), on the layer's *window*: the box of its tent matte grown by ``2 (r_k + r_max)`` pixels (``r`` the
PSF's half-width + 1, ``r_max`` the widest layer's).  A layer's blur reaches ``r_k`` beyond its matte, its continuation behind nearer content matters where that
content's blur (``r_max``) lets it show, and both spread once more through partly occluding
neighbours.  The continuation itself is estimated by pull-push on the window grown by another
:data:`EXTENSION_HALO_PX` (64) pixels, whose coarse levels then see the neighbourhood the whole
frame would give them: the depth campaign's RGB-D results equal the full-frame estimate's
(same dB to 0.1), and on the 1080p frame of ``benchmarks/bench_depth.py`` the two differ by
60 dB PSNR (max 0.05 of the range, at panel edges).  On such a frame, whose layers are bands of
a floor, each window is a few per cent of the frame.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import finite_number, positive_number
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError
from vissim.optics.array_backend import CPU as CPU_BACKEND
from vissim.optics.array_backend import ArrayBackend, array_backend, array_module
from vissim.optics.blur import pad_array, padded_shape, padding_width_px
from vissim.optics.blur_device import convolve_padded
from vissim.optics.prescription import Prescription, as_prescription
from vissim.optics.psf import PSF, compute_psf, geometric_blur_radius_arcmin, suggested_size_px
from vissim.optics.pullpush import pull_push, upsample2
from vissim.optics.threads import available_cores, single_threaded_blas
from vissim.optics.wavefront import Wavefront
from vissim.progress import Progress
from vissim.units import arcmin_to_rad

__all__ = ["DepthBlurResult", "DepthLayer", "LayerPlan", "blur_depth", "depth_to_proximity_diopters",
           "layer_spacing_diopters", "plan_layers"]

log = logging.getLogger(__name__)

#: Pixels by which a layer's continuation behind nearer content is estimated beyond its window.
EXTENSION_HALO_PX = 64
#: A blur diameter (px) from which a layer may go on the coarse grid, and the PSNR (dB, unit range)
#: of its coarse blur against the fine one on white noise there (``tests/test_depth.py``).
COARSE_BLUR_PX = 14.0
COARSE_MIN_DB = 44.0
#: Plans with more layers are refused unless ``max_layers`` is raised (or None: no limit).
DEFAULT_MAX_LAYERS = 256
DEPTH_PADDING_MODES = ("edge", "reflect")


# -- the optics of one depth ------------------------------------------------------------
def layer_spacing_diopters(arcmin_per_px: float, pupil_diameter_mm: float, fraction: float = 0.5) -> float:
    """Largest layer spacing in proximity: ``fraction * theta / p`` (theta rad/px, p metres)."""
    theta_rad = float(arcmin_to_rad(check_arcmin_per_px(arcmin_per_px)))
    pupil_m = check_pupil_mm(pupil_diameter_mm) * 1e-3
    return positive_number(fraction, "layer spacing fraction", "pixels") * theta_rad / pupil_m


@dataclass(frozen=True)
class LayerPlan:
    """Layer proximities (dioptres, far to near), each gap <= ``max_spacing_diopters``."""

    proximities_diopters: tuple[float, ...]
    max_spacing_diopters: float

    @property
    def n_layers(self) -> int:
        return len(self.proximities_diopters)


def plan_layers(
    min_proximity_diopters: float,
    max_proximity_diopters: float,
    max_spacing_diopters: float,
    max_layers: int | None = DEFAULT_MAX_LAYERS,
    *,
    anchor_diopters: float | None = None,
    symmetric: bool = False,
) -> LayerPlan:
    """Layers covering ``[min, max]`` with gaps <= ``max_spacing_diopters``; ends (and ``anchor_diopters``) exact.

    The anchor is the in-focus proximity: it gets a layer of its own, so whatever the eye
    focuses on is rendered with exactly its in-focus PSF.  Each side of it is spaced evenly.
    The count is ``ceil(range / spacing) + 1`` (+1 with an anchor inside the range).

    ``symmetric``: with an anchor inside the range, step by exactly ``max_spacing_diopters`` from
    it both ways, and end at the range's ends (at most one layer more per side), so layers
    pair up at equal and opposite defocus: for an eye whose wavefront is defocus alone their
    PSFs are point reflections of each other (one computed PSF serves both, :func:`blur_depth`).
    """
    low, high = float(min_proximity_diopters), float(max_proximity_diopters)
    if high < low:
        raise VissimInputError(f"proximity range is reversed: {low:g} D to {high:g} D")
    inside = anchor_diopters is not None and low < anchor_diopters < high
    knots = [low, float(anchor_diopters), high] if inside else [low, high]
    if symmetric and inside:
        a, step = float(anchor_diopters), float(max_spacing_diopters)
        below, above = (int(math.ceil(span / step - 1e-9)) - 1 for span in (a - low, high - a))
        grid = a + step * np.arange(-below, above + 1)
        values = [low] + [v for v in grid if low < v < high] + [high]
    else:
        values = [low]
        for a, b in zip(knots[:-1], knots[1:]):
            n = int(math.ceil((b - a) / max_spacing_diopters - 1e-9))
            values.extend(a + (b - a) * np.arange(1, n + 1) / n)
    n_layers = len(values)
    if max_layers is not None and n_layers > max_layers:
        near, far = (("infinity" if d == 0 else f"{1.0 / d:.3g} m") for d in (high, low))
        raise VissimInputError(
            f"the scene spans {low:.3g} to {high:.3g} D of proximity ({near} to {far}), which needs "
            f"{n_layers} layers at <= {max_spacing_diopters:.3g} D spacing (max_layers={max_layers}); check that the depth "
            "is in metres, or raise max_layers (--max-layers) or the layer spacing fraction"
        )
    return LayerPlan(tuple(float(v) for v in values), float(max_spacing_diopters))


def depth_to_proximity_diopters(depth_m) -> np.ndarray:
    """``1/depth`` (float64) for a depth map in metres; ``inf`` (sky) gives 0."""
    depth = np.asarray(depth_m, dtype=np.float64)
    if depth.ndim != 2 or min(depth.shape) < 1:
        raise VissimInputError(f"depth map must have shape (H, W) in metres, got {depth.shape}")
    bad = ~((depth > 0) & (np.isfinite(depth) | (depth == np.inf)))
    if bad.any():
        example = depth[bad].flat[0]
        raise VissimInputError(
            f"depth map has {int(bad.sum())} pixels that are not positive metres (e.g. {float(example):g} m; "
            "NaN, 0 and negative depths are refused, inf means sky); fill holes first"
        )
    with np.errstate(divide="ignore"):
        return 1.0 / depth


@dataclass(frozen=True)
class DepthLayer:
    """One blurred layer: where it sits, what the eye needs there, and its PSF."""

    index: int
    proximity_diopters: float
    defocus_sphere_diopters: float  # effective prescription sphere Rx_S + L - A
    blur_diameter_arcmin: float  # geometric, largest ray deviation x 2
    psf_size_px: int
    coverage_fraction: float  # sum of this layer's matte over the image / pixel count

    @property
    def distance_m(self) -> float:
        return math.inf if self.proximity_diopters <= 0 else 1.0 / self.proximity_diopters


@dataclass(frozen=True, eq=False)
class DepthBlurResult:
    """The blurred image (float32) and how it was made."""

    image: np.ndarray
    layers: tuple[DepthLayer, ...]  # the non-empty layers, far to near
    n_layers: int  # layers of the plan, empty ones included
    max_layer_spacing_diopters: float
    occlusion_threshold_diopters: float
    accommodation_diopters: float
    in_focus_proximity_diopters: float  # the anchor layer: Rx and accommodation give zero defocus here
    padded_shape: tuple[int, int]

    def as_json(self) -> dict:
        out = {"n_layers": self.n_layers, "n_blurred_layers": len(self.layers)}
        out |= {f.name: getattr(self, f.name) for f in dataclasses.fields(self)[3:]}  # the plan's numbers
        out["padded_shape"] = list(self.padded_shape)
        out["layers"] = [{k: v for k, v in dataclasses.asdict(la).items() if k != "index"} for la in self.layers]
        return out


# -- validation helpers ---------------------------------------------------------------
def _check_accommodation(accommodation_diopters) -> float:
    value = finite_number(accommodation_diopters, "accommodation", "dioptres")
    if value < 0:
        raise VissimInputError(f"accommodation exerted must be >= 0 dioptres, got {accommodation_diopters!r} D")
    return value


def _base_wavefront(eye_rx: Prescription, pupil_mm: float, extra: Wavefront | None) -> Wavefront:
    front = Wavefront.from_prescription(eye_rx, pupil_mm)
    if extra is None:
        return front
    if not isinstance(extra, Wavefront):
        raise TypeError(f"extra_wavefront must be a Wavefront, got {type(extra).__name__}")
    if extra.pupil_diameter_mm < pupil_mm * (1 - 1e-12):
        raise VissimInputError(
            f"extra_wavefront is measured over {extra.pupil_diameter_mm:g} mm, smaller than the {pupil_mm:g} mm pupil"
        )
    return front + extra.rescaled(pupil_mm)


@functools.lru_cache(maxsize=128)
def _cached_psf(items: tuple, pupil_mm: float, wavelength_nm: float, step: float, mode: str,
                size_px: int | None = None) -> PSF:
    """The PSF of one layer's wavefront (cached by wavefront), on a field that holds its blur or of ``size_px``
    (a coarse grid's, the fine field's arcmin; refused if it cannot hold it)."""
    front = Wavefront(dict(items), pupil_mm)
    size = size_px or suggested_size_px(front, step, pupil_diameter_mm=pupil_mm, wavelength_nm=wavelength_nm)
    return compute_psf(front, pupil_diameter_mm=pupil_mm, wavelength_nm=wavelength_nm, arcmin_per_px=step, size_px=size, mode=mode)


def _wavefront_key(coefficients: dict, sign: float = 1.0) -> tuple:
    return tuple(sorted((k, round(sign * v, 12)) for k, v in coefficients.items() if round(v, 12) != 0.0))


def _layer_psf(front: Wavefront, pupil_mm: float, wavelength_nm: float, step: float, mode: str, seen: dict,
               size_px: int | None = None) -> PSF:
    """A layer's PSF; the point reflection of an already computed one when its wavefront is that one's negative.

    ``|F(P e^{-ikW})(x)|^2 = |F(P e^{ikW})(-x)|^2``, and the geometric PSF's rays land at
    ``-grad W``: both PSFs of ``-W`` are those of ``W`` reflected through the origin (to round-off;
    odd sizes only, whose origin ``[N//2, N//2]`` is the centre).  For an eye whose wavefront is
    defocus alone, the symmetric layer plan pairs every layer with one of opposite defocus.
    """
    key = _wavefront_key(front.coefficients_um)
    mirror = None if size_px is not None or key in seen else seen.get(_wavefront_key(front.coefficients_um, -1.0))
    if mirror is not None and mirror.data.shape[0] % 2 == 1:
        psf = _reflected(mirror, front)
    else:
        psf = _cached_psf(tuple(front.coefficients_um.items()), pupil_mm, wavelength_nm, step, mode, size_px)
    seen[key] = psf
    return psf


def _reflected(psf: PSF, front: Wavefront) -> PSF:
    """``psf`` reflected through its centre, as the PSF of ``front`` (the negative of its wavefront)."""
    data = np.ascontiguousarray(psf.data[::-1, ::-1])
    data.setflags(write=False)
    return dataclasses.replace(psf, data=data, wavefront=front)


class _LayerOptics:
    """Each non-empty layer's PSF (as :func:`_layer_psf` chooses them), computed at most once.

    ``fronts`` and ``scales`` (the grid's pixel, in image pixels) by layer, far to near.  A layer
    either computes its PSF (cached by wavefront) or reflects that of an earlier layer whose
    wavefront is its negative.  ``sizes``: each PSF's side (px of its grid).  :meth:`prefetch`
    computes a layer's PSF in a thread pool; :meth:`psf` waits for it.
    """

    def __init__(self, fronts: dict, scales: dict, pupil_mm: float, wavelength_nm: float, step: float, mode: str):
        self.fronts, self.scales = fronts, scales
        self.optics = (pupil_mm, wavelength_nm, step, mode)
        self.sizes, self.source, seen = {}, {}, {}
        for k, front in fronts.items():
            key = (scales[k], _wavefront_key(front.coefficients_um))
            opposite = seen.get((scales[k], _wavefront_key(front.coefficients_um, -1.0)))
            reflect = scales[k] == 1 and key not in seen and opposite is not None and self.sizes[opposite] % 2 == 1
            self.source[k] = opposite if reflect else None
            self.sizes[k] = self.sizes[opposite] if reflect else self._size(k)
            seen[key] = k
        self.futures: dict = {}

    def _size(self, k: int) -> int:
        pupil_mm, wavelength_nm, step, _ = self.optics
        size = suggested_size_px(self.fronts[k], step, pupil_diameter_mm=pupil_mm, wavelength_nm=wavelength_nm)
        if self.scales[k] == 1:
            return size
        size //= self.scales[k]  # the fine grid's field (arcmin) on the coarse grid: windows as wide as the fine's
        return size + 1 - size % 2

    def _compute(self, k: int) -> PSF:
        pupil_mm, wavelength_nm, step, mode = self.optics
        items = tuple(self.fronts[k].coefficients_um.items())
        if self.scales[k] == 1:  # size_px=None as depth_layers passes it: one lru_cache entry
            return _cached_psf(items, pupil_mm, wavelength_nm, step, mode, None)
        return _cached_psf(items, pupil_mm, wavelength_nm, step * self.scales[k], mode, size_px=self.sizes[k])

    def prefetch(self, pool, k: int) -> None:
        """Start computing the PSF layer ``k`` needs in ``pool`` (once)."""
        while self.source[k] is not None:
            k = self.source[k]
        if k not in self.futures:
            self.futures[k] = pool.submit(self._compute, k)

    def psf(self, k: int) -> PSF:
        if self.source[k] is not None:
            return _reflected(self.psf(self.source[k]), self.fronts[k])
        return self.futures[k].result() if k in self.futures else self._compute(k)


# -- the layered blur -----------------------------------------------------------------
def blur_depth(
    image,
    depth_m,
    *,
    eye_prescription: Prescription,
    pupil_diameter_mm: float,
    arcmin_per_px: float,
    accommodation_diopters: float = 0.0,
    wavelength_nm: float = 550.0,
    mode: str = "wave",
    extra_wavefront: Wavefront | None = None,
    layer_spacing_fraction: float = 0.5,
    max_layers: int | None = DEFAULT_MAX_LAYERS,
    occlusion_threshold_px: float = 1.0,
    padding: str = "edge",
    crop_px: int = 0,
    coarse_blur_px: float | None = None,
    device: str = "cpu",
    progress: Progress | None = None,
) -> DepthBlurResult:
    """Blur a linear-light image whose pixels lie at different depths, with occlusion.

    Parameters
    ----------
    image : ndarray of shape (H, W) or (H, W, C)
        Linear light, indexed ``[row, col]``.
    depth_m : ndarray of shape (H, W)
        Distance of each pixel's surface from the eye, metres; ``inf`` for sky.
    eye_prescription : Prescription
        The eye's correcting lens (myope negative), *not worn*: the eye is uncorrected.
    accommodation_diopters : float
        Accommodation exerted (D, >= 0), the same for the whole scene; see
        :func:`vissim.optics.accommodation.accommodation_for_target`.
    extra_wavefront : Wavefront, optional
        Further aberrations of the eye (higher orders), the same at every depth.
    layer_spacing_fraction : float
        Neighbouring layers' blur discs differ by at most this many pixels.
    max_layers : int, optional
        Refuse scenes needing more layers (default ``DEFAULT_MAX_LAYERS``); ``None``: no limit.
    occlusion_threshold_px : float
        Content occludes what lies behind it only when their blur discs differ by more than
        this many pixels; closer in depth they are one surface and add.
    padding : {"edge", "reflect"}
        Outside the image, colour, depth and coverage continue the border.
    crop_px : int
        Pixels cut from every side of the result: the input covers a margin beyond the frame
        wanted (as ``render depth`` writes it), so the frame sees what lies beyond it.
    coarse_blur_px : float, optional
        Blur layers whose geometric blur diameter is at least this many pixels on a grid twice
        as coarse (:func:`_blur_coarse`); ``None`` (default): every layer on the image's grid.
        At :data:`COARSE_BLUR_PX` (14 px) a layer of white noise, the hardest input, comes out
        within :data:`COARSE_MIN_DB` (44 dB PSNR) of its fine blur; wider blurs come closer.
    device : {"cpu", "cuda", "auto"}
        Where the layers are blurred (:mod:`vissim.optics.array_backend`): ``"cuda"`` on a GPU
        through CuPy (the ``gpu`` extra), ``"auto"`` there when one is present.  PSFs are computed
        on the CPU either way.  On the CPU, layers are blurred on as many threads as the process
        has cores.
    progress : callable, optional
        ``progress("depth layers", done, total)`` after each non-empty layer is composited
        (``total`` of them; :mod:`vissim.progress`).

    Returns
    -------
    DepthBlurResult
        ``image``: float32, shape (H - 2 crop_px, W - 2 crop_px) or (..., C), rows and columns as
        the input's (row 0 at the top); ``layers``: the depth layers blurred, far to near, each
        with its proximity (D), defocus (D) and blur diameter (arcmin);
        ``in_focus_proximity_diopters``: where the eye is focused (D); ``as_json()`` for a record.

    Examples
    --------
    A -2 D myope (sharp at 0.5 m) looking at a dark half at 0.5 m beside a bright half at 2 m:

    >>> import numpy as np
    >>> import vissim
    >>> image = np.full((32, 48), 0.9, np.float32)
    >>> image[:, :24] = 0.04
    >>> depth_m = np.where(np.arange(48) < 24, 0.5, 2.0) * np.ones((32, 1))
    >>> result = vissim.blur_depth(image, depth_m, eye_prescription=vissim.Prescription(-2.0),
    ...                            pupil_diameter_mm=4.0, arcmin_per_px=1.0, mode="geometric")
    >>> result.image.shape, result.image.dtype.name, result.in_focus_proximity_diopters
    ((32, 48), 'float32', 2.0)
    >>> [round(layer.proximity_diopters, 2) for layer in result.layers]  # far to near
    [0.5, 2.0]
    """
    rx = as_prescription(eye_prescription)
    pupil = check_pupil_mm(pupil_diameter_mm)
    step = check_arcmin_per_px(arcmin_per_px)
    accommodation = _check_accommodation(accommodation_diopters)
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"PSF mode must be 'wave' or 'geometric', got {mode!r}")
    if padding not in DEPTH_PADDING_MODES:
        raise VissimInputError(f"depth-blur padding must be one of {', '.join(DEPTH_PADDING_MODES)}; got {padding!r}")
    wavelength = finite_number(wavelength_nm, "wavelength", "nm")
    threshold_px = positive_number(occlusion_threshold_px, "occlusion threshold", "pixels of blur")
    backend = array_backend(device)
    if coarse_blur_px is not None:
        coarse_blur_px = positive_number(coarse_blur_px, "coarse-grid blur threshold", "pixels of blur diameter")
    if max_layers is not None and (int(max_layers) != max_layers or max_layers < 1):
        raise VissimInputError(f"max_layers must be a positive whole number of layers, got {max_layers!r}")
    pixels = np.asarray(image)
    if pixels.ndim not in (2, 3) or min(pixels.shape[:2]) < 1:
        raise VissimInputError(f"image must have shape (H, W) or (H, W, C), got {pixels.shape}")
    if not np.all(np.isfinite(pixels)):
        raise VissimInputError("image has NaN or infinite pixels; blur needs finite linear-light values")
    proximity = depth_to_proximity_diopters(depth_m)
    if proximity.shape != pixels.shape[:2]:
        raise VissimInputError(f"depth map {proximity.shape} does not match the image {pixels.shape[:2]} (rows, cols)")
    if int(crop_px) != crop_px or crop_px < 0 or 2 * crop_px >= min(proximity.shape):
        raise VissimInputError(f"crop_px must be whole pixels >= 0 leaving an image; got {crop_px!r} px for "
                               f"{proximity.shape[1]} x {proximity.shape[0]} px")
    crop = int(crop_px)
    colour = np.ascontiguousarray(pixels[np.newaxis] if pixels.ndim == 2 else np.moveaxis(pixels, -1, 0), np.float32)
    rows, cols = proximity.shape

    base = _base_wavefront(rx, pupil, extra_wavefront)
    in_focus_diopters = accommodation - base.to_prescription().spherical_equivalent_diopters
    spacing_max = layer_spacing_diopters(step, pupil, layer_spacing_fraction)
    plan = plan_layers(float(proximity.min()), float(proximity.max()), spacing_max, max_layers,
                       anchor_diopters=in_focus_diopters, symmetric=True)
    layer_diopters = np.array(plan.proximities_diopters)
    threshold_diopters = max(layer_spacing_diopters(step, pupil, threshold_px), spacing_max * (1 + 1e-9))
    lower, frac = _matte_indices(proximity, layer_diopters)
    coverage = np.bincount(lower.ravel(), weights=(1.0 - frac).ravel(), minlength=plan.n_layers + 1)
    coverage += np.bincount((lower + 1).ravel(), weights=frac.ravel(), minlength=plan.n_layers + 1)
    upper = np.minimum(lower + 1, plan.n_layers - 1).astype(np.int32)
    lower, frac = lower.astype(np.int32), frac.astype(np.float32)
    active = [k for k in range(plan.n_layers) if coverage[k] > 0]

    fronts = {k: base.with_defocus_diopters(layer_diopters[k] - accommodation) for k in active}
    blurs_arcmin = {k: 2.0 * geometric_blur_radius_arcmin(fronts[k], pupil) for k in active}
    scales = {k: COARSE_FACTOR if coarse_blur_px is not None and blurs_arcmin[k] / step >= coarse_blur_px else 1
              for k in active}
    optics = _LayerOptics(fronts, scales, pupil, wavelength, step, mode)
    sizes = optics.sizes
    layers = [DepthLayer(k, float(layer_diopters[k]), rx.sphere_diopters + float(layer_diopters[k]) - accommodation,
                         blurs_arcmin[k], sizes[k] * scales[k], float(coverage[k] / lower.size)) for k in active]
    reach = {k: (sizes[k] // 2 + 1) * scales[k] for k in active}
    reach_max = max(reach.values())
    boxes = _layer_boxes(lower, upper, frac, plan.n_layers)
    xp, transfers = backend.xp, {}
    colour, lower, upper, frac = (backend.asarray(a) for a in (colour, lower, upper, frac))
    numerator = xp.zeros_like(colour)
    denominator = xp.zeros((rows, cols), np.float32)
    occluders = xp.zeros((rows, cols), np.float32)  # blurred coverage of layers that fully occlude this one
    pending: list[tuple[float, tuple, np.ndarray]] = []  # nearer layers' blurred coverage (window), occluding in part
    farthest = layer_diopters[active[0]]
    largest = (0, 0)
    threads = _worker_threads(backend)

    def blurred_layer(k: int) -> tuple:
        # Layer k reaches its matte's box grown by its own PSF; its continuation behind nearer content
        # matters only where that content's blur leaves it visible: the largest PSF's reach further.
        window = _grow(boxes[k], 2 * (reach[k] + reach_max), (rows, cols))
        # The continuation is estimated on a larger window: pull-push's coarse levels see farther.
        e0, e1, f0, f1 = _grow(window, EXTENSION_HALO_PX, (rows, cols))
        wide = (slice(e0, e1), slice(f0, f1))
        planes = _extended_layer(colour[:, e0:e1, f0:f1], lower[wide], upper[wide], frac[wide], layer_diopters, k,
                                 threshold_diopters, rows=(boxes[k][0] - e0, boxes[k][1] - e0),
                                 keep=(window[0] - e0, window[1] - e0))
        window_rows = window[0]
        planes = planes[:, window[0] - e0 : window[1] - e0]  # the rows extended: those of the window
        if scales[k] == 1:  # the blur reaches only the planes' nonzero box grown by the PSF
            window = _grow(_nonzero_box(planes, (window_rows, f0)), reach[k], (rows, cols), within=window)
        r0, r1, c0, c1 = window
        planes = planes[:, r0 - window_rows : r1 - window_rows, c0 - f0 : c1 - f0]
        touches = (r0 == 0, r1 == rows, c0 == 0, c1 == cols)
        if scales[k] == 1:
            blurred, shape = _blur_window(planes, optics.psf(k), padding, touches, backend, transfers, threads)
        else:
            blurred, shape = _blur_coarse(planes, optics.psf(k), padding, touches, scales[k], backend, transfers,
                                          threads)
        return window, blurred, shape

    for done, (k, (window, blurred, shape)) in enumerate(_in_order(blurred_layer, optics, reversed(active), threads), 1):
        while pending and pending[0][0] - layer_diopters[k] >= 2 * threshold_diopters:  # near to far
            _, (r0, r1, c0, c1), matte_j = pending.pop(0)
            occluders[r0:r1, c0:c1] += matte_j
        r0, r1, c0, c1 = window
        transmitted = occluders[r0:r1, c0:c1].copy()
        for proximity_j, window_j, matte_j in pending:
            weight = _occlusion_weight(proximity_j - layer_diopters[k], threshold_diopters)
            if weight > 0:
                _add_overlap(transmitted, window, weight * matte_j, window_j)
        xp.clip(1.0 - transmitted, 0.0, 1.0, out=transmitted)
        largest = max(largest, shape)
        if layer_diopters[k] - threshold_diopters > farthest:  # it occludes layers behind it: keep its blurred coverage
            pending.append((layer_diopters[k], window, blurred[-1].copy()))
        blurred *= transmitted
        numerator[:, r0:r1, c0:c1] += blurred[:-1]
        denominator[r0:r1, c0:c1] += blurred[-1]
        if progress is not None:
            progress("depth layers", done, len(active))
    log.info("depth blur: %d layers planned, %d non-empty, largest padded window %s", plan.n_layers, len(active), largest)
    shape = largest
    low = int((denominator < 0.5).sum())
    if low:
        log.info("depth blur: %d pixels have total blurred coverage below 0.5 (min %.3g)", low, float(denominator.min()))
    out = numerator / xp.maximum(denominator, 1e-6)
    out = backend.to_numpy(out[:, crop : rows - crop, crop : cols - crop])
    result = out[0] if pixels.ndim == 2 else np.moveaxis(out, 0, -1)
    return DepthBlurResult(
        np.ascontiguousarray(result, dtype=np.float32), tuple(layers), plan.n_layers, plan.max_spacing_diopters,
        threshold_diopters, accommodation, in_focus_diopters, shape,
    )


def _matte_indices(proximity: np.ndarray, layer_diopters: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's farther layer index ``i`` and its weight ``t`` in layer ``i + 1`` (tent matte)."""
    if layer_diopters.size == 1:
        return np.zeros(proximity.shape, np.int64), np.zeros(proximity.shape)
    lower = np.clip(np.searchsorted(layer_diopters, proximity, side="right") - 1, 0, layer_diopters.size - 2)
    gap = layer_diopters[lower + 1] - layer_diopters[lower]
    frac = np.clip((proximity - layer_diopters[lower]) / gap, 0.0, 1.0)
    snap_up = frac > 1.0 - 1e-6  # on a layer (to rounding): that layer only
    lower[snap_up] += 1
    frac[snap_up | (frac < 1e-6)] = 0.0
    return lower, frac


def _occlusion_weight(proximity_gap_diopters, threshold_diopters: float):
    """How much nearer content occludes: 0 up to the threshold, rising to 1 at twice it."""
    return np.clip(np.asarray(proximity_gap_diopters) / threshold_diopters - 1.0, 0.0, 1.0)


def _extended_layer(colour, lower, upper, frac, layer_diopters: np.ndarray, k: int, threshold_diopters: float, work=None,
                    rows: tuple[int, int] | None = None, keep: tuple[int, int] | None = None):
    """Layer ``k``: premultiplied colours and coverage (C + 1, H, W), extended behind its occluders.

    ``lower``/``upper`` are each pixel's two layers and ``frac`` (float32) its weight in
    ``upper`` (the tent matte).  ``hidden`` is the part of each pixel that occludes layer ``k``
    (its mattes on nearer layers, weighted by :func:`_occlusion_weight`); there layer ``k``
    continues with the pull-push estimate of its own colour and coverage from the rest of the
    image (where its coverage is 0 the estimate is 0 too: no layer grows sideways).  The
    extended coverage also occludes the layers behind it: they are behind its continuation.
    ``work`` (from :func:`_workspace`) holds reused buffers; the result may be one of them.
    ``rows`` (first, end): the rows outside which layer ``k``'s matte is zero (default: unknown).
    ``keep`` (first, end): the rows of the result the caller uses; others are left undefined
    (default: all).
    """
    xp = array_module(colour)
    n_ch = colour.shape[0]
    work = _workspace(colour.shape, xp) if work is None else work
    stack, hidden, scratch = work["stack"], work["hidden"], work["scratch"]
    height = colour.shape[1]
    first, end = rows or (0, height)
    keep_first, keep_end = keep or (0, height)
    # zero beside the matte: in the rows kept, and a row either side (pull-push's first 2 x 2 cells read it)
    stack[:, min(keep_first, max(first - 1, 0)) : first] = 0.0
    stack[:, end : max(keep_end, min(end + 1, height))] = 0.0
    band = (slice(first, end), slice(None))
    matte = stack[n_ch, first:end]
    matte[...] = _matte(lower[band], upper[band], frac[band], k, xp)
    xp.multiply(colour[:, first:end], matte, out=stack[:n_ch, first:end])
    weights = _occlusion_weight(layer_diopters - layer_diopters[k], threshold_diopters).astype(np.float32)
    if not weights.any():
        return stack
    weights = xp.asarray(weights)
    xp.take(weights, lower, out=hidden)
    xp.take(weights, upper, out=scratch)
    scratch -= hidden
    scratch *= frac
    hidden += scratch
    hidden_rows = keep_first + np.flatnonzero(_to_host(hidden[keep_first:keep_end].any(axis=1)))
    if hidden_rows.size == 0:  # nothing of layer k is hidden in the rows kept
        return stack
    xp.subtract(1.0, hidden, out=scratch)
    estimate = pull_push(stack, scratch, rows=(first, end))
    # Where hidden > 0 the pixel has no coverage of its own on layer k (its layers are nearer),
    # so level 0 of the push is hidden * (upsampled estimate); it enters weighted by hidden again
    # (rows without hidden pixels: nothing to add).
    r0, r1 = int(hidden_rows[0]) // 2, (int(hidden_rows[-1]) + 2) // 2  # estimate rows: 2 x 2 cells
    upsampled = work["upsampled"][:, 2 * r0 : 2 * r1]
    upsampled.reshape(n_ch + 1, r1 - r0, 2, estimate.shape[2], 2)[...] = estimate[:, r0:r1, None, :, None]
    low, high = max(2 * r0, keep_first), min(2 * r1, keep_end)
    upsampled = upsampled[:, low - 2 * r0 : high - 2 * r0, : hidden.shape[1]]
    hidden = hidden[low:high]
    hidden *= hidden
    upsampled *= hidden
    stack[:, low:high] += upsampled
    return stack


def _matte(lower, upper, frac, k: int, xp):
    """Layer ``k``'s tent matte: ``1 - frac`` where it is the pixel's farther layer, ``frac`` where the nearer."""
    return xp.where(lower == k, 1.0 - frac, xp.where(upper == k, frac, 0.0))


def _layer_boxes(lower, upper, frac, n_layers: int) -> dict[int, tuple[int, int, int, int]]:
    """Each layer's bounding box (row0, row1, col0, col1) of the pixels its tent matte touches."""
    rows, cols = lower.shape
    row_index = np.arange(rows, dtype=np.int64)[:, None]
    col_index = np.arange(cols, dtype=np.int64)[None, :]
    in_lower, in_upper = (frac < 1.0).astype(np.float32), (frac > 0.0).astype(np.float32)
    hits = []
    for index, size in ((row_index, rows), (col_index, cols)):
        count = np.zeros(n_layers * size)
        for layer, present in ((lower, in_lower), (upper, in_upper)):
            count += np.bincount((layer.astype(np.int64) * size + index).ravel(), weights=present.ravel(),
                                 minlength=n_layers * size)
        hits.append(count.reshape(n_layers, size) > 0)
    boxes = {}
    for k in range(n_layers):
        r, c = np.flatnonzero(hits[0][k]), np.flatnonzero(hits[1][k])
        if r.size:
            boxes[k] = (int(r[0]), int(r[-1]) + 1, int(c[0]), int(c[-1]) + 1)
    return boxes


def _grow(box, reach: int, shape, within=None) -> tuple[int, int, int, int]:
    """``box`` grown by ``reach`` on every side, inside the image (``shape``) and ``within`` a window."""
    r0, r1, c0, c1 = box
    w0, w1, v0, v1 = within or (0, shape[0], 0, shape[1])
    return max(r0 - reach, w0), min(r1 + reach, w1), max(c0 - reach, v0), min(c1 + reach, v1)


def _nonzero_box(planes, origin: tuple[int, int]) -> tuple[int, int, int, int]:
    """The box (row0, row1, col0, col1) of the image holding every nonzero pixel of (C, h, w) ``planes``
    whose pixel [0, 0] is the image's ``origin``; all of them if none is nonzero."""
    nonzero = planes.any(axis=0)
    rows = np.flatnonzero(_to_host(nonzero.any(axis=1)))
    cols = np.flatnonzero(_to_host(nonzero.any(axis=0)))
    if rows.size == 0:
        rows, cols = np.arange(planes.shape[1]), np.arange(planes.shape[2])
    return origin[0] + int(rows[0]), origin[0] + int(rows[-1]) + 1, origin[1] + int(cols[0]), origin[1] + int(cols[-1]) + 1


def _to_host(array) -> np.ndarray:
    return array.get() if hasattr(array, "get") and not isinstance(array, np.ndarray) else np.asarray(array)


def _worker_threads(backend: ArrayBackend) -> int:
    """Threads that blur layers at once: the cores this process may use on the CPU; one on a GPU."""
    return available_cores() if backend is CPU_BACKEND else 1


def _in_order(work, optics: _LayerOptics, order, threads: int):
    """``(k, work(k))`` for each layer ``k`` of ``order``, in that order.

    With ``threads > 1`` the layers are worked on ahead in a thread pool (at most ``2 threads``
    ahead of the caller; their PSFs twice as far ahead, so that a layer seldom waits for its own):
    a layer's extension and blur depend on no other layer, only its compositing (the caller's)
    does.  A layer's task waits only for PSF tasks submitted before it, which have therefore
    started: no deadlock.
    """
    order = list(order)
    if threads <= 1:
        for k in order:
            yield k, work(k)
        return
    futures: dict = {}
    with single_threaded_blas(), ThreadPoolExecutor(threads) as pool:  # our threads, not OpenBLAS's, use the cores
        try:
            for i, k in enumerate(order):
                for later in order[i : i + 4 * threads + 1]:
                    optics.prefetch(pool, later)
                for later in order[i : i + 2 * threads + 1]:
                    if later not in futures:
                        futures[later] = pool.submit(work, later)
                yield k, futures.pop(k).result()
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _add_overlap(target: np.ndarray, window, source: np.ndarray, source_window) -> None:
    """``target`` (on ``window``) += ``source`` (on ``source_window``) where the two windows overlap."""
    r0, r1 = max(window[0], source_window[0]), min(window[1], source_window[1])
    c0, c1 = max(window[2], source_window[2]), min(window[3], source_window[3])
    if r0 < r1 and c0 < c1:
        target[r0 - window[0] : r1 - window[0], c0 - window[2] : c1 - window[2]] += \
            source[r0 - source_window[0] : r1 - source_window[0], c0 - source_window[2] : c1 - source_window[2]]


def _blur_window(planes, psf: PSF, padding: str, touches, backend: ArrayBackend = CPU_BACKEND,
                 transfers: dict | None = None, threads: int | None = None) -> tuple:
    """Blur (C, h, w) planes of a window with one PSF (:func:`vissim.optics.blur_device.convolve_padded`).

    ``touches``: whether the window's (top, bottom, left, right) side is the image's border.
    Beyond the image's border the planes continue as ``padding`` says; beyond a window side inside
    the image they are zero (the window already holds everything of the layer that reaches it).
    ``backend`` holds the planes (NumPy or CuPy); ``transfers`` caches kernel spectra on its device;
    ``threads``: the CPU FFT's threads (default all).  Returns the blurred planes and the padded grid's shape.
    """
    if padding not in DEPTH_PADDING_MODES:
        raise AssertionError(f"depth padding {padding!r}")  # pragma: no cover  (blur_depth refuses it)
    n, h, w = planes.shape
    offset = padding_width_px(psf.data.shape[0])
    shape = padded_shape((h, w), psf.data.shape[0])
    padded = pad_array(planes, ((0, 0), (offset, shape[0] - h - offset), (offset, shape[1] - w - offset)), padding,
                       xp=backend.xp)
    top, bottom, left, right = touches
    if not top:
        padded[:, :offset] = 0.0
    if not bottom:
        padded[:, offset + h :] = 0.0
    if not left:
        padded[:, :, :offset] = 0.0
    if not right:
        padded[:, :, offset + w :] = 0.0
    blurred = convolve_padded(padded, psf, backend, transfers, threads=threads)
    return blurred[:, offset : offset + h, offset : offset + w], shape


#: The coarse grid's pixel, in image pixels per side (``coarse_blur_px`` of :func:`blur_depth`).
COARSE_FACTOR = 2


def _blur_coarse(planes, psf: PSF, padding: str, touches, factor: int, backend: ArrayBackend = CPU_BACKEND,
                 transfers: dict | None = None, threads: int | None = None) -> tuple:
    """Blur on a grid ``factor`` times coarser: block means in, the coarse PSF, bilinear (cell-centred) back.

    ``psf`` is sampled at ``factor`` times the image's arcmin/px.  For a wide PSF the blurred
    image holds little above the coarse grid's Nyquist frequency, so this is close to the fine
    blur (:data:`COARSE_MIN_DB` at :data:`COARSE_BLUR_PX`) at a quarter of the FFT work.
    """
    n, h, w = planes.shape
    q = factor
    xp = backend.xp
    even = xp.pad(planes, ((0, 0), (0, (-h) % q), (0, (-w) % q)), mode="edge")
    coarse = even.reshape(n, even.shape[1] // q, q, even.shape[2] // q, q).mean(axis=(2, 4))
    blurred, shape = _blur_window(xp.ascontiguousarray(coarse, dtype=np.float32), psf, padding, touches, backend,
                                  transfers, threads)
    fine = blurred
    for _ in range(int(round(math.log2(q)))):
        fine = upsample2(fine, (2 * fine.shape[1], 2 * fine.shape[2]))
    return fine[:, :h, :w], shape


def _workspace(shape: tuple[int, int, int], xp=np) -> dict:
    """Buffers for :func:`_extended_layer` (``xp``: the array module, NumPy or CuPy)."""
    n_ch, rows, cols = shape
    return {
        "stack": xp.empty((n_ch + 1, rows, cols), np.float32),
        "hidden": xp.empty((rows, cols), np.float32),
        "scratch": xp.empty((rows, cols), np.float32),
        "upsampled": xp.empty((n_ch + 1, rows + rows % 2, cols + cols % 2), np.float32),
    }
