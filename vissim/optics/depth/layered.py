"""Depth blur of a *layered* scene: each layer's radiance and coverage known, hidden parts included.

When the scene is known (every vissim depth scene), each of its layers -- a panel, or any
surface that never occludes itself -- can be rendered alone, unoccluded: its premultiplied
radiance ``C_k`` and its coverage ``A_k`` (alpha) per pixel, and its proximity ``L`` (dioptres;
one value for a fronto-parallel layer, a map for a slanted one).  Then nothing has to be
guessed behind an edge, unlike the RGB-D path (`vissim.optics.depth.depth_map.blur_depth`).

Geometric optics (``mode="geometric"``).  A ray through pupil point ``p`` that ends on pixel
``x`` left layer ``k`` at ``x - n_k(p)``, where ``n_k(p)`` is the landing offset of that ray
for the layer's defocus (``-grad W_k(p)``, as in `vissim.optics.psf.compute.compute_psf`); it meets
the nearer layers first, so the pixel sees the front-to-back *over* of the layers, each
shifted by its own parallax for that pupil point, averaged over the pupil::

    out(x) = < sum_k C_k(x - n_k(p)) prod_{j nearer than k} (1 - A_j(x - n_j(p))) >_p

exactly what a thin lens images of planar layers (for the eye and the DSLR of
`vissim.bench.depth.viewers`: the ray through ``p`` of the pixel with chief-ray tangent ``t``
leaves along ``t - K p``), so it converges to the render.  The pupil is sampled as the
geometric PSF is (a stratified, jittered grid of 250 000 to 4 million rays, fixed seed) and
each ray's offsets are rounded to whole pixels: for one layer alone the average is then
exactly the pixel-integrated geometric PSF's convolution (the histogram of rounded offsets
is the PSF integrated over pixels).  Rays with the same rounded offsets on every layer
involved form one term, weighted by their share of the pupil.  A layer that no nearer layer
overlaps (after both are blurred) is blurred by one FFT; the others are composited term by
term on the window their blur can reach.  A slanted layer is cut into proximity slices by
the tent matte of `vissim.optics.depth.depth_map.blur_depth` (its slices add: a plane never
occludes itself), each slice with its own offsets, and their sum is divided by the same sum
for the plane's uniform continuation (``_density``: the lens gathers radiance along rays, the
slice sum scatters light, and they differ by a few per cent on a steep slant).

Wave optics (``mode="wave"``), an approximation.  The ray-optics composite is diffracted by
the aperture in focus, and each layer adds what its wave PSF does beyond that (the Fresnel
ripples and spread of a defocused wave PSF ``W_k`` against the ray disc ``G_k`` diffracted),
dimmed by the share of the layer that ray optics lets through the nearer layers::

    out_wave = out_geo * D + sum_k tau_k (C_k * W_k - C_k * G_k * D),
    tau_k = (V_k * D) / ((A_k * G_k) * D)

``D`` is the aberration-free diffraction PSF of the pupil and ``V_k`` the layer's coverage seen
through the nearer layers (the composite above with ``A_k`` for ``C_k``); ``tau_k = 1`` for a
layer no nearer layer overlaps and where ``(A_k * G_k) * D`` is below 1e-6.  Exact for layers
that do not overlap (each gets exactly ``C_k * W_k``), in the geometric limit, and where a layer
is fully hidden; at partly occluded edges, a wave PSF's ripples are cut as the ray disc is.
The depth campaign measures it against the render convolved with ``D``.

Layers are ordered near to far by their coverage-weighted mean proximity; they must not
interpenetrate.  Behind the last layer is black (these scenes are self-emitting panels).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, fields

import numpy as np

from vissim.checks import DEFAULT_LAYER_SPACING_FRACTION, DEFAULT_WAVELENGTH_NM
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.blur.convolve import blur_image
from vissim.optics.depth.depth_map import eye_of, layer_spacing_diopters, matte_indices, plan_layers
from vissim.optics.depth.psfs import cached_psf
from vissim.optics.depth.windows import grow_box
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import PSF, geometric_blur_radius_arcmin
from vissim.optics.pupil.rays import landing_arcmin, ray_count, stratified_pupil_rays
from vissim.optics.rx.viewing_setup import DepthViewer
from vissim.optics.pupil.wavefront import Wavefront

ndimage = lazy_module("scipy.ndimage")

__all__ = ["SceneLayer", "LayeredBlurResult", "composite_layers"]

log = logging.getLogger(__name__)

#: Terms (distinct rounded offset tuples) above which a layer's composite is refused as too costly.
MAX_TERMS = 200_000


@dataclass(frozen=True, eq=False)
class SceneLayer:
    """One layer, rendered alone: premultiplied radiance, coverage and proximity (D; float or (H, W))."""

    radiance: np.ndarray
    coverage: np.ndarray
    proximity_diopters: float | np.ndarray


@dataclass(frozen=True, eq=False)
class LayeredBlurResult:
    """The composited image (float32) and how it was made."""

    image: np.ndarray
    n_layers: int
    n_slices: int
    n_rays: int
    n_terms: int  # pupil terms composited (over all overlapping layers)
    overlapping_layers: int  # layers composited term by term (the rest: one FFT each)
    accommodation_diopters: float
    mode: str

    def as_json(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "image"}


def _offsets_px(front: Wavefront, pupil_mm: float, step: float, rays) -> np.ndarray:
    """Each ray's landing offset (row, col) rounded to whole pixels, int32 (n, 2)."""
    col, row = landing_arcmin(front, pupil_mm, *rays)  # as compute_psf
    col, row = col / step, row / step
    return np.stack([np.floor(row + 0.5), np.floor(col + 0.5)], axis=1).astype(np.int32)


