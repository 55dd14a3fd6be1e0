"""Memory a depth campaign's items will need, estimated before anything is allocated (rough upper bounds)."""

from __future__ import annotations

from vissim.checks import check_allocation, size_text
from vissim.errors import VissimInputError
from vissim.render.run import render_memory_bytes  # no Mitsuba import: that happens when a render starts

__all__ = ["check_depth_campaign_memory"]

#: Layered depth blur, per pixel of the (oversampled) image: layers' images, masks and spectra.
BYTES_PER_DEPTH_PX = 256
#: Layered input, per pixel and scene layer: its radiance and coverage, padded, and float64 composites.
BYTES_PER_LAYER_PX = 64


def check_depth_campaign_memory(campaign) -> None:
    """Refuse a depth campaign an item of which would not fit in this machine's memory."""
    settings = campaign.settings
    for config, built in zip(campaign.configurations, campaign.built):
        rows, cols = config.scene.size_px
        margin = built.margin_px  # the simulations' inputs extend beyond the frame
        fine = float(rows + 2 * margin) * (cols + 2 * margin) * settings.oversample**2
        layered = BYTES_PER_LAYER_PX * len(config.scene.panels) if "layered" in settings.inputs else 0
        need = max(render_memory_bytes(rows * cols, settings.spp), render_memory_bytes(fine, settings.aux_spp),
                   fine * (BYTES_PER_DEPTH_PX + layered))
        try:
            check_allocation(need, f"its {size_text((rows * settings.oversample, cols * settings.oversample))} renders "
                                   f"and layered blur")
        except VissimInputError as exc:
            raise VissimInputError(f"{campaign.source}: {config.name}: {exc}") from None
