"""Depth-dependent blur: one eye, one accommodation state, a scene with a depth map.

Defocus per depth (derivation in `vissim.optics.rx.accommodation`; decided by
`vissim.optics.rx.viewing_setup.DepthViewer`, `vissim.optics.rx.viewing_setup.ViewingSetup.eye` at every depth).  An object
``d`` metres away has *proximity* ``L = 1/d`` dioptres (``L = 0`` for sky at infinity).  An eye whose correcting
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
(colours, extended coverage) (one real FFT pair, `vissim.optics.blur.device.convolve_window`,
whose row transforms skip the padding rows on the CPU; blur.py's overlap-save squares measured
no faster on these windows), on the layer's *window*: the box of its tent matte grown by
``2 (r_k + r_max)`` pixels (``r`` the PSF's half-width + 1, ``r_max`` the widest layer's).  A
layer's blur reaches ``r_k`` beyond its matte, its continuation behind nearer content matters
where that content's blur (``r_max``) lets it show, and both spread once more through partly
occluding neighbours.  The continuation itself is estimated by pull-push on the window grown by
another `vissim.optics.depth.composite.EXTENSION_HALO_PX` (64) pixels, whose coarse levels then
see the neighbourhood the whole frame would give them: the depth campaign's RGB-D results equal
the full-frame estimate's (same dB to 0.1), and on the 1080p frame of
``benchmarks/bench_depth.py`` the two differ by 60 dB PSNR (max 0.05 of the range, at panel
edges).  On such a frame, whose layers are bands of a floor, each window is a few per cent of
the frame.  Within it, the FFT covers only the box of the extended layer's nonzero pixels grown
by ``r_k`` (beyond it the blur is exactly zero), and pull-push sums only the rows that hold the
layer's matte (the rest are sums of zeros).  The compositor leaves out a window's leading and
trailing rows where nearer content hides the layer completely.

Threads: a layer's extension and blur depend on no other layer; only its compositing (the
transmission through nearer layers) does.  On the CPU, one thread per core extends and blurs
layers ahead (their PSFs computed in the same pool, OpenBLAS held at one thread meanwhile:
`vissim.optics.runtime.threads`; the last few started largest first, so that a large background
does not end the call alone) while the calling thread composites them near to far, in order:
the result equals the one-thread blur to float32 round-off (``tests/test_depth_threads.py``).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import os
from dataclasses import dataclass

import numpy as np

from vissim.checks import DEFAULT_LAYER_SPACING_FRACTION, DEFAULT_MAX_LAYERS, DEFAULT_WAVELENGTH_NM, size_text
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import describe, instance_of, positive_number
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.errors import VissimInputError, VissimTypeError
from vissim.optics.runtime.array_backend import array_backend
from vissim.optics.blur.convolve import pixel_array
from vissim.optics.depth.composite import Compositor, LayerScene, blurred_layer
from vissim.optics.depth.psfs import LayerOptics, in_order, layer_pool, worker_threads
from vissim.optics.depth.windows import COARSE_FACTOR, DEPTH_PADDING_MODES, layer_boxes
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import geometric_blur_radius_arcmin
from vissim.optics.psf.field_size import load_size_tables
from vissim.optics.rx.viewing_setup import DepthViewer
from vissim.optics.pupil.wavefront import Wavefront
from vissim.progress import Progress
from vissim.units import arcmin_to_rad

__all__ = ["DepthBlurResult", "DepthLayer", "LayerPlan", "blur_depth", "depth_to_proximity_diopters",
           "layer_spacing_diopters", "plan_layers", "matte_indices", "eye_of"]

log = logging.getLogger(__name__)

#: A blur diameter (px) from which a layer may go on the coarse grid, and the PSNR (dB, unit range)
#: of its coarse blur against the fine one on white noise there (``tests/test_depth.py``).
COARSE_BLUR_PX = 14.0
COARSE_MIN_DB = 44.0


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
    PSFs are point reflections of each other (one computed PSF serves both, `blur_depth`).
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
    if isinstance(depth_m, (str, bytes, os.PathLike)):
        raise VissimTypeError(f"depth_m must be an ndarray of metres, shape (H, W) (read a file with "
                              f"vissim.imageio.read_data_map(path).pixels), got {depth_m!r}")
    try:
        depth = np.asarray(depth_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise VissimTypeError(f"depth_m must be an ndarray of metres, shape (H, W), got {describe(depth_m)}") from None
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


# -- the eye ---------------------------------------------------------------------------
def eye_of(eye: DepthViewer | None, rx, pupil_diameter_mm, accommodation_diopters, extra_wavefront) -> DepthViewer:
    """``eye``, or the `DepthViewer` the keywords describe (accommodation None: 0 D); both at once are refused."""
    if eye is not None:
        instance_of(eye, DepthViewer, "eye", "a vissim.optics.rx.viewing_setup.DepthViewer")
        given = [name for name, value in (("rx", rx), ("pupil_diameter_mm", pupil_diameter_mm),
                                          ("accommodation_diopters", accommodation_diopters),
                                          ("extra_wavefront", extra_wavefront)) if value is not None]
        if given:
            raise VissimInputError(f"give the eye as eye= or as its keywords, not both (also given: {', '.join(given)})")
        return eye
    if rx is None or pupil_diameter_mm is None:
        raise VissimTypeError("the eye is needed: eye= (a vissim.optics.rx.viewing_setup.DepthViewer), or rx= and "
                              "pupil_diameter_mm=")
    accommodation = 0.0 if accommodation_diopters is None else accommodation_diopters
    return DepthViewer(rx, pupil_diameter_mm, accommodation, extra_wavefront)


# -- the layered blur -----------------------------------------------------------------
def blur_depth(
    image,
    depth_m,
    *,
    rx: Prescription | None = None,
    pupil_diameter_mm: float | None = None,
    arcmin_per_px: float,
    accommodation_diopters: float | None = None,
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM,
    mode: str = "wave",
    extra_wavefront: Wavefront | None = None,
    eye: DepthViewer | None = None,
    layer_spacing_fraction: float = DEFAULT_LAYER_SPACING_FRACTION,
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
    rx : Prescription
        The eye's correcting lens (myope negative), *not worn*: the eye is uncorrected.
    pupil_diameter_mm : float
        The eye's pupil, mm.
    accommodation_diopters : float, optional
        Accommodation exerted (D, >= 0; default 0), the same for the whole scene; see
        `vissim.optics.rx.accommodation.accommodation_for_target`.
    extra_wavefront : Wavefront, optional
        Further aberrations of the eye (higher orders), the same at every depth.
    eye : DepthViewer, optional
        The eye as one object (`vissim.optics.rx.viewing_setup.DepthViewer`), instead of the four keywords above.
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
        as coarse (`blur_coarse`); ``None`` (default): every layer on the image's grid.
        At `COARSE_BLUR_PX` (14 px) a layer of white noise, the hardest input, comes out
        within `COARSE_MIN_DB` (44 dB PSNR) of its fine blur; wider blurs come closer.
    device : {"cpu", "cuda", "auto"}
        Where the layers are blurred (`vissim.optics.runtime.array_backend`): ``"cuda"`` on a GPU
        through CuPy (the ``gpu`` extra), ``"auto"`` there when one is present.  PSFs are computed
        on the CPU either way.  On the CPU, layers are blurred on as many threads as the process
        has cores.
    progress : callable, optional
        ``progress("depth layers", done, total)`` after each non-empty layer is composited
        (``total`` of them; `vissim.progress`).

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
    >>> result = vissim.blur_depth(image, depth_m, rx=vissim.Prescription(-2.0),
    ...                            pupil_diameter_mm=4.0, arcmin_per_px=1.0, mode="geometric")
    >>> result.image.shape, result.image.dtype.name, result.in_focus_proximity_diopters
    ((32, 48), 'float32', 2.0)
    >>> [round(layer.proximity_diopters, 2) for layer in result.layers]  # far to near
    [0.5, 2.0]
    """
    eye = eye_of(eye, rx, pupil_diameter_mm, accommodation_diopters, extra_wavefront)
    pupil = eye.pupil_diameter_mm
    step = check_arcmin_per_px(arcmin_per_px)
    wavelength, threshold_px, coarse_blur_px, backend = _checked_options(
        mode, padding, wavelength_nm, occlusion_threshold_px, coarse_blur_px, max_layers, device)
    eye.check_light(wavelength)
    pixels, proximity, crop = _checked_image_and_depth(image, depth_m, crop_px)
    colour = np.ascontiguousarray(pixels[np.newaxis] if pixels.ndim == 2 else np.moveaxis(pixels, -1, 0), np.float32)

    in_focus_diopters = eye.in_focus_proximity_diopters
    plan, threshold_diopters = _depth_plan(proximity, in_focus_diopters, step, pupil, layer_spacing_fraction,
                                           threshold_px, max_layers)
    layer_diopters = np.array(plan.proximities_diopters)
    threads = worker_threads(backend)
    with layer_pool(threads) as pool:  # one thread per core on the CPU: blur sizes, PSFs, layers
        if pool is not None:  # the PSF sizes' tables load (and their imports run) while the matte is cut
            pool.submit(load_size_tables)
        matte = _tent_matte(proximity, layer_diopters)
        boxes_job = None if pool is None else pool.submit(layer_boxes, matte.lower, matte.upper, matte.frac, plan.n_layers)
        optics, layers = _layer_optics(eye, layer_diopters, matte, wavelength, step, mode, coarse_blur_px, pool)
        boxes = layer_boxes(matte.lower, matte.upper, matte.frac, plan.n_layers) if boxes_job is None else boxes_job.result()
        scene = LayerScene.on(backend, colour, (matte.lower, matte.upper, matte.frac), layer_diopters,
                              threshold_diopters, boxes, optics, padding, 1 if pool is not None else None)
        compositor = Compositor(scene, layer_diopters[matte.active[0]])
        near_to_far = in_order(functools.partial(blurred_layer, scene), optics, reversed(matte.active), pool, threads,
                               cost=scene.window_px)
        for done, (k, (window, blurred, shape)) in enumerate(near_to_far, 1):
            compositor.add(k, window, blurred, shape)
            if progress is not None:
                progress("depth layers", done, len(matte.active))
    log.info("depth blur: %d layers planned, %d non-empty, largest padded window %s", plan.n_layers, len(matte.active),
             compositor.largest)
    out = compositor.image(crop)
    result = out[0] if pixels.ndim == 2 else np.moveaxis(out, 0, -1)
    return DepthBlurResult(
        np.ascontiguousarray(result, dtype=np.float32), tuple(layers), plan.n_layers, plan.max_spacing_diopters,
        threshold_diopters, eye.accommodation_diopters, in_focus_diopters, compositor.largest,
    )


