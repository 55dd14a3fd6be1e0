"""The ATV tube rendered two ways: light tracing from the pixel (primary) and a camera-side check.

**Light tracing** (`trace_atv`).  Rays start on the lit pixel (a Lambertian square of
radiance L) and are traced through the Mitsuba scene of `vissim.bench.atv.scene.atv_scene` with
``scene.ray_intersect`` (vectorised Dr.Jit arrays), refracting by vector Snell's law at every
lens hit with the mesh's interpolated vertex normal ``si.sh_frame.n`` (the exact analytic
normal at the vertices; ``si.n`` is the flat face normal), oriented against the ray.  Hits on
the tube, the pixel or a lens rim (``|n_z| < 0.5``) absorb the ray, as does total internal
reflection; with ``config.fresnel_loss`` each refraction weighs the ray by the unpolarised
Fresnel transmittance (deterministic, no reflected rays).  Rays leaving the tube are carried
to the pupil plane z = 0; inside the pupil the eye is a thin lens: the ray through pupil point
x (mm) with direction tangent u lands at visual angle ``-u + (E + A) x`` mrad, and its flux is
binned onto the arcmin grid (row 0 up, columns to the eye's right = world -x).

Sampling: scrambled Sobol points (`scipy.stats.qmc.Sobol`, seeded; ``n_rays`` is rounded
up to a power of two), dimensions 0-1 the direction and 2-3 the point on the pixel.  Directions
are cosine-distributed over a cone -- a disc of direction cosines -- around the paraxial
direction to the pupil, just wide enough that every ray able to reach the pupil is sampled
(`cone_radius_rad` x 1.05 + 0.1 mrad; a ray in the pupil
from the cone's outer 2 % widens the cone and traces again).  Each ray carries
``L x pixel area x pi sin^2(cone) / n_rays``, so image pixels hold flux per arcmin²
(`vissim.atv.predict`).  Putting the direction first in the Sobol sequence cut the
noise at the blur plateau by 1.7x against pseudo-random sampling (3.6 % vs 6.1 % at ~260 rays
per pixel); the pixel dimensions, spread over ~4 image pixels, gain nothing.

**Camera side** (`render_atv_camera`).  The eye is Mitsuba's ``thinlens`` (aperture radius
pupil / 2, focused where the eye is), the lenses use ``vissim_refract`` and a ``path`` integrator
without Russian roulette finds the pixel by chance: noisy, since each camera ray must land on a
78 µm square through the lenses.  Light tracing cannot do this side's job in Mitsuba (its
particle tracer returns nothing through smooth glass and does not connect to a thin-lens
sensor), and vice versa: so both exist, one checking the other.

**Measured** (llvm_ad_mono, 2 shared cores at load 2-5; 4 mm pupil, 0.5'/px unless stated).
Light tracing: 2^18 rays 0.3-0.6 s, 2^20 rays 1.1-3 s, 2^22 rays 5-14 s per configuration; against
2^24-ray references (in focus, +2 D, -4 D) the smoothed peak is within 0.2 % at 2^18 rays,
0.07 % at 2^20 and 0.01 % at 2^22, the spot diameter within 0.1 % and the flux within 0.01 %;
the largest raw pixel is 10-20 % high at 2^20 (noise bias).  Camera side, +2 D at 1'/px on a
37 px field: 8192 spp in 45 s gives 12 % noise per pixel, 32768 spp in 73 s 6 %; flux within
0.2-0.4 % and spot diameter within 0.3-0.5 % of the tracer, annulus means within 2 sigma; in
focus it is nearly noise-free (64 spp, 0.4 s).  Hence light tracing is the primary method.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, dataclass

import numpy as np

from vissim.bench.atv.spot import spot_metrics, suggested_atv_size_px
from vissim.bench.atv.tube import AtvConfig
from vissim.bench.atv.paraxial import atv_paraxial
from vissim.bench.atv.scene import atv_scene
from vissim.errors import VissimError, VissimInputError
from vissim.lazy_import import lazy_module
from vissim.render.backend import mitsuba
from vissim.render.plugins import register_plugins
from vissim.render.run import pass_seeds, render_scene, to_mitsuba_dict
from vissim.units import ARCMIN_PER_RAD, arcmin_to_rad, mm_to_m

stats = lazy_module("scipy.stats")

__all__ = ["AtvResult", "trace_atv", "render_atv_camera", "DEFAULT_N_RAYS"]

log = logging.getLogger(__name__)

DEFAULT_N_RAYS = 1 << 22
_BATCH_RAYS = 1 << 21
_CONE_MARGIN = 1.05
_CONE_PAD_RAD = 1.0e-4
_CONE_FILL_LIMIT = 0.98
_START_OFFSET_MM = 1.0e-3
_RIM_NORMAL_Z = 0.5


@dataclass(frozen=True, eq=False)
class AtvResult:
    """A rendered retinal image of the pixel: flux per arcmin² (float32, vissim grid) and metrics.

    ``std_image`` is the per-pixel standard error (light tracing: the Monte Carlo estimate
    sqrt(sum w²), an upper bound for the Sobol sampling; camera: the spread of independent
    passes).  ``total_flux`` counts all light in the pupil (tracer) or the field (camera);
    ``peak`` (the largest value after a light smoothing that removes sampling noise),
    ``peak_pixel`` and ``spot_diameter_arcmin`` (the radial-profile FWHM) are defined in
    `vissim.bench.atv.spot.spot_metrics`.
    """

    image: np.ndarray
    std_image: np.ndarray
    arcmin_per_px: float
    total_flux: float
    peak: float
    peak_pixel: float
    peak_relative_std: float
    spot_diameter_arcmin: float
    centroid_arcmin: tuple[float, float]
    n_rays: int
    seconds: float
    method: str
    seed: int
    variant: str
    mitsuba_version: str
    config: AtvConfig

    def summary(self) -> dict:
        """Plain JSON-ready numbers (what ``vissim render atv --json`` prints)."""
        return {
            "method": self.method,
            "peak_irradiance_per_arcmin2": self.peak,
            "peak_relative_std": self.peak_relative_std,
            "peak_pixel_per_arcmin2": self.peak_pixel,
            "spot_diameter_arcmin": self.spot_diameter_arcmin,
            "spot_diameter_definition": "FWHM of the azimuthally averaged radial profile",
            "total_flux": self.total_flux,
            "centroid_arcmin": list(self.centroid_arcmin),
            "arcmin_per_px": self.arcmin_per_px,
            "size_px": list(self.image.shape),
            "n_rays": self.n_rays,
            "seed": self.seed,
            "seconds": self.seconds,
            "variant": self.variant,
            "mitsuba_version": self.mitsuba_version,
        }


def _atv_result(image: np.ndarray, std_image: np.ndarray, step: float, *, total_flux: float | None = None,
                **run) -> AtvResult:
    """``image`` and its standard error with their spot metrics; ``total_flux`` None: the image's integral.

    ``run`` holds the remaining `AtvResult` fields (how the image was made).
    """
    metrics = asdict(spot_metrics(image, step, std_image))  # SpotMetrics' fields are AtvResult's, but one
    del metrics["peak_smoothing_px"]
    if total_flux is not None:
        metrics["total_flux"] = total_flux
    return AtvResult(image=image, std_image=std_image, arcmin_per_px=step, **metrics, **run)


def _check_sampling(arcmin_per_px, size_px, config: AtvConfig) -> tuple[float, int]:
    try:
        step = float(arcmin_per_px)
    except (TypeError, ValueError):
        step = math.nan
    if not math.isfinite(step) or step <= 0.0:
        raise VissimInputError(f"angular sampling must be > 0 arcmin per pixel, got {arcmin_per_px!r}")
    size = suggested_atv_size_px(config, step) if size_px is None else size_px
    if not isinstance(size, (int, np.integer)) or not 1 <= size <= 8192:
        raise VissimInputError(f"image size must be a whole number of pixels in 1-8192, got {size_px!r}")
    return step, int(size)


def _concentric_disc(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shirley-Chiu map of the unit square onto the unit disc: (x, y, radius)."""
    a, b = 2.0 * a - 1.0, 2.0 * b - 1.0
    first = np.abs(a) > np.abs(b)
    radius = np.where(first, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(first, (math.pi / 4.0) * (b / a), math.pi / 2.0 - (math.pi / 4.0) * (a / b))
    phi = np.where((a == 0.0) & (b == 0.0), 0.0, phi)
    return radius * np.cos(phi), radius * np.sin(phi), np.abs(radius)


class _Tracer:
    """The scene loaded once; `batch` traces one batch of pixel rays to the pupil."""

    def __init__(self, config: AtvConfig, variant: str | None):
        self.mi = mitsuba("mono", variant)
        if self.mi.variant().startswith("scalar"):
            raise VissimError(
                f"the ATV light tracer needs a vectorised Mitsuba variant (llvm_ad_* or cuda_ad_*), not "
                f"{self.mi.variant()}; install LLVM >= 16 (e.g. Debian's libllvm19)")
        import drjit as dr

        self.dr = dr
        register_plugins(self.mi)
        # optimize=False: Mitsuba would merge lenses of equal BSDF into one shape.
        self.scene = self.mi.load_dict(to_mitsuba_dict(atv_scene(config, camera=False), self.mi), optimize=False)
        indices = {"collimator": config.tube.lens_refractive_index}
        if config.trial_lens is not None:
            indices["trial_lens"] = config.trial_lens.refractive_index
        self.lenses = [(self.mi.ShapePtr(s), indices[s.id()]) for s in self.scene.shapes() if s.id() in indices]
        if len(self.lenses) != len(indices):  # pragma: no cover - optimize=False keeps them apart
            raise VissimError(f"the ATV scene lost its lens shapes ({', '.join(indices)}) on loading")
        self.max_events = 2 * len(self.lenses) + 2
        self.fresnel = config.fresnel_loss
        self.start_z = config.layout().phone_z_mm - _START_OFFSET_MM
        self.radius_mm = 0.5 * config.eye.pupil_diameter_mm
        self.eye_matrix = np.asarray(config.eye.viewing_setup().defocus_matrix_diopters)
        self.dropped = 0

    def batch(self, x0, y0, dx, dy):
        """Visual angles (rad, world x/y), weights and in-pupil mask of rays from (x0, y0) along (dx, dy)."""
        mi, dr = self.mi, self.dr
        n = len(x0)
        d = mi.Vector3f(mi.Float(dx), mi.Float(dy), mi.Float(-np.sqrt(1.0 - dx * dx - dy * dy)))
        ray = mi.Ray3f(mi.Point3f(mi.Float(x0), mi.Float(y0), dr.full(mi.Float, self.start_z, n)), d)
        active = dr.full(mi.Bool, True, n)
        weight = dr.full(mi.Float, 1.0, n)
        hit = active
        for _ in range(self.max_events):
            si = self.scene.ray_intersect(ray, active)
            hit = active & si.is_valid()
            glass = dr.full(mi.Float, 1.0, n)
            lens = dr.full(mi.Bool, False, n)
            for shape, index in self.lenses:
                on = hit & (si.shape == shape)
                lens |= on
                glass = dr.select(on, index, glass)
            normal = si.sh_frame.n
            refract = lens & (dr.abs(normal.z) >= _RIM_NORMAL_Z)
            exiting = dr.dot(ray.d, normal) > 0.0
            normal = dr.select(exiting, -normal, normal)
            eta = dr.select(exiting, glass, 1.0 / glass)  # n_incident / n_transmitted
            cos_i = -dr.dot(ray.d, normal)
            k = 1.0 - eta * eta * (1.0 - cos_i * cos_i)
            go = refract & (k >= 0.0)
            cos_t = dr.sqrt(dr.maximum(k, 0.0))
            new_d = dr.normalize(eta * ray.d + (eta * cos_i - cos_t) * normal)
            if self.fresnel:
                n_i, n_t = dr.select(exiting, glass, 1.0), dr.select(exiting, 1.0, glass)
                rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t)
                rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t)
                weight = dr.select(go, weight * (1.0 - 0.5 * (rs * rs + rp * rp)), weight)
            spawned = si.spawn_ray(new_d)
            ray = mi.Ray3f(dr.select(go, spawned.o, ray.o), dr.select(go, new_d, ray.d))
            active = active & (~hit | go)  # tube, pixel, rims and total internal reflection absorb
            dr.eval(ray, active, weight)
            if not dr.any(hit & go):
                break
        leaving = active & ~hit & (ray.d.z < 0.0)
        self.dropped += int(np.count_nonzero(np.asarray(active & hit, dtype=bool)))
        t = -ray.o.z / ray.d.z
        xp, yp = ray.o.x + t * ray.d.x, ray.o.y + t * ray.d.y
        ox, oy, dxo, dyo, dzo = (np.asarray(v, dtype=np.float64) for v in (xp, yp, ray.d.x, ray.d.y, ray.d.z))
        keep = np.asarray(leaving, dtype=bool) & (ox * ox + oy * oy <= self.radius_mm**2)
        w = np.asarray(weight, dtype=np.float64)[keep]
        xp_mm = np.stack([ox[keep], oy[keep]])
        tangent = np.stack([dxo[keep], dyo[keep]]) / -dzo[keep]
        visual = -tangent + 1.0e-3 * (self.eye_matrix @ xp_mm)  # rad; D x mm = mrad
        return visual, w, keep


