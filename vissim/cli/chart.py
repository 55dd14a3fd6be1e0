"""``vissim chart``: a LogMAR chart, a single-letter chart or a thesis tile, in angle or for print."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from vissim.checks import size_text
from vissim.atomic import write_json_atomic
from vissim.chart_defaults import DEFAULT_LETTER_SEED, INK_REFLECTANCE, PAPER_REFLECTANCE, POLARITIES
from vissim.cli._common import add_json_arg, print_result, refuse_existing
from vissim.errors import VissimInputError
from vissim.provenance import make_provenance
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_TILE_SHAPE_PX
from vissim.units import mm_to_m
from vissim.cli import command_help

log = logging.getLogger(__name__)

_SIDECAR_SUFFIX = ".letters.json"
_PRINT_SUFFIXES = (".pdf", ".png", ".tif", ".tiff")
_IMAGE_SUFFIXES = (".exr", ".png", ".tif", ".tiff")


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "chart",
        help=command_help("chart"),
        description=(
            "Render Sloan-letter charts in ETDRS layout (5 letters a row, letter gap = letter width, "
            "row gap = next row's letter height).  By default the image is sampled in visual angle "
            "(linear reflectance, for simulation); --print gives the chart at its physical size for "
            "the viewing distance as a vector PDF or a PNG at --dpi.  Every letter box is listed in "
            "OUTPUT.letters.json."
        ),
    )
    rows = parser.add_mutually_exclusive_group()
    rows.add_argument("--logmar", type=float, metavar="L", help="one row at this LogMAR (default: the rows of --logmar-range)")
    rows.add_argument("--logmar-range", metavar="START,STOP",
                      help="rows from START to STOP inclusive (default 1.0,-0.3 as in the thesis)")
    parser.add_argument("--logmar-step", type=float, default=0.1, metavar="L", help="row step (default 0.1)")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--letters", metavar="LETTERS",
                       help="letters of every row (e.g. NCKZO), or one group per row separated by commas (default: 5 distinct "
                            "letters a row, picked by --seed)")
    which.add_argument("--letter", metavar="X", help="a single letter (one per row; default: as --letters)")
    parser.add_argument("--seed", type=int, default=DEFAULT_LETTER_SEED,
                        help=f"seed that picks 5 distinct letters per row when none are given "
                             f"(default {DEFAULT_LETTER_SEED})")
    parser.add_argument("--polarity", choices=POLARITIES, default="black-on-white",
                        help="black letters on white paper, or white on black (default black-on-white)")
    parser.add_argument("--arcmin-per-px", type=float, default=1.0, metavar="ARCMIN",
                        help="angular pixel size (default 1, as the thesis)")
    parser.add_argument("--chart-distance-m", type=float, default=mm_to_m(THESIS_CHART_DISTANCE_MM), metavar="M",
                        help="viewing distance in metres (default 0.9144, three feet)")
    parser.add_argument("--paper-reflectance", type=float, default=PAPER_REFLECTANCE, metavar="R",
                        help=f"linear reflectance of the paper (default {PAPER_REFLECTANCE})")
    parser.add_argument("--ink-reflectance", type=float, default=INK_REFLECTANCE, metavar="R",
                        help=f"linear reflectance of the ink (default {INK_REFLECTANCE})")
    parser.add_argument("--tile", action="store_true",
                        help="one letter centred on a 113 x 133 px tile (the thesis's optotype tiles)")
    parser.add_argument("--print", dest="print_form", action="store_true",
                        help="the chart at its physical size: .pdf (vector) or .png at --dpi")
    parser.add_argument("--dpi", type=float, default=360.0, help="print resolution (default 360, as the thesis)")
    parser.add_argument("-o", "--output", required=True, metavar="PATH",
                        help="image to write (.exr recommended; with --print .pdf or .png)")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_json_arg(parser)
    parser.set_defaults(func=run)
    return parser


def _logmar_range(text: str) -> tuple[float, float]:
    parts = text.replace(":", ",").split(",")
    try:
        start, stop = (float(p) for p in parts)
    except ValueError:
        raise VissimInputError(f"--logmar-range must be START,STOP in LogMAR (e.g. 1.0,-0.3), got {text!r}") from None
    return start, stop


def _letters(args: argparse.Namespace) -> str | None:
    if args.letter is not None:
        if len(args.letter.strip()) != 1:
            raise VissimInputError(f"--letter takes one Sloan letter, got {args.letter!r}; use --letters for more")
        return args.letter.strip()
    if args.letters is not None and not args.letters.replace(",", "").strip():
        raise VissimInputError(f"--letters is empty ({args.letters!r}); give Sloan letters, e.g. NCKZO")
    return args.letters


def run(args: argparse.Namespace) -> int:
    from vissim.charts import (chart_sidecar, etdrs_chart_spec, layout_chart, optotype_tile,  # paid when it runs
                               render_chart_angular, save_chart_pdf, save_chart_png)
    from vissim.imageio import image_files, write_image

    out = Path(args.output)
    suffix = out.suffix.lower()
    letters = _letters(args)
    look = {"viewing_distance_m": args.chart_distance_m, "polarity": args.polarity,
            "paper_reflectance": args.paper_reflectance, "ink_reflectance": args.ink_reflectance}
    if args.tile:
        if args.print_form or args.logmar_range is not None:
            raise VissimInputError("--tile makes one angular tile: it takes --logmar, not --print or --logmar-range")
        if letters is None or len(letters.strip()) != 1 or args.logmar is None:
            raise VissimInputError("--tile needs one letter (--letter N) and one --logmar")
    if args.logmar is not None:
        spec_range = (args.logmar, args.logmar)
    else:
        spec_range = _logmar_range(args.logmar_range) if args.logmar_range else (1.0, -0.3)
    spec = etdrs_chart_spec(spec_range, args.logmar_step, letters=letters, seed=args.seed, **look)
    allowed = _PRINT_SUFFIXES if args.print_form else _IMAGE_SUFFIXES
    if suffix not in allowed:
        raise VissimInputError(f"-o {out}: expected one of {', '.join(allowed)}")
    sidecar_path = out.with_name(out.name + _SIDECAR_SUFFIX)
    images = (out,) if suffix == ".pdf" else image_files(out)  # a PDF keeps its provenance inside
    refuse_existing(*images, sidecar_path, overwrite=args.overwrite)
    provenance = make_provenance(command="vissim chart", options={k: v for k, v in vars(args).items() if k not in ("func", "json")}, spec=spec)

    if args.print_form:
        layout = layout_chart(spec, dpi=args.dpi)
        if suffix == ".pdf":
            save_chart_pdf(spec, out, overwrite=args.overwrite, provenance=provenance)
        else:
            save_chart_png(spec, out, dpi=args.dpi, overwrite=args.overwrite, provenance=provenance)
        height_mm, width_mm = layout.page_size_mm
        what = f"print chart {size_text((round(height_mm, 1), round(width_mm, 1)), 'mm')}" + ("" if suffix == ".pdf" else f" at {args.dpi:g} dpi")
        sidecar = chart_sidecar(spec, layout)
        record = {"kind": "print chart", "page_size_mm": [height_mm, width_mm],
                  "dpi": None if suffix == ".pdf" else args.dpi}
    else:
        if args.tile:
            chart = optotype_tile(letters.strip(), args.logmar, arcmin_per_px=args.arcmin_per_px,
                                  size_px=THESIS_TILE_SHAPE_PX, **look)
        else:
            chart = render_chart_angular(spec, args.arcmin_per_px)
        write_image(out, chart.pixels, provenance=provenance, overwrite=args.overwrite, encoding="srgb",
                    arcmin_per_px=args.arcmin_per_px)
        what = f"{'tile' if args.tile else 'chart'} {size_text(chart.pixels.shape)} at {args.arcmin_per_px:g} arcmin/px"
        sidecar = chart.sidecar()
        record = {"kind": "tile" if args.tile else "chart", "size_px": list(chart.pixels.shape[:2]),
                  "arcmin_per_px": args.arcmin_per_px}
    n = len(sidecar["letters"])
    lines = [f"wrote {out} ({what}, {n} letter{'s' if n != 1 else ''})"]
    lines += [f"wrote {provenance_path} (provenance)" for provenance_path in images[1:]]
    write_json_atomic(sidecar_path, sidecar | {"provenance": provenance}, overwrite=args.overwrite)
    lines.append(f"wrote {sidecar_path} (letter boxes)")
    record |= {"letters": [box["letter"] for box in sidecar["letters"]], "chart_distance_m": args.chart_distance_m,
               "polarity": args.polarity}
    print_result(args, lines, record, [*images, sidecar_path], provenance)
    return 0