# -- the stages of blur_depth ---------------------------------------------------------
def _checked_options(mode: str, padding: str, wavelength_nm, occlusion_threshold_px, coarse_blur_px, max_layers,
                     device: str):
    """Checks: (wavelength nm, occlusion threshold px, coarse-grid blur px or None, array backend)."""
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"PSF mode must be 'wave' or 'geometric', got {mode!r}")
    if padding not in DEPTH_PADDING_MODES:
        raise VissimInputError(f"depth-blur padding must be one of {', '.join(DEPTH_PADDING_MODES)}; got {padding!r}")
    wavelength = check_wavelength_nm(wavelength_nm)
    threshold_px = positive_number(occlusion_threshold_px, "occlusion threshold", "pixels of blur")
    backend = array_backend(device)
    if coarse_blur_px is not None:
        coarse_blur_px = positive_number(coarse_blur_px, "coarse-grid blur threshold", "pixels of blur diameter")
    if max_layers is not None and (int(max_layers) != max_layers or max_layers < 1):
        raise VissimInputError(f"max_layers must be a positive whole number of layers, got {max_layers!r}")
    return wavelength, threshold_px, coarse_blur_px, backend


def _checked_image_and_depth(image, depth_m, crop_px) -> tuple[np.ndarray, np.ndarray, int]:
    """Checks: the image's pixels, each pixel's proximity (D) and the crop (px)."""
    pixels = pixel_array(image)
    if pixels.ndim not in (2, 3) or min(pixels.shape[:2]) < 1:
        raise VissimInputError(f"image must have shape (H, W) or (H, W, C), got {pixels.shape}")
    if not np.all(np.isfinite(pixels)):
        raise VissimInputError("image has NaN or infinite pixels; blur needs finite linear-light values")
    proximity = depth_to_proximity_diopters(depth_m)
    if proximity.shape != pixels.shape[:2]:
        raise VissimInputError(f"the depth map is {size_text(proximity.shape)} but the image {size_text(pixels.shape)}")
    if int(crop_px) != crop_px or crop_px < 0 or 2 * crop_px >= min(proximity.shape):
        raise VissimInputError(f"crop_px must be whole pixels >= 0 leaving an image; got {crop_px!r} px for "
                               f"{size_text(proximity.shape)}")
    return pixels, proximity, int(crop_px)


