"""The files a campaign run reads, from its record: no output of the run may replace one of them.

The same record (`vissim.validation.engine.protocol.Campaign.record`, kept in ``campaign.json``)
serves a run about to start and a report rebuilt later.
"""

from __future__ import annotations

from pathlib import Path

from vissim.validation.engine.registry import DEFAULT_KIND, bench_kind

__all__ = ["campaign_inputs", "recorded_inputs"]


def recorded_inputs(record: dict) -> list[Path]:
    """Every file a campaign ``record`` says its run reads: the campaign file and what its bench kind reads."""
    kind = bench_kind(record.get("kind", DEFAULT_KIND))
    source = [Path(record["source"])] if record.get("source") else []
    return source + kind.input_files(record)


def campaign_inputs(campaign) -> list[Path]:
    """Every file a run of ``campaign`` reads (`recorded_inputs` of its record)."""
    return recorded_inputs(campaign.record([]))