def _histogram_psf(offsets: np.ndarray, step: float, pupil_mm: float, wavelength_nm: float) -> PSF:
    """The rays' rounded offsets as a pixel-integrated geometric PSF (odd square, origin at the centre)."""
    half = int(np.abs(offsets).max()) if offsets.size else 0
    size = 2 * half + 1
    counts = np.zeros((size, size))
    np.add.at(counts, (offsets[:, 0] + half, offsets[:, 1] + half), 1.0)
    return PSF.from_array(counts / len(offsets), step, wavelength_nm=wavelength_nm, pupil_diameter_mm=pupil_mm)


@dataclass
class _Slice:
    layer: int
    proximity_diopters: float
    radiance: np.ndarray  # (C, H, W) premultiplied, this slice's share
    coverage: np.ndarray  # (H, W)
    plane: np.ndarray | None = None  # the slice's matte of the layer's plane continued over the grid (slanted layers)
    offsets: np.ndarray | None = None
    psf: PSF | None = None


def _check_layer(layer: SceneLayer, shape, index: int):
    if not isinstance(layer, SceneLayer):
        raise VissimInputError(f"layer {index} must be a SceneLayer, got {type(layer).__name__}")
    radiance = np.asarray(layer.radiance, dtype=np.float32)
    coverage = np.asarray(layer.coverage, dtype=np.float32)
    if radiance.ndim not in (2, 3) or coverage.ndim != 2 or radiance.shape[:2] != coverage.shape:
        raise VissimInputError(f"layer {index}: radiance (H, W[, C]) and coverage (H, W) must share a grid, got "
                               f"{radiance.shape} and {coverage.shape}")
    if shape is not None and (radiance.shape[:2] != shape[:2] or radiance.ndim != len(shape)):
        raise VissimInputError(f"layer {index}: radiance {radiance.shape} differs from layer 0's {shape}")
    if not (np.all(np.isfinite(radiance)) and np.all(np.isfinite(coverage))):
        raise VissimInputError(f"layer {index} has NaN or infinite pixels")
    if coverage.min(initial=0.0) < -1e-6 or coverage.max(initial=0.0) > 1.0 + 1e-3:
        raise VissimInputError(f"layer {index}: coverage must lie in [0, 1], got {coverage.min():g} to {coverage.max():g}")
    proximity = np.asarray(layer.proximity_diopters, dtype=np.float64)
    if proximity.ndim not in (0, 2) or (proximity.ndim == 2 and proximity.shape != coverage.shape):
        raise VissimInputError(f"layer {index}: proximity must be one value or an (H, W) map in dioptres, "
                               f"got shape {proximity.shape}")
    if not np.all(np.isfinite(proximity)) or proximity.min() < 0:
        raise VissimInputError(f"layer {index}: proximity must be finite dioptres >= 0 (0 = infinity)")
    colour = radiance[np.newaxis] if radiance.ndim == 2 else np.moveaxis(radiance, -1, 0)
    return np.ascontiguousarray(colour), np.clip(coverage, 0.0, 1.0), proximity