def _depth_plan(proximity: np.ndarray, in_focus_diopters: float, step: float, pupil: float, spacing_fraction: float,
                threshold_px: float, max_layers: int | None) -> tuple[LayerPlan, float]:
    """The layers (symmetric about the in-focus proximity) and the occlusion threshold in dioptres (module doc)."""
    spacing_max = layer_spacing_diopters(step, pupil, spacing_fraction)
    plan = plan_layers(float(proximity.min()), float(proximity.max()), spacing_max, max_layers,
                       anchor_diopters=in_focus_diopters, symmetric=True)
    threshold_diopters = max(layer_spacing_diopters(step, pupil, threshold_px), spacing_max * (1 + 1e-9))
    return plan, threshold_diopters


@dataclass(frozen=True, eq=False)
class _TentMatte:
    """Each pixel's farther layer ``lower``, nearer ``upper`` (NumPy's index type) and weight ``frac`` in the nearer
    (float32); each layer's summed matte ``coverage`` (px) and the non-empty layers, far to near."""

    lower: np.ndarray
    upper: np.ndarray
    frac: np.ndarray
    coverage: np.ndarray
    active: list[int]


def _tent_matte(proximity: np.ndarray, layer_diopters: np.ndarray) -> _TentMatte:
    """Matting: each pixel split linearly in dioptres between its two neighbouring layers (module doc)."""
    n_layers = layer_diopters.size
    lower, frac = matte_indices(proximity, layer_diopters)
    coverage = np.bincount(lower.ravel(), weights=(1.0 - frac).ravel(), minlength=n_layers + 1)
    coverage += np.bincount((lower + 1).ravel(), weights=frac.ravel(), minlength=n_layers + 1)
    upper = np.minimum(lower + 1, n_layers - 1)
    active = [k for k in range(n_layers) if coverage[k] > 0]
    return _TentMatte(lower, upper, frac.astype(np.float32), coverage, active)


