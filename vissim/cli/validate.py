"""``vissim validate`` and ``vissim report``: run a validation campaign, rebuild its report."""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.errors import VissimInputError
from vissim.progress import terminal_progress
from vissim.cli import command_help
from vissim.cli._common import add_json_arg, print_result


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate",
        help=command_help("validate"),
        description="Render each configuration of a campaign on the virtual bench (the ground truth), "
        "apply the wave, geometric and thesis-mode simulations to the no-lens render and to the "
        "synthetic chart, and compare (SSIM, PSNR, absolute difference, after sub-pixel "
        "registration). A depth campaign (kind = \"depth\", e.g. validation/depth.toml) compares "
        "depth-scene renders with the depth-layered simulation per panel and at occlusion edges. "
        "Re-running reuses finished renders and items.",
    )
    parser.add_argument("campaign", type=Path, help="campaign TOML, e.g. validation/quick.toml")
    parser.add_argument("-o", "--output", type=Path, required=True, help="run folder, e.g. runs/quick")
    parser.add_argument("--workers", type=int, default=1, metavar="N", help="render in N local processes (default 1: in this one)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="send renders to a Dask distributed scheduler")
    parser.add_argument("--spp", type=int, metavar="N", help="override the campaign's samples per pixel")
    add_json_arg(parser)
    parser.set_defaults(func=run_validate, writes_progressively=True)

    report = subparsers.add_parser(
        "report",
        help=command_help("report"),
        description="Rebuild metrics.json/csv, tables.md, figures and report.html of a run folder without rendering.",
    )
    report.add_argument("run", type=Path, help="run folder written by vissim validate")
    add_json_arg(report)
    report.set_defaults(func=run_report, writes_progressively=True)


def run_validate(args: argparse.Namespace) -> int:
    from vissim.validation.engine.validate import validate

    try:
        with terminal_progress() as progress:
            done = validate(args.campaign, args.output, workers=args.workers, scheduler=args.scheduler,
                            spp=args.spp, show_progress=False, progress=progress)
    except OSError as exc:  # the run folder cannot be written (permissions, a full disk)
        raise VissimInputError(f"cannot write {exc.filename or args.output}: {exc.strerror or exc}") from None
    summary = done.summary
    record = {"kind": done.kind, "items_total": summary.items_total, "items_reused": summary.items_reused,
              "renders_made": summary.renders_made, "renders_reused": summary.renders_reused,
              "renders_seconds": summary.renders_seconds, "items_seconds": summary.items_seconds,
              "skipped": list(summary.skipped), "lines": list(done.lines),
              "metrics": _metrics(args.output) if args.json else None}  # read back only for --json
    print_result(args, [*done.lines, *(f"skipped: {message}" for message in summary.skipped)], record, done.report_files)
    return 0


def _metrics(run_dir: Path):
    """The run's ``metrics.json`` (every item's numbers), or None where the kind writes none."""
    import json

    path = Path(run_dir) / "metrics.json"
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else None


def run_report(args: argparse.Namespace) -> int:
    from vissim.validation.engine.validate import rebuild_report

    with terminal_progress() as progress:
        written, lines = rebuild_report(args.run, progress=progress)
    print_result(args, [*lines, f"report: {args.run / 'report.html'} ({len(written)} files)"],
                 {"lines": list(lines), "metrics": _metrics(args.run) if args.json else None}, written)
    return 0
