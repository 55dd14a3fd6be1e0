"""One Mitsuba render whose pixels do not depend on thread timing: `render_image`.

Why: on the JIT variants Mitsuba's ``SamplingIntegrator::render`` adds every sample into the
film with an atomic scatter-add.  Dr.Jit's LLVM backend runs the kernel as blocks of 16384
samples (or ``cores`` blocks when the wavefront is small) on a thread pool; when ``spp`` does
not divide the block, the samples of one pixel fall in two blocks, two threads add partial
sums into it in a racing order, and float32 rounding makes the pixel differ from run to run
(the bench at 132 spp: a few pixels per image, up to 6e-7).  Power-of-two ``spp`` only hid it.

`render_image` does what that render does -- the same sampler calls in the same order,
the same rays, the same ``integrator.sample`` -- but keeps each sample's channels and sums the
``spp`` samples of a pixel in NumPy (float64, a fixed order), then develops the film as Mitsuba
does.  At 1 spp it equals ``mi.render`` bit for bit (tests/render/test_determinism.py).

`render_samples` returns the samples themselves (each pixel's R, G, B per sample, before any
sum), for statistics other than the film's mean (`vissim.render.run`).  Mitsuba's films only
average (a weighted sum over the reconstruction filter); on scalar variants with a box filter it
takes ``spp`` one-sample renders instead (a one-sample box-filtered pixel is its sample).

Scalar variants keep ``mi.render``: one thread renders each 32 x 32 tile, and with a box filter
each pixel lies in one tile, so its sum has a fixed order already.  Scenes this module cannot
reproduce (another filter, a sampled border, a special film, an integrator other than ``path``
or ``direct``, e.g. ``aov``) go to ``mi.render`` and are recorded as not deterministic on JIT
variants.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from vissim.checks import size_text
from vissim.errors import VissimInputError

__all__ = ["Rendered", "Samples", "accumulation", "pass_seeds", "promises_determinism", "render_image", "render_samples"]

log = logging.getLogger(__name__)

#: C++ integrators that keep SamplingIntegrator::render (``aov`` overrides it, ``ptracer`` is adjoint).
FIXED_ORDER_INTEGRATORS = ("PathIntegrator", "DirectIntegrator")

#: Largest wavefront (samples in one pass) a JIT variant indexes with 32-bit integers.
MAX_WAVEFRONT = 0xFFFFFFFF


@dataclass(frozen=True)
class Rendered:
    """A developed film ``image`` (H, W, C) float32, the spp the sampler took, and how."""

    image: np.ndarray
    spp: int
    accumulation: str  # see accumulation()
    deterministic: bool


@dataclass(frozen=True)
class Samples:
    """Each pixel's samples: ``values`` (H * W, spp, 3) float32 R, G, B, row-major pixels; how they were taken."""

    values: np.ndarray
    spp: int
    accumulation: str
    deterministic: bool



def pass_seeds(seed: int, passes: int) -> list[int]:
    """Sampler seeds of the passes: one pass keeps ``seed``; more draw from SeedSequence([seed, i])."""
    if passes == 1:
        return [int(seed)]
    return [int(np.random.SeedSequence([int(seed), i]).generate_state(1)[0]) for i in range(passes)]

def promises_determinism(variant: str, method: str) -> bool:
    """Whether renders on ``variant`` accumulated by ``method`` (`accumulation`) are bit-identical per seed.

    Verified (tests/render/test_determinism.py): ``llvm_*`` with "fixed-order" sums, ``scalar_*``
    with "tiles".  CUDA uses the same fixed-order sums but is untested here: not promised.
    """
    if variant.startswith("scalar_"):
        return method == "tiles"
    return variant.startswith("llvm_") and method == "fixed-order"


def accumulation(mi, scene) -> str:
    """How a render of ``scene`` sums samples: "fixed-order" (`render_image` itself, JIT
    variants), "tiles" (Mitsuba's scalar render, each pixel in one tile) or "mitsuba" (anything else:
    atomic or overlapping adds)."""
    sensor = scene.sensors()[0]
    film, integrator = sensor.film(), scene.integrator()
    box = film.rfilter().is_box_filter() and not film.sample_border()
    if mi.variant().startswith("scalar_"):
        return "tiles" if box and isinstance(integrator, mi.SamplingIntegrator) else "mitsuba"
    ok = (box and not mi.has_flag(film.flags(), mi.FilmFlags.Special)
          and integrator.class_name() in FIXED_ORDER_INTEGRATORS)
    return "fixed-order" if ok else "mitsuba"


def render_image(mi, scene, spp: int, seed: int) -> Rendered:
    """Render ``scene`` (loaded) with ``spp`` samples per pixel from ``seed`` (module doc)."""
    method = accumulation(mi, scene)
    if method != "fixed-order":
        if method == "mitsuba":
            log.debug("%s: Mitsuba's atomic film adds, not bit-identical per seed", scene.integrator().class_name())
        image = np.asarray(mi.render(scene, spp=int(spp), seed=int(seed)), dtype=np.float32)
        used = int(scene.sensors()[0].sampler().sample_count())
        return Rendered(image, used, method, promises_determinism(mi.variant(), method))
    import drjit as dr

    with dr.suspend_grad():
        image, used = _fixed_order(mi, dr, scene, int(spp), int(seed))
    return Rendered(image, used, method, promises_determinism(mi.variant(), method))