def _layer_optics(eye: DepthViewer, layer_diopters: np.ndarray, matte: _TentMatte, wavelength: float, step: float, mode: str,
                  coarse_blur_px: float | None, pool) -> tuple[LayerOptics, list[DepthLayer]]:
    """Each non-empty layer's wavefront (``eye`` at its proximity), blur diameter, grid (coarse from
    ``coarse_blur_px``) and PSF (on ``pool``'s threads if given), and its record."""
    pupil = eye.pupil_diameter_mm
    fronts = {k: eye.wavefront_at(layer_diopters[k]) for k in matte.active}
    blurs = (map if pool is None else pool.map)(lambda f: geometric_blur_radius_arcmin(f, pupil), fronts.values())
    blurs_arcmin = {k: 2.0 * radius for k, radius in zip(fronts, blurs)}
    scales = {k: COARSE_FACTOR if coarse_blur_px is not None and blurs_arcmin[k] / step >= coarse_blur_px else 1
              for k in matte.active}
    optics = LayerOptics(fronts, scales, pupil, wavelength, step, mode, pool)
    layers = [DepthLayer(k, float(layer_diopters[k]), eye.sphere_at_diopters(float(layer_diopters[k])),
                         blurs_arcmin[k], optics.sizes[k] * scales[k], float(matte.coverage[k] / matte.lower.size))
              for k in matte.active]
    return optics, layers


def matte_indices(proximity: np.ndarray, layer_diopters: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's farther layer index ``i`` and its weight ``t`` in layer ``i + 1`` (tent matte)."""
    if layer_diopters.size == 1:
        return np.zeros(proximity.shape, np.intp), np.zeros(proximity.shape)
    lower = np.searchsorted(layer_diopters, proximity, side="right")
    lower -= 1
    np.clip(lower, 0, layer_diopters.size - 2, out=lower)
    frac = proximity - layer_diopters[lower]
    frac /= np.diff(layer_diopters)[lower]  # the gap above each pixel's farther layer
    np.clip(frac, 0.0, 1.0, out=frac)
    snap_up = frac > 1.0 - 1e-6  # on a layer (to rounding): that layer only
    lower[snap_up] += 1
    frac[snap_up | (frac < 1e-6)] = 0.0
    return lower, frac
