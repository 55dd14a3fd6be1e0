"""``vissim render``: render the virtual optical bench with Mitsuba 3 to a linear EXR.

Sub-commands: ``render bench`` (the DSLR bench, `vissim.bench.dslr.bench`), ``render atv``
(the ATV tube, `vissim.bench.atv.tube`), ``render depth`` (depth scenes,
`vissim.bench.depth.scene`) and ``render eye`` (a letter through a schematic eye,
`vissim.cli.render_eye`).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from vissim.checks import size_text
from vissim.chart_defaults import POLARITIES
from vissim.cli._common import add_json_arg, add_trial_lens_args, print_result, size_from_text, check_outputs_apart, refuse_existing, trial_lens_powers
from vissim.cli.render_atv import add_atv_parser
from vissim.cli.render_depth import add_depth_parser
from vissim.cli.render_eye import add_eye_parser
from vissim.errors import VissimInputError
from vissim.progress import terminal_progress
from vissim.cli import command_help

log = logging.getLogger(__name__)

__all__ = ["add_parser", "add_bench_parser", "add_atv_parser", "add_depth_parser"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "render",
        help=command_help("render"),
        description="Render the virtual optical bench with Mitsuba 3: a camera, trial lenses and a chart.",
    )
    benches = parser.add_subparsers(dest="bench", metavar="BENCH")
    add_bench_parser(benches)
    add_atv_parser(benches)
    add_depth_parser(benches)
    add_eye_parser(benches)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)
    return parser


def add_bench_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "bench",
        help="the DSLR with trial lenses in front of a letter chart",
        description=(
            "Render the thesis's DSLR bench (18 mm f/5 camera focused on a chart at 914.4 mm, trial "
            "lenses 10 mm in front) by path tracing through meshed trial lenses.  Options override the "
            "--scene file; --sphere/--cylinder replace its lenses with one lens."
        ),
    )
    parser.add_argument("--scene", metavar="TOML", help="bench scene file (see scenes/dslr_bench.toml)")
    add_trial_lens_args(parser.add_argument_group("trial lens (replaces the scene's lenses)"), none_given="the scene's lenses")
    parser.add_argument("--f-number", type=float, metavar="N", help="camera f-number (default 5)")
    chart = parser.add_mutually_exclusive_group()
    chart.add_argument("--letter", metavar="X", help="one Sloan letter (C D H K N O R S V Z; default: the scene's chart, R)")
    chart.add_argument("--chart", metavar="TOML", help="a file whose [chart] table describes the chart")
    parser.add_argument("--logmar", type=float, metavar="L", help="letter size in LogMAR (with --letter)")
    parser.add_argument("--polarity", choices=POLARITIES, help="default black-on-white")
    parser.add_argument("--arcmin-per-px", type=float, metavar="ARCMIN", help="angular pixel size (default 1)")
    parser.add_argument("--size", metavar="N|ROWSxCOLS",
                        help="image size in pixels: N (a square) or ROWSxCOLS (default 133x113)")
    parser.add_argument("--spp", type=int, metavar="N", help="samples per pixel (default 256)")
    parser.add_argument("--seed", type=int, metavar="S", help="sampler seed (default 0)")
    parser.add_argument("--sampler", choices=("independent", "stratified", "multijitter", "ldsampler"),
                        help="Mitsuba sampler (default multijitter)")
    parser.add_argument("--fresnel-loss", action="store_true", default=None,
                        help="uncoated lenses: weight by the Fresnel transmittance of each surface")
    colour = parser.add_mutually_exclusive_group()
    colour.add_argument("--rgb", action="store_true", help="render RGB (default: monochrome)")
    colour.add_argument("--spectral", action="store_true",
                        help="render spectrally, the lenses' glass dispersive (spectacle crown, Abbe number "
                             "58.6): the chart's white is equal-energy (illuminant E) and each pixel is the CIE 1931 "
                             "luminance Y of the light that reaches it, so colour fringes and the focus shift with "
                             "wavelength are in the image; recorded in the output's provenance.  Noisier than the "
                             "default (about 5x the variance of a letter chart at equal --spp).  Default: one "
                             "channel at the d line (587.56 nm), where the glass has the lenses' index")
    parser.add_argument("--variant", metavar="V", help="Mitsuba variant (default: chosen by vissim)")
    parser.add_argument("--optics", choices=("ray", "wave"), default="ray",
                        help="ray: Mitsuba's render (default); wave: the wave-optical truth, the chart imaged "
                             "through the lenses' traced wavefront (no noise, no Mitsuba)")
    parser.add_argument("--wavelength-nm", metavar="NM[,NM...]",
                        help="with --optics wave: wavelength(s), traced through the dispersive glass "
                             "(default the d line, 587.5618 nm, where the glass has the rendered index)")
    parser.add_argument("-o", "--output", required=True, metavar="PATH", help="output .exr (linear float32)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    add_json_arg(parser)
    parser.set_defaults(func=run_bench)
    return parser


def _lenses(args):
    from vissim.optics.rx.trial_lens import TrialLens

    powers = trial_lens_powers(args)
    return None if powers is None else (TrialLens(*powers),)


def _chart_table(args, scene_doc: dict) -> dict:
    table = dict(scene_doc.get("chart", {})) if isinstance(scene_doc.get("chart", {}), dict) else {}
    if args.letter is not None or args.logmar is not None:
        for key in ("letters", "logmar_range", "logmar_step", "seed"):
            table.pop(key, None)
    given = {key: getattr(args, key) for key in ("letter", "logmar", "polarity")}
    table.update({key: value for key, value in given.items() if value is not None})
    return table


def run_bench(args: argparse.Namespace) -> int:
    from vissim.bench.dslr.scene_files import bench_from_tables, chart_spec_from_table, load_chart_toml
    from vissim.bench.scene_toml import read_scene_toml
    from vissim.imageio import write_image

    output = Path(args.output)
    check_outputs_apart((args.scene, args.chart), [output])
    if output.suffix.lower() != ".exr":
        raise VissimInputError(f"the bench writes linear float EXR; give an output ending in .exr, got {output}")
    refuse_existing(output, overwrite=args.overwrite)
    doc, source = ({}, "command line") if args.scene is None else read_scene_toml(args.scene)
    bench = bench_from_tables(
        doc, source, lenses=_lenses(args), f_number=args.f_number, arcmin_per_px=args.arcmin_per_px,
        size_px=None if args.size is None else size_from_text(args.size), spp=args.spp, seed=args.seed,
        sampler=args.sampler, fresnel_loss=args.fresnel_loss,
    )
    if args.chart is not None:
        if args.logmar is not None or args.polarity is not None:
            raise VissimInputError("--logmar and --polarity go with --letter; a --chart file sets its own")
        chart = load_chart_toml(args.chart, bench.chart_distance_mm)
    else:
        chart = chart_spec_from_table(_chart_table(args, doc), source, bench.chart_distance_mm)
    if args.optics == "wave":
        return _write_wave_truth(bench, chart, args, output)
    if args.wavelength_nm is not None:
        raise VissimInputError("--wavelength-nm goes with --optics wave (Mitsuba renders one refractive index)")
    kind = "spectral" if args.spectral else "rgb" if args.rgb else "mono"
    result = _render_with_progress(bench, chart, kind, args.variant)
    write_image(output, result.pixels, provenance=result.provenance, overwrite=args.overwrite,
                arcmin_per_px=bench.arcmin_per_px)
    theory = result.provenance["inputs"]["theory"]
    blur = ", ".join(f"{d:.2f}' along {m:g}°" for d, m in theory["blur_diameter_arcmin"])
    added = "no trial lens" if theory["added_power"] is None else f"added {theory['added_power']}"
    print_result(args, [f"wrote {output}: {size_text(result.pixels.shape)}, {result.spp} spp, "
                        f"{result.variant}, {result.seconds:.1f} s; theory: blur {blur}, {added}"],
                 {"size_px": list(result.pixels.shape[:2]), "spp": result.spp, "variant": result.variant,
                  "seconds": result.seconds, "blur_diameter_arcmin": theory["blur_diameter_arcmin"],
                  "added_power": theory["added_power"]}, [output], result.provenance)
    return 0


def _write_wave_truth(bench, chart, args, output: Path) -> int:
    from vissim.bench.dslr.traced_wavefront import D_LINE_NM
    from vissim.bench.dslr.wave_truth import wave_truth
    from vissim.cli._common import parse_float_list
    from vissim.imageio import write_image
    from vissim.provenance import make_provenance

    if (args.rgb or args.spectral or args.variant is not None or args.spp is not None or args.seed is not None
            or args.sampler):
        raise VissimInputError("--rgb, --spectral, --variant, --spp, --seed and --sampler are render options; "
                               "--optics wave computes the image without Mitsuba")
    wavelengths = [D_LINE_NM] if args.wavelength_nm is None else parse_float_list(args.wavelength_nm, "--wavelength-nm", "nm")
    truth = wave_truth(bench, chart, wavelengths_nm=wavelengths)
    provenance = make_provenance(command="render bench --optics wave", **truth.provenance)
    write_image(output, truth.pixels, provenance=provenance, overwrite=args.overwrite, arcmin_per_px=bench.arcmin_per_px)
    traced = truth.provenance["traced"][0]
    print_result(args, [f"wrote {output}: {size_text(truth.pixels.shape)}, wave truth at "
                        f"{', '.join(f'{w:g}' for w in wavelengths)} nm; traced RMS {traced['rms_um']:.4g} µm over "
                        f"{traced['pupil_diameter_mm']:g} mm"],
                 {"size_px": list(truth.pixels.shape[:2]), "wavelength_nm": wavelengths, "rms_um": traced["rms_um"],
                  "pupil_diameter_mm": traced["pupil_diameter_mm"]}, [output], provenance)
    return 0


def _render_with_progress(bench, chart, kind: str, variant: str | None):
    from vissim.render.run import render_bench

    with terminal_progress() as progress:
        report = None if progress is None else (lambda done, total: progress("rendering (samples per pixel)", done, total))
        return render_bench(bench, chart, kind=kind, variant=variant, progress=report)