def _slices(index: int, colour, coverage, proximity, spacing_diopters: float, anchor_diopters: float) -> list[_Slice]:
    """A layer cut into proximity slices by the tent matte (one slice for a constant proximity).

    As `vissim.optics.depth.depth_map.blur_depth` plans its layers (`vissim.optics.depth.depth_map.plan_layers`,
    symmetric): exact ends, and steps of the largest spacing from the in-focus proximity
    ``anchor_diopters`` when the layer spans it.
    """
    inside = coverage > 0
    if proximity.ndim == 0 or not inside.any():
        value = float(proximity) if proximity.ndim == 0 else 0.0
        return [_Slice(index, value, colour, coverage)]
    values = proximity[inside]
    low, high = float(values.min()), float(values.max())
    if high - low <= 1e-9:
        return [_Slice(index, low, colour, coverage)]
    # The plane continued where the layer has no coverage: each pixel takes its nearest covered pixel's proximity.
    nearest = ndimage.distance_transform_edt(~inside, return_distances=False, return_indices=True)
    continued = np.clip(proximity[tuple(nearest)], low, high)
    plan = np.array(plan_layers(low, high, spacing_diopters, None, anchor_diopters=anchor_diopters,
                                symmetric=True).proximities_diopters)
    lower, frac = matte_indices(continued, plan)
    out = []
    for k in range(plan.size):
        plane = (np.where(lower == k, 1.0 - frac, 0.0) + np.where((lower + 1 == k), frac, 0.0)).astype(np.float32)
        matte = plane * inside
        if matte.any():
            out.append(_Slice(index, float(plan[k]), colour * matte, coverage * matte, plane))
    return out


def _density(layer: list[_Slice]) -> np.ndarray | None:
    """``J = sum_s M_s * G_s`` of a slanted layer's plane, for dividing its slices' sum (None: one slice).

    Summing slices blurred by different PSFs *scatters* each point's light by its own PSF; a
    thin lens *gathers*: a pixel sees the plane's radiance wherever each ray meets it, so a
    uniform plane images uniformly, while the scatter sum bunches light where the blur grows
    (by about ``1 - slope x p``, a few per cent on a steep slant).  Dividing by the scatter sum
    of the plane's own mattes ``M_s`` (its slices continued over the grid) makes a uniform
    plane exactly uniform, as `vissim.optics.depth.depth_map.blur_depth` normalises by its blurred coverage.
    """
    if len(layer) < 2:
        return None
    density = sum(_fft_blur(s.plane[np.newaxis], s.psf)[0] for s in layer)
    return np.where(density > 0.5, density, 1.0)


def _support(s: _Slice) -> tuple[int, int, int, int] | None:
    rows = np.flatnonzero((s.coverage > 0).any(axis=1) | (s.radiance != 0).any(axis=(0, 2)))
    cols = np.flatnonzero((s.coverage > 0).any(axis=0) | (s.radiance != 0).any(axis=(0, 1)))
    if rows.size == 0:
        return None
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def _meets(a, b) -> bool:
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


def _pack(offsets: np.ndarray) -> np.ndarray:
    """Rows of small ints (n, m) -> one int64 key per row (unique rows <-> unique keys)."""
    low = int(offsets.min())
    span = int(offsets.max()) - low + 1
    if span ** offsets.shape[1] >= 2**62:
        return None
    key = np.zeros(offsets.shape[0], np.int64)
    for column in offsets.T:
        key = key * span + (column - low)
    return key


