"""``vissim demo``: the built-in demonstration (a chart through -2.00 DS and -2.00 DC x 90)."""

from __future__ import annotations

import argparse
from pathlib import Path

from vissim.chart_defaults import DEMO_PRESCRIPTIONS
from vissim.errors import VissimInputError
from vissim.cli import command_help


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo",
        help=command_help("demo"),
        description="Render a LogMAR chart at 1 arcmin/px and blur it, in linear light, through an "
        "eye corrected by " + " and by ".join(DEMO_PRESCRIPTIONS.values()) + " (3 mm pupil, 550 nm).",
    )
    parser.add_argument("-o", "--output", type=Path, default=Path("runs/demo"), help="output folder (default runs/demo)")
    parser.add_argument("--overwrite", action="store_true", help="replace files from an earlier run")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vissim.chart_demo import run_demo  # paid when it runs

    if args.output.exists() and not args.output.is_dir():
        raise VissimInputError(f"-o {args.output} is a file; the demo writes into a folder")
    for path in run_demo(args.output, overwrite=args.overwrite):
        print(f"wrote {path}")
    return 0