def _bin(visual_rad, weights, step_arcmin, size) -> tuple[np.ndarray, np.ndarray, int]:
    """(flux, sum of squared weights) per pixel; count of rays outside the field."""
    col = np.floor(-visual_rad[0] * ARCMIN_PER_RAD / step_arcmin + 0.5).astype(np.int64) + size // 2
    row = np.floor(-visual_rad[1] * ARCMIN_PER_RAD / step_arcmin + 0.5).astype(np.int64) + size // 2
    inside = (col >= 0) & (col < size) & (row >= 0) & (row < size)
    flat = row[inside] * size + col[inside]
    w = weights[inside]
    out = [np.bincount(flat, weights=v, minlength=size * size).reshape(size, size) for v in (w, w * w)]
    return out[0], out[1], int((~inside).sum())


def trace_atv(config: AtvConfig, *, n_rays: int = DEFAULT_N_RAYS, seed: int = 0, arcmin_per_px: float = 0.5,
              size_px: int | None = None, variant: str | None = None) -> AtvResult:
    """Light-trace the ATV tube (module doc): the retinal image of the pixel, flux per arcmin².

    ``n_rays`` (rounded up to a power of two) are emitted into the cone that reaches the pupil;
    ``size_px`` defaults to `vissim.bench.atv.spot.suggested_atv_size_px`.
    """
    if not isinstance(config, AtvConfig):
        raise VissimInputError(f"trace_atv needs an AtvConfig, got {type(config).__name__}")
    if not isinstance(n_rays, (int, np.integer)) or not 1 <= n_rays <= 1 << 34:
        raise VissimInputError(f"n_rays must be a whole number of rays in 1-2^34, got {n_rays!r}")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise VissimInputError(f"seed must be a whole number >= 0, got {seed!r}")
    step, size = _check_sampling(arcmin_per_px, size_px, config)
    start = time.perf_counter()
    total_rays = 1 << max(0, int(n_rays - 1).bit_length())
    tracer = _Tracer(config, variant)
    par = atv_paraxial(config)
    pitch = config.tube.pixel_pitch_mm
    offset = np.asarray(config.tube.pixel_offset_mm)
    cone = _CONE_MARGIN * par.cone_radius_rad + _CONE_PAD_RAD
    radiance = config.tube.pixel_radiance
    while True:
        sobol = stats.qmc.Sobol(4, scramble=True, seed=int(seed))
        flux, flux_sq = np.zeros((size, size)), np.zeros((size, size))
        in_pupil, outside, total, fill = 0, 0, 0.0, 0.0
        per_ray = radiance * mm_to_m(pitch) ** 2 * math.pi * cone**2 / total_rays
        for first in range(0, total_rays, _BATCH_RAYS):
            u = sobol.random(min(_BATCH_RAYS, total_rays - first))
            ex, ey, rho = _concentric_disc(u[:, 0], u[:, 1])
            x0 = offset[0] + (u[:, 2] - 0.5) * pitch
            y0 = offset[1] + (u[:, 3] - 0.5) * pitch
            visual, w, keep = tracer.batch(x0, y0, par.cone_center[0] + cone * ex, par.cone_center[1] + cone * ey)
            if keep.any():
                fill = max(fill, float(rho[keep].max()))
            w = w * per_ray
            f, f2, out = _bin(visual, w, step, size)
            flux += f
            flux_sq += f2
            outside += out
            in_pupil += int(keep.sum())
            total += float(w.sum())
        if fill <= _CONE_FILL_LIMIT or cone >= 0.5:
            break
        log.warning("rays from the edge of the %.4g rad sampling cone reach the pupil; widening it 1.5x", cone)
        cone *= 1.5
    if tracer.dropped:
        log.warning("%d rays were still bouncing after %d surface events and were dropped",
                    tracer.dropped, tracer.max_events)
    area = step * step
    if total > 0.0 and outside / max(in_pupil, 1) > 0.01:
        log.warning("%.1f %% of the rays in the pupil land outside the %d px field", 100.0 * outside / in_pupil, size)
    seconds = time.perf_counter() - start
    result = _atv_result((flux / area).astype(np.float32), (np.sqrt(flux_sq) / area).astype(np.float32), step,
                         total_flux=total, n_rays=total_rays, seconds=seconds, method="trace", seed=int(seed),
                         variant=tracer.mi.variant(), mitsuba_version=tracer.mi.__version__, config=config)
    log.info("traced %d rays (%d in the pupil) on %s in %.2f s: flux %.4g, spot %.3g arcmin",
             total_rays, in_pupil, tracer.mi.variant(), seconds, total, result.spot_diameter_arcmin)
    return result