def _terms(offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct offset rows and each one's share of the rays."""
    key = _pack(offsets)
    if key is None:
        rows, counts = np.unique(offsets, axis=0, return_counts=True)
        return rows, counts / offsets.shape[0]
    _, first, counts = np.unique(key, return_index=True, return_counts=True)
    return offsets[first], counts / offsets.shape[0]


def _composite_layer(target: list[_Slice], occluders: list[list[_Slice]], window, pad: int, padded: dict,
                     density: dict) -> tuple:
    """Sum over pupil terms of ``sum_s C_s(x - n_s) prod_j (1 - A_j(x - n_j))`` on ``window``, and the same
    with the coverage ``A_s`` for ``C_s`` (the last plane): (C + 1, h, w), and the number of terms."""
    r0, r1, c0, c1 = window
    involved = target + [s for layer in occluders for s in layer]
    offsets = np.concatenate([s.offsets for s in involved], axis=1)  # (n_rays, 2 * slices)
    rows, weights = _terms(offsets)
    if len(rows) > MAX_TERMS:
        raise VissimInputError(f"a layer's occlusion needs {len(rows)} pupil terms (> {MAX_TERMS}); use fewer, "
                               "flatter layers")
    n_ch = target[0].radiance.shape[0] + 1
    out = np.zeros((n_ch, r1 - r0, c1 - c0), np.float64)
    sizes = [len(layer) for layer in occluders]
    scales = [None if density.get(layer[0].layer) is None else 1.0 / density[layer[0].layer][r0:r1, c0:c1]
              for layer in occluders]
    for row, weight in zip(rows, weights):
        shifts = row.reshape(-1, 2)
        transmitted = None
        at = len(target)
        for size, scale in zip(sizes, scales):
            cover = None
            for s, (dr, dc) in zip(involved[at : at + size], shifts[at : at + size]):
                part = padded[id(s)][1][r0 + pad - dr : r1 + pad - dr, c0 + pad - dc : c1 + pad - dc]
                cover = part.copy() if cover is None else cover + part
            if scale is not None:
                cover *= scale
            at += size
            np.subtract(1.0, cover, out=cover)
            np.clip(cover, 0.0, 1.0, out=cover)
            transmitted = cover if transmitted is None else transmitted * cover
        transmitted *= weight
        for s, (dr, dc) in zip(target, shifts[: len(target)]):
            colour = padded[id(s)][0][:, r0 + pad - dr : r1 + pad - dr, c0 + pad - dc : c1 + pad - dc]
            cover = padded[id(s)][1][r0 + pad - dr : r1 + pad - dr, c0 + pad - dc : c1 + pad - dc]
            out[:-1] += colour * transmitted
            out[-1] += cover * transmitted
    own = density.get(target[0].layer)
    if own is not None:
        out /= own[r0:r1, c0:c1]
    return out, len(rows)


def composite_layers(
    layers,
    *,
    rx: Prescription | None = None,
    pupil_diameter_mm: float | None = None,
    arcmin_per_px: float,
    accommodation_diopters: float | None = None,
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM,
    mode: str = "geometric",
    extra_wavefront: Wavefront | None = None,
    eye: DepthViewer | None = None,
    layer_spacing_fraction: float = DEFAULT_LAYER_SPACING_FRACTION,
    n_rays: int | None = None,
    crop_px: int = 0,
) -> LayeredBlurResult:
    """Blur a layered scene through an uncorrected eye, with exact occlusion in ray optics (module doc).

    Parameters
    ----------
    layers : sequence of SceneLayer
        Each layer alone on one pixel grid: premultiplied radiance (H, W) or (H, W, C), coverage
        (H, W) in [0, 1], proximity in dioptres (a value, or an (H, W) map for a slanted layer).
    rx
        The eye's prescription, as in `vissim.optics.depth.depth_map.blur_depth`.
    pupil_diameter_mm
        The eye's pupil, mm, as in `vissim.optics.depth.depth_map.blur_depth`.
    accommodation_diopters
        The eye's accommodation, D, as in `vissim.optics.depth.depth_map.blur_depth`.
    wavelength_nm
        The eye's wavelength, nm, as in `vissim.optics.depth.depth_map.blur_depth`.
    extra_wavefront
        The eye's further aberrations, as in `vissim.optics.depth.depth_map.blur_depth`.
    eye : DepthViewer, optional
        The eye as one object (`vissim.optics.rx.viewing_setup.DepthViewer`), instead of the four keywords above.
    mode : {"geometric", "wave"}
    layer_spacing_fraction : float
        A slanted layer's slices differ in blur by at most this many pixels.
    n_rays : int, optional
        Pupil rays (default: as the geometric PSF, 250 000 to 4 million with the blur's area).
    crop_px : int
        Pixels cut from every side of the result (the layers cover a margin beyond the frame).
    """
    eye = eye_of(eye, rx, pupil_diameter_mm, accommodation_diopters, extra_wavefront)
    pupil = eye.pupil_diameter_mm
    step = check_arcmin_per_px(arcmin_per_px)
    wavelength = check_wavelength_nm(wavelength_nm)
    eye.check_light(wavelength)
    if mode not in ("wave", "geometric"):
        raise VissimInputError(f"PSF mode must be 'wave' or 'geometric', got {mode!r}")
    checked, shape = _checked_layers(layers, crop_px)
    n_ch, rows, cols = checked[0][0].shape

    checked.sort(key=_depth_order, reverse=True)  # near (large proximity) first
    spacing = layer_spacing_diopters(step, pupil, layer_spacing_fraction)
    in_focus = eye.in_focus_proximity_diopters
    by_layer = [_slices(i, *item, spacing, in_focus) for i, item in enumerate(checked)]
    slices = [s for layer in by_layer for s in layer]
    fronts = {id(s): eye.wavefront_at(s.proximity_diopters) for s in slices}
    rays = _trace_slices(slices, fronts, pupil, step, wavelength, n_rays)

    density = {layer[0].layer: _density(layer) for layer in by_layer}
    geometric, transmission, n_terms, overlapping = _geometric_composite(by_layer, density, (n_ch, rows, cols), mode)
    if mode == "geometric":
        out = geometric
    else:
        out = _wave_composite(geometric, by_layer, density, transmission, fronts, pupil, wavelength, step)
    c = int(crop_px)
    out = out[:, c : rows - c, c : cols - c]
    image = out[0] if len(shape) == 2 else np.moveaxis(out, 0, -1)
    log.info("layered depth blur: %d layers, %d slices, %d rays, %d terms", len(by_layer), len(slices), len(rays[0]),
             n_terms)
    return LayeredBlurResult(np.ascontiguousarray(image, dtype=np.float32), len(by_layer), len(slices), len(rays[0]),
                             n_terms, overlapping, eye.accommodation_diopters, mode)


# -- the stages of composite_layers ---------------------------------------------------
def _checked_layers(layers, crop_px) -> tuple[list, tuple]:
    """Checks: each layer's (colour (C, H, W), coverage, proximity), and the radiance's shape (H, W[, C])."""
    layers = list(layers)
    if not layers:
        raise VissimInputError("a layered scene needs at least one layer")
    checked, shape = [], None
    for i, layer in enumerate(layers):
        colour, coverage, proximity = _check_layer(layer, shape, i)
        shape = np.asarray(layer.radiance).shape
        checked.append((colour, coverage, proximity))
    _, rows, cols = checked[0][0].shape
    if int(crop_px) != crop_px or crop_px < 0 or 2 * crop_px >= min(rows, cols):
        raise VissimInputError(f"crop_px must be whole pixels >= 0 leaving an image; got {crop_px!r} px")
    return checked, shape


def _depth_order(item) -> float:
    """A checked layer's coverage-weighted mean proximity (D): its place in the near-to-far order."""
    colour, coverage, proximity = item
    if proximity.ndim == 0 or coverage.sum() == 0:
        return float(proximity.mean())
    return float((proximity * coverage).sum() / coverage.sum())


def _trace_slices(slices: list[_Slice], fronts: dict, pupil: float, step: float, wavelength: float,
                  n_rays: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Each slice's rays' rounded offsets and their histogram PSF (set on the slices); the pupil rays.

    ``n_rays`` None: as the geometric PSF, 250 000 to 4 million with the widest blur's area.
    """
    if n_rays is None:
        blur_px = max(geometric_blur_radius_arcmin(f, pupil) for f in fronts.values()) / step
        n_rays = ray_count(blur_px)
    rays = stratified_pupil_rays(int(n_rays))
    for s in slices:
        s.offsets = _offsets_px(fronts[id(s)], pupil, step, rays)
        s.psf = _histogram_psf(s.offsets, step, pupil, wavelength)
    return rays


def _geometric_composite(by_layer: list[list[_Slice]], density: dict, shape: tuple[int, int, int], mode: str):
    """Ray optics: each layer blurred by one FFT, or composited term by term where a nearer layer overlaps it.

    Returns the composite (C, H, W), each overlapped layer's (visible, unoccluded blurred) coverage
    in wave mode (``tau_k``'s parts, module doc), the pupil terms composited and the layers overlapped.
    """
    n_ch, rows, cols = shape
    slices = [s for layer in by_layer for s in layer]
    reach = {id(s): int(np.abs(s.offsets).max()) for s in slices}
    boxes = {}
    for s in slices:
        box = _support(s)
        boxes[id(s)] = None if box is None else grow_box(box, reach[id(s)], (rows, cols))
    geometric = np.zeros((n_ch, rows, cols), np.float64)
    transmission = {}  # layer -> (visible coverage V_k, unoccluded blurred coverage A_k * G_k) on its window
    pad = max(reach.values()) + 1
    padded = {id(s): (np.pad(s.radiance, ((0, 0), (pad, pad), (pad, pad))), np.pad(s.coverage, pad)) for s in slices}
    n_terms = overlapping = 0
    for k, layer in enumerate(by_layer):
        own = [boxes[id(s)] for s in layer if boxes[id(s)] is not None]
        if not own:
            continue
        window = (min(b[0] for b in own), max(b[1] for b in own), min(b[2] for b in own), max(b[3] for b in own))
        occluders = [[s for s in nearer if boxes[id(s)] is not None and _meets(boxes[id(s)], window)]
                     for nearer in by_layer[:k]]
        occluders = [o for o in occluders if o]
        if not occluders:
            light = sum(_fft_blur(s.radiance, s.psf) for s in layer)
            geometric += light if density[k] is None else light / density[k]
            continue
        part, terms = _composite_layer(layer, occluders, window, pad, padded, density)
        r0, r1, c0, c1 = window
        geometric[:, r0:r1, c0:c1] += part[:-1]
        if mode == "wave":
            whole = sum(_fft_blur(s.coverage[np.newaxis], s.psf)[0] for s in layer)
            whole = whole if density[k] is None else whole / density[k]
            visible = np.zeros((rows, cols))
            visible[r0:r1, c0:c1] = part[-1]
            transmission[k] = (visible, whole)
        n_terms += terms
        overlapping += 1
    return geometric, transmission, n_terms, overlapping


def _wave_composite(geometric: np.ndarray, by_layer: list[list[_Slice]], density: dict, transmission: dict,
                    fronts: dict, pupil: float, wavelength: float, step: float) -> np.ndarray:
    """Wave optics: the ray composite diffracted by the pupil in focus, plus each layer's wave PSF's
    excess over its diffracted ray disc, dimmed by ``tau_k`` (module doc)."""
    diffraction = _wave_psf(Wavefront.zero(pupil), pupil, wavelength, step)  # what the aperture's diffraction adds
    out = _fft_blur(geometric.astype(np.float32), diffraction)
    for k, layer in enumerate(by_layer):
        residual = sum(_fft_blur(s.radiance, _wave_psf(fronts[id(s)], pupil, wavelength, step))
                       - _fft_blur(_fft_blur(s.radiance, s.psf).astype(np.float32), diffraction) for s in layer)
        if density[k] is not None:
            residual = residual / density[k]
        if k in transmission:
            visible, whole = (_fft_blur(a[np.newaxis].astype(np.float32), diffraction)[0] for a in transmission[k])
            tau = np.where(whole > 1e-6, visible / np.maximum(whole, 1e-6), 1.0)
            residual = residual * np.clip(tau, 0.0, 1.0)
        out += residual
    return out


def _fft_blur(colour: np.ndarray, psf: PSF) -> np.ndarray:
    """(C, H, W) blurred by ``psf`` with zero padding (nothing lies beyond a layer's grid)."""
    image = np.moveaxis(colour, 0, -1)
    blurred = blur_image(image, psf, arcmin_per_px=psf.arcmin_per_px, padding="constant", background=0.0,
                         dtype=np.float64)
    return np.moveaxis(blurred, -1, 0)


def _wave_psf(front: Wavefront, pupil_mm: float, wavelength_nm: float, step: float) -> PSF:
    # size_px=None passed as psfs.LayerOptics passes it: lru_cache keys an omitted argument apart
    return cached_psf(tuple(front.coefficients_um.items()), pupil_mm, wavelength_nm, step, "wave", None)
