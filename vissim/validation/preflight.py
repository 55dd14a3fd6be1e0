"""Memory a campaign's items will need, estimated from their settings before anything is allocated.

The estimates are rough upper bounds of the largest single step (a bench render, a PSF, one
blurred image), enough to refuse a campaign that cannot fit (a 1e9 px tile, a PSF wider than
the tile by orders of magnitude) with a message saying what it would need, before a file is
written.  The machine's memory is :func:`vissim.checks.check_allocation`'s.
"""

from __future__ import annotations

from vissim.checks import check_allocation
from vissim.errors import VissimInputError
from vissim.optics.psf import (
    geometric_blur_radius_arcmin,
    psf_sampling,
    suggested_size_px,
)
from vissim.optics.wavefront import Wavefront

__all__ = ["render_memory_bytes", "item_memory_bytes", "check_campaign_memory", "check_depth_campaign_memory"]

#: Mitsuba's state per sample in flight (ray, sampler, film sample), bytes: a generous guess.
BYTES_PER_RENDER_SAMPLE = 256
#: Samples per render pass (vissim.render.run.DEFAULT_PASS_SAMPLES; not imported: it loads Mitsuba).
RENDER_PASS_SAMPLES = 1 << 22
#: Blurring one pixel: the float64 padded image, its complex128 spectrum, the product, the result.
BYTES_PER_BLUR_PX = 64
#: A wave PSF's FFT grid point (complex128 field and spectrum, float64 intensity).
BYTES_PER_FFT_PX = 48
#: A geometric PSF's pixel (float64 accumulators).
BYTES_PER_PSF_PX = 32
#: vissim.optics.psf.compute_psf refuses larger fields.
MAX_PSF_PX = 16384
#: The bench's chart texture: texels per camera pixel (DslrBench.texels_per_px) and bytes per texel.
TEXELS_PER_PX = 4.0
BYTES_PER_TEXEL = 12
#: Layered depth blur, per pixel of the (oversampled) image: layers' images, masks and spectra.
BYTES_PER_DEPTH_PX = 256


def render_memory_bytes(n_pixels: float, spp: int) -> float:
    """One render: the samples of one pass in flight and the float64 accumulator."""
    in_flight = n_pixels * min(spp, max(1, RENDER_PASS_SAMPLES // max(int(n_pixels), 1)))
    return in_flight * BYTES_PER_RENDER_SAMPLE + n_pixels * 8 * 2


def _psf_bytes(front: Wavefront, pupil_mm: float, step: float, wavelength_nm: float, mode: str) -> tuple[float, int]:
    size = suggested_size_px(front, step, wavelength_nm=wavelength_nm)
    if size > MAX_PSF_PX:
        raise VissimInputError(f"its PSF would be {size} px wide at {step:.3g} arcmin/px "
                               f"(the limit is {MAX_PSF_PX} px)")
    if mode == "wave":
        blur = geometric_blur_radius_arcmin(front, pupil_mm)
        fft = psf_sampling(pupil_mm, wavelength_nm, step, size, blur).fft_size  # refuses FFTs over its limit
        return float(fft) ** 2 * BYTES_PER_FFT_PX, size
    return float(size) ** 2 * BYTES_PER_PSF_PX, size


def item_memory_bytes(configuration, settings) -> tuple[float, str]:
    """(peak bytes, the step that needs them) for one single-plane campaign item."""
    from vissim.validation.item import SYNTHETIC_OVERSAMPLE
    from vissim.validation.renders import campaign_bench
    from vissim.validation.simulate import simulation_setup

    rows, cols = settings.tile_px
    bench = campaign_bench(configuration, settings)
    theory = bench.viewing_setup(settings.wavelength_nm)
    blur_px = max(d for d, _ in theory.blur_diameter_arcmin) / settings.arcmin_per_px
    mag = max(1.0, max(abs(m) for m, _ in theory.magnification_principal))
    texels = [TEXELS_PER_PX * (n * mag * 1.05 + 2 * blur_px + 4) for n in (rows, cols)]
    steps = [(render_memory_bytes(rows * cols, settings.spp) + texels[0] * texels[1] * BYTES_PER_TEXEL,
              f"its bench render ({rows} x {cols} px, {texels[0]:.0f} x {texels[1]:.0f} texel chart)")]
    for kind in settings.simulations:
        sim = simulation_setup(kind, theory, bench.physical_lenses, configuration, settings)
        front = sim.setup.wavefront
        for name in settings.inputs:
            s = SYNTHETIC_OVERSAMPLE if name == "synthetic" else 1
            step = settings.arcmin_per_px / s
            try:
                psf, size = _psf_bytes(front, sim.setup.pupil_diameter_mm, step, settings.wavelength_nm, sim.mode)
            except VissimInputError as exc:
                raise VissimInputError(f"the {kind} simulation of the {name} input: {exc}") from None
            image = float(rows * s + size) * float(cols * s + size) * BYTES_PER_BLUR_PX
            steps.append((psf + image, f"the {kind} simulation of the {name} input ({rows * s} x {cols * s} px, "
                                       f"{size} px PSF)"))
    return max(steps)


def check_campaign_memory(campaign) -> None:
    """Refuse a single-plane campaign an item of which would not fit in this machine's memory."""
    for config in campaign.configurations:
        try:
            need, step = item_memory_bytes(config, campaign.settings)
            check_allocation(need, step)
        except VissimInputError as exc:
            raise VissimInputError(f"{campaign.source}: {config.name}: {exc}") from None


def check_depth_campaign_memory(campaign) -> None:
    """Refuse a depth campaign an item of which would not fit in this machine's memory."""
    settings = campaign.settings
    for config in campaign.configurations:
        rows, cols = config.scene.size_px
        fine = float(rows) * cols * settings.oversample**2
        need = max(render_memory_bytes(rows * cols, settings.spp), render_memory_bytes(fine, settings.aux_spp),
                   fine * BYTES_PER_DEPTH_PX)
        try:
            check_allocation(need, f"its {rows * settings.oversample} x {cols * settings.oversample} px renders "
                                   f"and layered blur")
        except VissimInputError as exc:
            raise VissimInputError(f"{campaign.source}: {config.name}: {exc}") from None

