"""Memory a campaign's items will need, estimated from their settings before anything is allocated.

The estimates are rough upper bounds of the largest single step (a bench render, a PSF, one
blurred image), enough to refuse a campaign that cannot fit (a 1e9 px tile, a PSF wider than
the tile by orders of magnitude) with a message saying what it would need, before a file is
written.  The machine's memory is `vissim.checks.check_allocation`'s; a render's and the chart
texture's needs are the renderer's own estimates (`vissim.render.run.render_memory_bytes`,
`vissim.bench.dslr.chart_texture_shape`).
"""

from __future__ import annotations

from vissim.bench.dslr.bench import chart_mm_per_texel, chart_texture_shape
from vissim.bench.scene_parts import TEXTURE_BYTES_PER_TEXEL
from vissim.checks import MAX_PSF_SIZE_PX, check_allocation, size_text
from vissim.errors import VissimInputError
from vissim.optics.psf.compute import geometric_blur_radius_arcmin, psf_sampling, suggested_size_px
from vissim.optics.pupil.wavefront import Wavefront
from vissim.render.run import render_memory_bytes  # no Mitsuba import: that happens when a render starts
from vissim.optics.blur.resample import SUBPIXELS_PER_PX
from vissim.validation.dslr.simulate import simulation_setup

__all__ = ["item_memory_bytes", "check_campaign_memory"]

#: Blurring one pixel: the float64 padded image, its complex128 spectrum, the product, the result.
BYTES_PER_BLUR_PX = 64
#: A wave PSF's FFT grid point (complex128 field and spectrum, float64 intensity).
BYTES_PER_FFT_PX = 48
#: A geometric PSF's pixel (float64 accumulators).
BYTES_PER_PSF_PX = 32


def _psf_bytes(front: Wavefront, pupil_mm: float, step: float, wavelength_nm: float, mode: str) -> tuple[float, int]:
    size = suggested_size_px(front, step, wavelength_nm=wavelength_nm)
    if size > MAX_PSF_SIZE_PX:
        raise VissimInputError(f"its PSF would be {size} px wide at {step:.3g} arcmin/px "
                               f"(the limit is {MAX_PSF_SIZE_PX} px)")
    if mode == "wave":
        blur = geometric_blur_radius_arcmin(front, pupil_mm)
        fft = psf_sampling(pupil_mm, wavelength_nm, step, size, blur).internal_size  # refuses grids over the limit
        return float(fft) ** 2 * BYTES_PER_FFT_PX, size
    return float(size) ** 2 * BYTES_PER_PSF_PX, size


def item_memory_bytes(built, settings) -> tuple[float, str]:
    """(peak bytes, the step that needs them) for one DSLR campaign item (``built``: its `DslrBuilt`)."""
    rows, cols = settings.tile_px
    bench, theory, configuration = built.bench, built.setup, built.configuration
    texels = chart_texture_shape(bench, theory, chart_mm_per_texel(bench))
    steps = [(render_memory_bytes(rows * cols, settings.spp) + texels[0] * texels[1] * TEXTURE_BYTES_PER_TEXEL,
              f"its bench render ({size_text((rows, cols))}, {size_text(texels, 'texel')} chart)")]
    for kind in settings.simulations:
        sim = simulation_setup(kind, theory, bench.physical_lenses, configuration, settings)
        front = sim.setup.wavefront
        # against the wave bench, wave-optical simulations run on the synthetic chart (as the truth does)
        extra = ("synthetic",) if settings.wave_truth and sim.mode == "wave" else ()
        for name in dict.fromkeys((*settings.inputs, *extra)):
            s = SUBPIXELS_PER_PX if name == "synthetic" else 1
            step = settings.arcmin_per_px / s
            try:
                psf, size = _psf_bytes(front, sim.setup.pupil_diameter_mm, step, settings.wavelength_nm, sim.mode)
            except VissimInputError as exc:
                raise VissimInputError(f"the {kind} simulation of the {name} input: {exc}") from None
            image = float(rows * s + size) * float(cols * s + size) * BYTES_PER_BLUR_PX
            steps.append((psf + image, f"the {kind} simulation of the {name} input ({size_text((rows * s, cols * s))}, "
                                       f"{size} px PSF)"))
    return max(steps)


def check_campaign_memory(campaign) -> None:
    """Refuse a DSLR campaign an item of which would not fit in this machine's memory."""
    for config, built in zip(campaign.configurations, campaign.built):
        try:
            need, step = item_memory_bytes(built, campaign.settings)
            check_allocation(need, step)
        except VissimInputError as exc:
            raise VissimInputError(f"{campaign.source}: {config.name}: {exc}") from None
