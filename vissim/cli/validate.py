"""``vissim validate`` and ``vissim report``: run a validation campaign, rebuild its report."""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.validation.campaign import load_campaign
from vissim.validation.report import build_report, load_results, metrics_rows
from vissim.validation.runner import run_campaign


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate",
        help="run a validation campaign: bench renders vs Fourier simulations",
        description="Render each configuration of a campaign on the virtual bench (the ground truth), "
        "apply the wave, geometric and thesis-mode simulations to the no-lens render and to the "
        "synthetic chart, and compare (SSIM, PSNR, absolute difference, after sub-pixel "
        "registration). Re-running reuses finished renders and items.",
    )
    parser.add_argument("campaign", type=Path, help="campaign TOML, e.g. validation/quick.toml")
    parser.add_argument("-o", "--output", type=Path, required=True, help="run folder, e.g. runs/quick")
    parser.add_argument("--workers", type=int, default=1, metavar="N", help="render in N local processes")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="send renders to a Dask distributed scheduler")
    parser.add_argument("--spp", type=int, metavar="N", help="override the campaign's samples per pixel")
    parser.set_defaults(func=run_validate)

    report = subparsers.add_parser(
        "report",
        help="rebuild a campaign run's report from its results",
        description="Rebuild metrics.json/csv, tables.md, figures and report.html of a run folder without rendering.",
    )
    report.add_argument("run", type=Path, help="run folder written by vissim validate")
    report.set_defaults(func=run_report)


def _print_summary(run_dir: Path) -> None:
    rows = metrics_rows(load_results(run_dir))
    print(f"{'configuration':44s} {'simulation':>10s} {'input':>9s} {'SSIM':>7s} {'PSNR dB':>8s} {'floor dB':>8s}")
    for r in rows:
        print(f"{r['configuration'][:44]:44s} {r['simulation']:>10s} {r['input']:>9s} {r['ssim']:7.4f} "
              f"{r['psnr_db']:8.2f} {r['noise_floor_psnr_db']:8.2f}")


def run_validate(args: argparse.Namespace) -> int:
    campaign = load_campaign(args.campaign)
    summary = run_campaign(campaign, args.output, workers=args.workers, scheduler=args.scheduler, spp=args.spp)
    print(
        f"{summary.items_total} items ({summary.items_reused} reused), {summary.renders_made} renders made, "
        f"{summary.renders_reused} reused"
    )
    written = build_report(args.output)
    _print_summary(args.output)
    print(f"report: {args.output / 'report.html'} ({len(written)} files)")
    return 0


def run_report(args: argparse.Namespace) -> int:
    if not (args.run / "campaign.json").exists():
        from vissim.errors import VissimInputError

        raise VissimInputError(f"{args.run} is not a vissim run folder (no campaign.json)")
    written = build_report(args.run)
    _print_summary(args.run)
    print(f"report: {args.run / 'report.html'} ({len(written)} files)")
    return 0