def render_samples(mi, scene, spp: int, seed: int) -> Samples:
    """The R, G, B of each of ``spp`` samples per pixel of ``scene`` (loaded) from ``seed`` (module doc)."""
    method = accumulation(mi, scene)
    if method == "fixed-order":
        import drjit as dr

        with dr.suspend_grad():
            channels, _, film, spp = _trace(mi, dr, scene, int(spp), int(seed))
            width, height = (int(v) for v in film.crop_size())
            values = np.stack([np.broadcast_to(np.asarray(c, dtype=np.float32), (width * height * spp,))
                               for c in channels[:3]], axis=-1)
        return Samples(values.reshape(width * height, spp, 3), spp, method,
                       promises_determinism(mi.variant(), method))
    if method != "tiles":  # a wider filter spreads a sample over several pixels: no pixel holds one sample
        raise VissimInputError("per-sample values need a box filter without a sampled border and a path or "
                               "direct integrator")
    renders = []
    for sample_seed in pass_seeds(seed, int(spp)):  # one-sample passes
        image = np.asarray(mi.render(scene, spp=1, seed=sample_seed), dtype=np.float32)
        image = np.repeat(image, 3, axis=2) if image.ndim == 3 and image.shape[2] == 1 else image
        renders.append(image.reshape(-1, image.shape[2])[:, :3])
    return Samples(np.stack(renders, axis=1), int(spp), method, promises_determinism(mi.variant(), method))


def _trace(mi, dr, scene, spp: int, seed: int):
    """Every sample's film channels (R, G, B, [A], W, AOVs; evaluated), the weight's index, the film, the spp."""
    # Mirrors SamplingIntegrator::render + render_sample (Mitsuba 3.9, one pass, JIT branch).
    sensor = scene.sensors()[0]
    film, sampler, integrator = sensor.film(), sensor.sampler(), scene.integrator()
    sampler.set_sample_count(spp)
    spp = int(sampler.sample_count())
    width, height = (int(v) for v in film.crop_size())
    n_pixels = width * height
    wavefront = n_pixels * spp
    if wavefront > MAX_WAVEFRONT:
        raise VissimInputError(f"{size_text((height, width))} at {spp} spp is {wavefront} samples in one pass, over "
                               f"2^32; render in passes (pass_spp)")
    film.prepare(integrator.aov_names())
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(dr.opaque(mi.UInt32, seed), wavefront)  # opaque: one kernel for every seed

    idx = dr.arange(mi.UInt32, wavefront) // dr.opaque(mi.UInt32, spp)
    row = idx // width
    pos = mi.Vector2i(mi.Int32(idx - row * width), mi.Int32(row)) + mi.Vector2i(film.crop_offset())
    scale = dr.rcp(mi.ScalarVector2f(film.crop_size()))
    offset = -mi.ScalarVector2f(film.crop_offset()) * scale
    sample_pos = mi.Vector2f(pos) + sampler.next_2d()
    aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
    time_s = mi.Float(sensor.shutter_open())
    if sensor.shutter_open_time() > 0:
        time_s += sampler.next_1d() * sensor.shutter_open_time()
    wavelength_sample = sampler.next_1d() if mi.is_spectral else mi.Float(0.0)
    ray, ray_weight = sensor.sample_ray_differential(time_s, wavelength_sample, dr.fma(sample_pos, scale, offset),
                                                     aperture)
    if ray.has_differentials:
        ray.scale_differential(dr.rsqrt(float(spp)))
    spec, valid, aovs = integrator.sample(scene, sampler, ray, sensor.get_medium(), True)
    spec_u = mi.unpolarized_spectrum(ray_weight * spec)
    if mi.is_spectral:
        rgb = mi.spectrum_to_srgb(spec_u, ray.wavelengths)
    elif mi.is_monochromatic:
        rgb = mi.Color3f(spec_u.x)
    else:
        rgb = spec_u
    has_alpha = mi.has_flag(film.flags(), mi.FilmFlags.Alpha)
    alpha = [dr.select(valid, mi.Float(1.0), mi.Float(0.0))] if has_alpha else []
    channels = [rgb.x, rgb.y, rgb.z, *alpha, mi.Float(1.0), *aovs]  # R, G, B, [A], W, AOVs
    weight_channel = 4 if has_alpha else 3
    if film.create_block().channel_count() != len(channels):
        raise VissimInputError(f"film {film.class_name()} has {film.create_block().channel_count()} channels, "
                               f"expected {len(channels)} (R, G, B, [A], W, AOVs)")
    dr.eval(channels)
    return channels, weight_channel, film, spp


def _fixed_order(mi, dr, scene, spp: int, seed: int) -> tuple[np.ndarray, int]:
    channels, weight_channel, film, spp = _trace(mi, dr, scene, spp, seed)
    width, height = (int(v) for v in film.crop_size())
    n_pixels = width * height
    means = np.empty((n_pixels, len(channels)), dtype=np.float32)
    done: dict[int, np.ndarray] = {}
    for k, channel in enumerate(channels):
        if k == weight_channel:
            means[:, k] = 1.0  # the film divides by W: put means, weight 1
            continue
        if channel.index not in done:
            values = np.asarray(channel)
            if values.size == 1:  # a literal: every sample alike
                done[channel.index] = np.full(n_pixels, values[0], dtype=np.float32)
            else:
                done[channel.index] = values.reshape(n_pixels, spp).mean(axis=1, dtype=np.float64).astype(np.float32)
        means[:, k] = done[channel.index]
    block = mi.ImageBlock(mi.TensorXf(means.reshape(height, width, len(channels))), film.crop_offset(),
                          film.rfilter())
    film.put_block(block)
    return np.asarray(film.develop(), dtype=np.float32), spp