def render_atv_camera(config: AtvConfig, *, spp: int = 1024, seed: int = 0, arcmin_per_px: float = 1.0,
                      size_px: int | None = None, passes: int = 4, variant: str | None = None) -> AtvResult:
    """Render the tube from the eye's side (module doc): ``passes`` independent renders of ``spp / passes``.

    Pixel values are radiance averaged over the pupil and the pixel's solid angle; times the
    pupil area (m²) and the solid angle of one arcmin² they become flux per arcmin², like
    `trace_atv`.  The standard error comes from the spread of the passes.
    """
    if not isinstance(config, AtvConfig):
        raise VissimInputError(f"render_atv_camera needs an AtvConfig, got {type(config).__name__}")
    if not isinstance(passes, (int, np.integer)) or passes < 2:
        raise VissimInputError(f"passes must be a whole number >= 2 (for the noise estimate), got {passes!r}")
    if not isinstance(spp, (int, np.integer)) or spp < passes:
        raise VissimInputError(f"spp must be a whole number of samples per pixel >= passes ({passes}), got {spp!r}")
    step, size = _check_sampling(arcmin_per_px, size_px, config)
    odd = size | 1  # the axis on a pixel centre; an even size drops the last row and column
    start = time.perf_counter()
    per_pass = [spp // passes + (1 if i < spp % passes else 0) for i in range(passes)]
    renders, used_variant = [], ""
    for count, pass_seed in zip(per_pass, pass_seeds(int(seed), passes)):
        scene = atv_scene(config, camera=True, arcmin_per_px=step, size_px=odd, spp=count, seed=pass_seed)
        result = render_scene(scene, kind="mono", spp=count, seed=pass_seed, variant=variant)
        renders.append(np.asarray(result.pixels, dtype=np.float64)[:size, :size])
        used_variant = result.variant
    weights = np.asarray(per_pass, dtype=float)[:, None, None]
    stack = np.stack(renders)
    mean = (stack * weights).sum(axis=0) / weights.sum()
    spread = np.sqrt(((stack - mean) ** 2 * weights).sum(axis=0) / weights.sum() / (passes - 1))
    to_flux = math.pi / 4.0 * mm_to_m(config.eye.pupil_diameter_mm) ** 2 * float(arcmin_to_rad(1.0)) ** 2
    seconds = time.perf_counter() - start
    log.info("camera-side ATV render: %d x %d px, %d spp in %d passes on %s, %.1f s", size, size, spp, passes,
             used_variant, seconds)
    return _atv_result((mean * to_flux).astype(np.float32), (spread * to_flux).astype(np.float32), step,
                       n_rays=int(spp) * odd * odd, seconds=seconds, method="camera", seed=int(seed),
                       variant=used_variant, mitsuba_version=mitsuba("mono", variant).__version__, config=config)
